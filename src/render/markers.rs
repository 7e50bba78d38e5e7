//! Markers: translucent boxes and planes drawn over the data in data space, such as the playhead
//! plane at the current time, a loop range, or the span of the hovered timeline song.
//!
//! Reads: up to [`MAX_MARKERS`] [`MarkerBox`] instances, written each frame. Writes: colour,
//! alpha-blended and tested against depth (points in front of a plane hide it), no depth writes.
//! A box whose size is zero along one axis is drawn as a plane.

use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::pipeline::{DrawPipeline, alpha_blended_target, depth_over, primitives};
use crate::render::shaders;

pub const MAX_MARKERS: usize = 8;

/// One marker box in data space. Keep in sync with `MarkerInstance` in shaders/markers.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MarkerBox {
    pub min: [f32; 4],
    pub max: [f32; 4],
    /// Face colour, straight alpha.
    pub fill: [f32; 4],
    pub edge: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<MarkerBox>() == 64);

impl MarkerBox {
    /// The box `[x0, x1]` across the full height and depth of the data cube.
    pub fn x_span(x0: f32, x1: f32, fill: [f32; 4], edge: [f32; 4]) -> Self {
        Self {
            min: [x0.min(x1), -1.0, -1.0, 0.0],
            max: [x0.max(x1), 1.0, 1.0, 0.0],
            fill,
            edge,
        }
    }

    /// The playhead: a plane across the data cube at normalized x.
    pub fn playhead(x: f32) -> Self {
        Self::x_span(x, x, [1.0, 1.0, 1.0, 0.14], [1.0, 1.0, 1.0, 0.85])
    }
}

pub struct MarkersPass {
    fill: wgpu::RenderPipeline,
    edges: wgpu::RenderPipeline,
    instances: wgpu::Buffer,
}

impl MarkersPass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "markers", &shaders::markers());
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("markers::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout)],
            immediate_size: 0,
        });
        let instance_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MarkerBox>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![
                0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Float32x4
            ],
        };
        let pipeline = |label: &str, entry: &str, topology: wgpu::PrimitiveTopology| {
            DrawPipeline {
                label,
                layout: &layout,
                module: &module,
                vertex_entry: entry,
                vertex_buffers: &[Some(instance_layout.clone())],
                target: alpha_blended_target(),
                primitive: primitives(topology),
                depth: depth_over(),
            }
            .build(device)
        };
        let fill = pipeline(
            "markers::fill_pipeline",
            "vs_fill",
            wgpu::PrimitiveTopology::TriangleList,
        );
        let edges = pipeline(
            "markers::edge_pipeline",
            "vs_edge",
            wgpu::PrimitiveTopology::LineList,
        );
        let instances = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("markers::instances"),
            size: (MAX_MARKERS * std::mem::size_of::<MarkerBox>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            fill,
            edges,
            instances,
        }
    }

    /// Writes this frame's markers (the first [`MAX_MARKERS`]); call before the render pass.
    pub fn prepare(&self, queue: &wgpu::Queue, markers: &[MarkerBox]) {
        let shown = &markers[..markers.len().min(MAX_MARKERS)];
        if !shown.is_empty() {
            queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(shown));
        }
    }

    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &FrameBinding, count: usize) {
        let count = count.min(MAX_MARKERS) as u32;
        if count == 0 {
            return;
        }
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_vertex_buffer(0, self.instances.slice(..));
        pass.set_pipeline(&self.fill);
        pass.draw(0..36, 0..count);
        pass.set_pipeline(&self.edges);
        pass.draw(0..24, 0..count);
    }
}
