//! Points view: draws a cloud's points as screen-aligned discs coloured by hp.
//!
//! Reads: the cloud uploaded by [`PointsGpu`] (one storage buffer per chunk, five f32 per point,
//! the PLY record as is). Writes: colour and depth of the render target.
//! Each point is an instance of three vertices (a triangle around the disc); the fragment
//! shader cuts the disc.
//! Clouds larger than one storage binding are split into chunks, each drawn on its own.
//! While the camera moves, every `stride`-th point is drawn (a level-of-detail subset).
//! The frequency axis of the view ([`PointsGpu::set_freq`], src/data/freq_axis.rs) remaps each
//! point's z in the vertex shader; the stored points are never changed.

use wgpu::util::DeviceExt;

use crate::data::cloud::Point;
use crate::data::freq_axis::{FreqMapping, FreqParams};
use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry};
use crate::render::gpu::target::{COLOR_FORMAT, DEPTH_FORMAT};
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
    points: wgpu::Buffer,
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
    /// [`PointsGpu::chunk_limit`] for the device's own limit).
    pub fn upload(
        device: &wgpu::Device,
        pass: &PointsPass,
        points: &[Point],
        max_chunk_bytes: u64,
    ) -> Self {
        let per_chunk = (max_chunk_bytes / std::mem::size_of::<Point>() as u64).max(1) as usize;
        let freq_table = freq_table_buffer(device, &[crate::data::freq_axis::HIDDEN]);
        let mut chunks = Vec::new();
        for (i, slice) in points.chunks(per_chunk).enumerate() {
            let points_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("points::cloud_chunk_{i}")),
                contents: bytemuck::cast_slice(slice),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            });
            let params = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("points::params_{i}")),
                size: std::mem::size_of::<PointParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group =
                cloud_bind_group(device, pass, i, &points_buffer, &params, &freq_table);
            chunks.push(Chunk {
                count: slice.len() as u32,
                first: (i * per_chunk) as u32,
                params,
                bind_group,
                points: points_buffer,
            });
        }
        Self {
            chunks,
            total: points.len() as u64,
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
        }
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
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("points::pipeline"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_state(true)),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
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
        for chunk in &points.chunks {
            let params = PointParams {
                stride,
                count: chunk.count,
                size_px: style.size_px,
                min_scalar: style.min_scalar,
                freq: points.freq.for_chunk(chunk.first),
            };
            queue.write_buffer(&chunk.params, 0, bytemuck::bytes_of(&params));
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
            pass.draw(0..3, 0..chunk.count.div_ceil(stride));
        }
    }
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

/// Depth test shared by the opaque passes: nearer wins, optionally writing depth.
pub fn depth_state(write: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
}
