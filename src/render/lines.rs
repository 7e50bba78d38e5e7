//! Lines: the box around the data with its tick marks (and any other guide lines), drawn in
//! data space with depth testing so the data can hide the far edges.
//!
//! Reads: a vertex buffer of [`LineVertex`] pairs. Writes: colour, tested against depth.

use wgpu::util::DeviceExt;

use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::pipeline::{DrawPipeline, alpha_blended_target, depth_over, primitives};
use crate::render::shaders;

/// One end of a line segment, as the vertex stage reads it (keep in sync with `LineVertex` in
/// shaders/lines.wgsl: position at location 0, colour at location 1, no padding between them).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    pub position: [f32; 3],
    pub color: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<LineVertex>() == 28);

/// Line segments on the GPU, two vertices each.
pub struct LinesGpu {
    buffer: wgpu::Buffer,
    count: u32,
}

impl LinesGpu {
    pub fn upload(device: &wgpu::Device, label: &str, vertices: &[LineVertex]) -> Self {
        let contents: &[u8] = if vertices.is_empty() {
            &[0; std::mem::size_of::<LineVertex>()]
        } else {
            bytemuck::cast_slice(vertices)
        };
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::VERTEX,
        });
        Self {
            buffer,
            count: vertices.len() as u32,
        }
    }
}

pub struct LinesPass {
    pipeline: wgpu::RenderPipeline,
}

impl LinesPass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "lines", &shaders::lines());
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout)],
            immediate_size: 0,
        });
        let pipeline = DrawPipeline {
            label: "lines::pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<LineVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
            })],
            target: alpha_blended_target(),
            primitive: primitives(wgpu::PrimitiveTopology::LineList),
            depth: depth_over(),
        }
        .build(device);
        Self { pipeline }
    }

    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &FrameBinding, lines: &LinesGpu) {
        if lines.count == 0 {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_vertex_buffer(0, lines.buffer.slice(..));
        pass.draw(0..lines.count, 0..1);
    }
}

/// The twelve edges of the box `[min, max]` plus tick marks on three of its edges, at the given
/// normalized positions along x, y and z.
pub fn box_with_ticks(
    min: glam::Vec3,
    max: glam::Vec3,
    ticks: [&[f32]; 3],
    color: [f32; 4],
) -> Vec<LineVertex> {
    let mut out = Vec::new();
    let corner = |i: u32| {
        glam::Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    };
    let mut segment = |a: glam::Vec3, b: glam::Vec3| {
        out.push(LineVertex {
            position: a.into(),
            color,
        });
        out.push(LineVertex {
            position: b.into(),
            color,
        });
    };
    for i in 0..8u32 {
        for bit in [1u32, 2, 4] {
            if i & bit == 0 {
                segment(corner(i), corner(i | bit));
            }
        }
    }
    // Tick marks on all four edges parallel to each axis, pointing away from the box; the
    // labels pick the edge facing the camera each frame.
    let size = max - min;
    let center = (min + max) * 0.5;
    let tick_length = 0.03 * size.max_element().max(1e-3);
    for (axis, positions) in ticks.iter().enumerate() {
        let out_axis = if axis == 1 { 0 } else { 1 };
        for &t in positions.iter() {
            for corner in 0..4u32 {
                let mut a = center;
                let (p, q) = match axis {
                    0 => (1, 2),
                    1 => (0, 2),
                    _ => (0, 1),
                };
                a[p] = if corner & 1 == 0 { min[p] } else { max[p] };
                a[q] = if corner & 2 == 0 { min[q] } else { max[q] };
                a[axis] = min[axis] + (t + 1.0) * 0.5 * size[axis];
                let mut outward = glam::Vec3::ZERO;
                outward[out_axis] = (a[out_axis] - center[out_axis]).signum() * tick_length;
                segment(a, a + outward);
            }
        }
    }
    out
}
