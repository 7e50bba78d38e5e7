//! GPU timestamps, for benchmarks: a query set, the buffer it resolves into and a copy the CPU
//! maps. Passes write into [`Timestamps::set`] (as compute-pass timestamp writes, or with
//! `write_timestamp` inside an encoder where the device allows it).

use crate::render::gpu::readback::{ReadbackError, map_buffer};

/// `count` timestamp queries and their read-back.
pub struct Timestamps {
    pub set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
}

impl Timestamps {
    /// None when the device lacks any of `needed` (`TIMESTAMP_QUERY`, and
    /// `TIMESTAMP_QUERY_INSIDE_ENCODERS` for writes between passes). GPU objects are labelled
    /// `label`, `label_resolve` and `label_read`.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        label: &str,
        count: u32,
        needed: wgpu::Features,
    ) -> Option<Self> {
        if !device.features().contains(needed) {
            return None;
        }
        let buffer = |suffix: &str, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label}{suffix}")),
                size: u64::from(count) * 8,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Self {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: buffer(
                "_resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "_read",
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            ),
            period: f64::from(queue.get_timestamp_period()),
        })
    }

    /// Records resolving the first `used` queries and copying them for [`Timestamps::read_ticks`].
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder, used: u32) {
        encoder.resolve_query_set(&self.set, 0..used, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, None);
    }

    /// The ticks of the last resolved queries (waits for the GPU).
    pub fn read_ticks(&self, device: &wgpu::Device) -> Result<Vec<u64>, ReadbackError> {
        Ok(bytemuck::pod_collect_to_vec(&map_buffer(
            device,
            &self.read,
            "the GPU timestamps",
        )?))
    }

    /// Milliseconds from tick `start` to tick `end`.
    pub fn ms(&self, start: u64, end: u64) -> f64 {
        end.wrapping_sub(start) as f64 * self.period / 1e6
    }
}
