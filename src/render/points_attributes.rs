//! Points view on an adapter without storage buffers in the vertex stage (WebGL2: the web
//! page's fallback, src/web/): the same screen-aligned discs, hp colours and pixel size as
//! [`super::points`], from the same point records.
//!
//! Reads: the cloud as a per-instance vertex buffer (five f32 per point, the PLY record as is:
//! position at location 0, scalar and hp at location 1), and a second one holding the moving
//! subset (every [`lod_stride`]-th point), since an instance buffer cannot be read at a
//! stride chosen per frame. Writes: colour and depth of the render target.
//! Each point is an instance of three vertices (a triangle around the disc); the fragment
//! shader cuts the disc. z is drawn as stored: the frequency axis's per-bin table
//! ([`super::points::PointsGpu::set_freq`]) is a storage buffer, which WebGL2 has not.
//! One buffer holds the whole cloud (a vertex buffer is not bounded by a storage binding).

use wgpu::util::DeviceExt;

use crate::data::cloud::{POINT_BYTES, Point};
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::uniform_entry;
use crate::render::gpu::pipeline::{DrawPipeline, depth_opaque, opaque_target, primitives};
use crate::render::points::{PointStyle, lod_stride};
use crate::render::shaders;

/// Keep in sync with `PointStyleParams` in shaders/points_instanced.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PointStyleParams {
    size_px: f32,
    min_scalar: f32,
    _pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<PointStyleParams>() == 16);
const _: () = assert!(POINT_BYTES == 20);

/// A cloud's points as instance vertex buffers.
pub struct InstancedPointsGpu {
    points: wgpu::Buffer,
    /// Every `moving_stride`-th point (the subset drawn while the camera moves).
    moving: wgpu::Buffer,
    moving_count: u32,
    pub total: u64,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl InstancedPointsGpu {
    /// Uploads `points`, and the subset `style` draws while moving.
    pub fn upload(
        device: &wgpu::Device,
        pass: &InstancedPointsPass,
        points: &[Point],
        style: &PointStyle,
    ) -> Self {
        let total = points.len() as u64;
        let stride = lod_stride(total, style, true) as usize;
        let subset: Vec<Point> = points.iter().step_by(stride.max(1)).copied().collect();
        let buffer = |label: &str, slice: &[Point]| {
            let contents: &[u8] = if slice.is_empty() {
                &[0; POINT_BYTES]
            } else {
                bytemuck::cast_slice(slice)
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::VERTEX,
            })
        };
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("points_instanced::params"),
            size: std::mem::size_of::<PointStyleParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("points_instanced::bind_group"),
            layout: &pass.style_layout,
            entries: &crate::render::gpu::layouts::whole_buffer_entries(&[&params]),
        });
        Self {
            points: buffer("points_instanced::cloud", points),
            moving: buffer("points_instanced::moving_subset", &subset),
            moving_count: subset.len() as u32,
            total,
            params,
            bind_group,
        }
    }
}

/// The instanced points pipeline, built once.
pub struct InstancedPointsPass {
    pipeline: wgpu::RenderPipeline,
    style_layout: wgpu::BindGroupLayout,
}

impl InstancedPointsPass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "points_instanced", &shaders::points_instanced());
        let style_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("points_instanced::style_layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("points_instanced::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&style_layout)],
            immediate_size: 0,
        });
        let pipeline = DrawPipeline {
            label: "points_instanced::pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: POINT_BYTES as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2],
            })],
            target: opaque_target(),
            primitive: primitives(wgpu::PrimitiveTopology::TriangleList),
            depth: depth_opaque(),
        }
        .build(device);
        Self {
            pipeline,
            style_layout,
        }
    }

    /// Writes this frame's parameters; call before the render pass that draws.
    pub fn prepare(&self, queue: &wgpu::Queue, points: &InstancedPointsGpu, style: &PointStyle) {
        let params = PointStyleParams {
            size_px: style.size_px,
            min_scalar: style.min_scalar,
            _pad: [0.0; 2],
        };
        queue.write_buffer(&points.params, 0, bytemuck::bytes_of(&params));
    }

    /// Draws every point at rest, the moving subset while the camera moves (as
    /// [`super::points::PointsPass::draw`]).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        points: &InstancedPointsGpu,
        moving: bool,
    ) {
        let (buffer, count) = if moving {
            (&points.moving, points.moving_count)
        } else {
            (&points.points, points.total as u32)
        };
        if count == 0 {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_bind_group(1, &points.bind_group, &[]);
        pass.set_vertex_buffer(0, buffer.slice(..));
        pass.draw(0..3, 0..count);
    }
}
