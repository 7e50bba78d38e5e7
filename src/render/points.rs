//! Points view: draws a cloud's points as screen-aligned discs coloured by hp.
//!
//! Reads: the cloud uploaded by [`PointsGpu`] (one storage buffer per chunk, five f32 per point,
//! the PLY record as is). Writes: colour and depth of the render target.
//! Each point is an instance of three vertices (a triangle around the disc); the fragment
//! shader cuts the disc.
//! Clouds larger than one storage binding are split into chunks, each drawn on its own.
//! While the camera moves, every `stride`-th point is drawn (a level-of-detail subset). Each
//! chunk has a second parameter block that always holds that subset's stride, so one submission
//! can draw full-density slices and the subset of the points not drawn yet (progressive points,
//! src/ui/progressive.rs).
//! The frequency axis of the view ([`PointsGpu::set_freq`], src/data/freq_axis.rs) remaps each
//! point's z in the vertex shader; the stored points are never changed.

use wgpu::util::DeviceExt;

use crate::data::cloud::{POINT_BYTES, Point};
use crate::data::freq_axis::{FreqMapping, FreqParams};
use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry};
use crate::render::gpu::pipeline::{DrawPipeline, depth_opaque, opaque_target, primitives};
use crate::render::shaders;

/// Keep in sync with `PointParams` in shaders/points.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PointParams {
    stride: u32,
    count: u32,
    size_px: f32,
    min_scalar: f32,
    freq: FreqParams,
}
const _: () = assert!(std::mem::size_of::<PointParams>() == 48);

/// How the points are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointStyle {
    /// Disc diameter in pixels.
    pub size_px: f32,
    /// Points whose scalar (loudness) is below this are hidden.
    pub min_scalar: f32,
    /// At most this many points are drawn while the camera moves.
    pub max_points_moving: u32,
}

impl Default for PointStyle {
    fn default() -> Self {
        Self {
            size_px: 2.0,
            min_scalar: 0.0,
            max_points_moving: 40_000,
        }
    }
}

struct Chunk {
    count: u32,
    /// Index of the chunk's first point in the cloud (the frequency jitter's seed).
    first: u32,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// The moving subset's parameters (its stride whatever `params` says).
    lod_params: wgpu::Buffer,
    lod_bind_group: wgpu::BindGroup,
    points: wgpu::Buffer,
}

/// A cloud's point buffers, filled, in chunks of `per_chunk` points ([`PointsGpu::buffers`]).
pub struct PointBuffers {
    chunks: Vec<(wgpu::Buffer, u32)>,
    per_chunk: usize,
    total: u64,
}

/// A cloud's points on the GPU.
pub struct PointsGpu {
    chunks: Vec<Chunk>,
    pub total: u64,
    /// The frequency axis's constants and per-bin table (identity until [`PointsGpu::set_freq`]).
    freq: FreqParams,
    freq_table: wgpu::Buffer,
}

impl PointsGpu {
    /// Uploads `points`, split into chunks of at most `max_chunk_bytes` (use
    /// [`PointsGpu::chunk_limit`] for the device's own limit). Each chunk goes through a staging
    /// copy of its own size, so the host briefly holds a second copy of the largest chunk (and,
    /// on a software rasterizer, the buffer itself lives in host memory too): use
    /// [`PointsGpu::upload_bounded`] for large clouds.
    pub fn upload(
        device: &wgpu::Device,
        pass: &PointsPass,
        points: &[Point],
        max_chunk_bytes: u64,
    ) -> Self {
        Self::from_buffers(device, pass, Self::buffers(device, points, max_chunk_bytes))
    }

    /// As [`PointsGpu::upload`], but the points travel in pieces of at most `staging_bytes`
    /// through the queue, each piece's staging memory released (the queue waited on) before the
    /// next is written: the host never holds more than one piece besides `points` and the
    /// buffers. The GPU buffers are identical to [`PointsGpu::upload`]'s.
    pub fn upload_bounded(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pass: &PointsPass,
        points: &[Point],
        max_chunk_bytes: u64,
        staging_bytes: u64,
    ) -> Self {
        let per_piece = (staging_bytes / POINT_BYTES as u64).max(1) as usize;
        Self::upload_with(pass, device, points, max_chunk_bytes, |label, slice| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (std::mem::size_of_val(slice) as u64).max(POINT_BYTES as u64),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            for (i, piece) in slice.chunks(per_piece).enumerate() {
                let offset = (i * per_piece * POINT_BYTES) as u64;
                queue.write_buffer(&buffer, offset, bytemuck::cast_slice(piece));
                flush_writes(device, queue);
            }
            buffer
        })
    }

    /// As [`PointsGpu::upload_bounded`], taking the points: they are sent from the end, and
    /// after each piece the vector is cut and shrunk, so the host's copy and the device's never
    /// add up to much more than one cloud (on a software rasterizer the device's copy is host
    /// memory). `points` is empty afterwards.
    pub fn upload_draining(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pass: &PointsPass,
        points: &mut Vec<Point>,
        max_chunk_bytes: u64,
        staging_bytes: u64,
    ) -> Self {
        let per_chunk = (max_chunk_bytes / POINT_BYTES as u64).max(1) as usize;
        let per_piece = (staging_bytes / POINT_BYTES as u64).max(1) as usize;
        let gpu = Self::upload_with(pass, device, points, max_chunk_bytes, |label, slice| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of_val(slice) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        for (c, chunk) in gpu.chunks.iter().enumerate().rev() {
            let start = c * per_chunk;
            let mut piece_end = start + chunk.count as usize;
            while piece_end > start {
                let piece_start = start + (piece_end - start - 1) / per_piece * per_piece;
                let offset = ((piece_start - start) * POINT_BYTES) as u64;
                let piece = &points[piece_start..piece_end];
                queue.write_buffer(&chunk.points, offset, bytemuck::cast_slice(piece));
                flush_writes(device, queue);
                points.truncate(piece_start);
                points.shrink_to_fit();
                piece_end = piece_start;
            }
        }
        *points = Vec::new();
        gpu
    }

    fn upload_with(
        pass: &PointsPass,
        device: &wgpu::Device,
        points: &[Point],
        max_chunk_bytes: u64,
        mut make_buffer: impl FnMut(&str, &[Point]) -> wgpu::Buffer,
    ) -> Self {
        let per_chunk = (max_chunk_bytes / POINT_BYTES as u64).max(1) as usize;
        let buffers = PointBuffers {
            chunks: points
                .chunks(per_chunk)
                .enumerate()
                .map(|(i, slice)| {
                    let label = format!("points::cloud_chunk_{i}");
                    (make_buffer(&label, slice), slice.len() as u32)
                })
                .collect(),
            per_chunk,
            total: points.len() as u64,
        };
        Self::from_buffers(device, pass, buffers)
    }

    /// The point buffers of [`PointsGpu::upload`] alone, made and filled without the pass:
    /// what a thread beside the window can do ([`PointsGpu::from_buffers`] does the rest, a
    /// few small buffers and bind groups). The same buffers as [`PointsGpu::upload`]'s.
    pub fn buffers(device: &wgpu::Device, points: &[Point], max_chunk_bytes: u64) -> PointBuffers {
        let per_chunk = (max_chunk_bytes / POINT_BYTES as u64).max(1) as usize;
        PointBuffers {
            chunks: points
                .chunks(per_chunk)
                .enumerate()
                .map(|(i, slice)| {
                    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(&format!("points::cloud_chunk_{i}")),
                        contents: bytemuck::cast_slice(slice),
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    });
                    (buffer, slice.len() as u32)
                })
                .collect(),
            per_chunk,
            total: points.len() as u64,
        }
    }

    /// The cloud drawn from `buffers` ([`PointsGpu::buffers`]): each chunk's parameters and
    /// bind groups.
    pub fn from_buffers(device: &wgpu::Device, pass: &PointsPass, buffers: PointBuffers) -> Self {
        let freq_table = freq_table_buffer(device, &[crate::data::freq_axis::HIDDEN]);
        let mut chunks = Vec::new();
        for (i, (points_buffer, count)) in buffers.chunks.into_iter().enumerate() {
            let params_buffer = |label: &str| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("points::{label}_{i}")),
                    size: std::mem::size_of::<PointParams>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            let (params, lod_params) = (params_buffer("params"), params_buffer("lod_params"));
            let bind_group =
                cloud_bind_group(device, pass, i, &points_buffer, &params, &freq_table);
            let lod_bind_group =
                cloud_bind_group(device, pass, i, &points_buffer, &lod_params, &freq_table);
            chunks.push(Chunk {
                count,
                first: (i * buffers.per_chunk) as u32,
                params,
                bind_group,
                lod_params,
                lod_bind_group,
                points: points_buffer,
            });
        }
        Self {
            chunks,
            total: buffers.total,
            freq: FreqParams::IDENTITY,
            freq_table,
        }
    }

    /// Shows the points on the frequency axis `mapping` (`None`: z as stored).
    pub fn set_freq(
        &mut self,
        device: &wgpu::Device,
        pass: &PointsPass,
        mapping: Option<&FreqMapping>,
    ) {
        let Some(mapping) = mapping else {
            self.freq = FreqParams::IDENTITY;
            return;
        };
        self.freq = mapping.params();
        self.freq_table = freq_table_buffer(device, &mapping.gpu_table());
        for (i, chunk) in self.chunks.iter_mut().enumerate() {
            chunk.bind_group = cloud_bind_group(
                device,
                pass,
                i,
                &chunk.points,
                &chunk.params,
                &self.freq_table,
            );
            chunk.lod_bind_group = cloud_bind_group(
                device,
                pass,
                i,
                &chunk.points,
                &chunk.lod_params,
                &self.freq_table,
            );
        }
    }

    /// Each chunk's point buffer (five f32 a point, the PLY record) and its point count, in
    /// cloud order: the voxelizer reads the points from here instead of uploading them again.
    pub fn chunk_buffers(&self) -> impl Iterator<Item = (&wgpu::Buffer, u32)> {
        self.chunks.iter().map(|c| (&c.points, c.count))
    }

    /// The largest chunk one storage binding and one buffer can hold on this device.
    pub fn chunk_limit(device: &wgpu::Device) -> u64 {
        storage_binding_limit(device)
    }

    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }
}

/// The frequency axis's per-bin table (`[lo, hi]` per bin) as a storage buffer.
fn freq_table_buffer(device: &wgpu::Device, table: &[[f32; 2]]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("points::freq_table"),
        contents: bytemuck::cast_slice(table),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

fn cloud_bind_group(
    device: &wgpu::Device,
    pass: &PointsPass,
    i: usize,
    points: &wgpu::Buffer,
    params: &wgpu::Buffer,
    freq_table: &wgpu::Buffer,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&format!("points::bind_group_{i}")),
        layout: &pass.cloud_layout,
        entries: &crate::render::gpu::layouts::whole_buffer_entries(&[points, params, freq_table]),
    })
}

/// The points pipeline, built once.
pub struct PointsPass {
    pipeline: wgpu::RenderPipeline,
    cloud_layout: wgpu::BindGroupLayout,
}

impl PointsPass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "points", &shaders::points());
        let cloud_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("points::cloud_layout"),
            entries: &[
                storage_entry(0, wgpu::ShaderStages::VERTEX, true),
                uniform_entry(1, wgpu::ShaderStages::VERTEX),
                storage_entry(2, wgpu::ShaderStages::VERTEX, true),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("points::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&cloud_layout)],
            immediate_size: 0,
        });
        let pipeline = DrawPipeline {
            label: "points::pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[],
            target: opaque_target(),
            primitive: primitives(wgpu::PrimitiveTopology::TriangleList),
            depth: depth_opaque(),
        }
        .build(device);
        Self {
            pipeline,
            cloud_layout,
        }
    }

    /// Writes this frame's parameters; call before the render pass that draws.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        points: &PointsGpu,
        style: &PointStyle,
        moving: bool,
    ) {
        let stride = lod_stride(points.total, style, moving);
        let lod = lod_stride(points.total, style, true);
        for chunk in &points.chunks {
            let params = |stride| PointParams {
                stride,
                count: chunk.count,
                size_px: style.size_px,
                min_scalar: style.min_scalar,
                freq: points.freq.for_chunk(chunk.first),
            };
            queue.write_buffer(&chunk.params, 0, bytemuck::bytes_of(&params(stride)));
            queue.write_buffer(&chunk.lod_params, 0, bytemuck::bytes_of(&params(lod)));
        }
    }

    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        points: &PointsGpu,
        style: &PointStyle,
        moving: bool,
    ) {
        let stride = lod_stride(points.total, style, moving);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        for chunk in &points.chunks {
            pass.set_bind_group(1, &chunk.bind_group, &[]);
            pass.draw(0..3 * chunk.count.div_ceil(stride), 0..1);
        }
    }

    /// Draws the points `range` (indices into the whole cloud, across chunks) at stride 1: one
    /// slice of a progressive frame (see [`progressive_ranges`]). Call [`PointsPass::prepare`]
    /// with `moving = false` first, so every chunk's stride is 1.
    pub fn draw_range(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        points: &PointsGpu,
        range: std::ops::Range<u64>,
    ) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        let mut chunk_start = 0u64;
        for chunk in &points.chunks {
            let chunk_end = chunk_start + u64::from(chunk.count);
            let (a, b) = (range.start.max(chunk_start), range.end.min(chunk_end));
            if a < b {
                pass.set_bind_group(1, &chunk.bind_group, &[]);
                pass.draw(
                    3 * (a - chunk_start) as u32..3 * (b - chunk_start) as u32,
                    0..1,
                );
            }
            chunk_start = chunk_end;
        }
    }
}

impl PointsPass {
    /// Draws the moving subset (every `lod_stride(total, style, true)`-th point, as
    /// [`PointsPass::prepare`] wrote it) of the points from index `first` on: during a
    /// progressive frame, a sparse stand-in for the points no slice has drawn yet.
    pub fn draw_lod_from(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        points: &PointsGpu,
        style: &PointStyle,
        first: u64,
    ) {
        let stride = u64::from(lod_stride(points.total, style, true));
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        let mut chunk_start = 0u64;
        for chunk in &points.chunks {
            let count = u64::from(chunk.count);
            let instances = lod_instances(first.saturating_sub(chunk_start), count, stride);
            if !instances.is_empty() {
                pass.set_bind_group(1, &chunk.lod_bind_group, &[]);
                pass.draw(3 * instances.start as u32..3 * instances.end as u32, 0..1);
            }
            chunk_start += count;
        }
    }
}

/// The instances of a chunk of `count` points drawn at `stride` (instance `i` is point
/// `i * stride`) whose points are at local index `first` or later.
pub fn lod_instances(first: u64, count: u64, stride: u64) -> std::ops::Range<u64> {
    let stride = stride.max(1);
    first.div_ceil(stride).min(count.div_ceil(stride))..count.div_ceil(stride)
}

/// Submits the queue's pending writes and waits for them, which releases their staging memory.
fn flush_writes(device: &wgpu::Device, queue: &wgpu::Queue) {
    let index = queue.submit([]);
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: Some(index),
        timeout: None,
    });
}

/// The slices of a progressive points frame: `0..total` cut into consecutive ranges of at most
/// `per_slice` points, each point in exactly one (none for an empty cloud).
pub fn progressive_ranges(total: u64, per_slice: u64) -> Vec<std::ops::Range<u64>> {
    let per_slice = per_slice.max(1);
    (0..total.div_ceil(per_slice))
        .map(|i| i * per_slice..((i + 1) * per_slice).min(total))
        .collect()
}

impl PointStyle {
    /// A disc size that suits a cloud of `count` points: small discs for dense song clouds,
    /// larger ones for sparse timelines.
    pub fn size_for(count: usize) -> f32 {
        match count {
            0..=20_000 => 4.0,
            20_001..=100_000 => 3.0,
            _ => 2.0,
        }
    }
}

/// Every how many points one is drawn: 1 at rest, more while moving so that at most
/// `style.max_points_moving` are drawn.
pub fn lod_stride(total: u64, style: &PointStyle, moving: bool) -> u32 {
    let budget = u64::from(style.max_points_moving.max(1));
    if moving && total > budget {
        total.div_ceil(budget) as u32
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_instances_are_the_subset_points_from_first_on() {
        // Stride 4 over 10 points: instances 0, 1, 2 draw points 0, 4, 8.
        assert_eq!(lod_instances(0, 10, 4), 0..3);
        assert_eq!(
            lod_instances(1, 10, 4),
            1..3,
            "point 4 is the first at or after 1"
        );
        assert_eq!(lod_instances(4, 10, 4), 1..3);
        assert_eq!(lod_instances(9, 10, 4), 3..3, "none left");
        assert_eq!(lod_instances(50, 10, 4), 3..3, "past the chunk");
        assert_eq!(lod_instances(3, 10, 1), 3..10);
        // Every point index the instances stand for is >= first and < count.
        for first in 0..12 {
            for i in lod_instances(first, 10, 3) {
                assert!(i * 3 >= first && i * 3 < 10);
            }
        }
    }
}
