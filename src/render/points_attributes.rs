//! Points view on an adapter without storage buffers in the vertex stage (WebGL2: the web
//! page's fallback, src/web/): the same screen-aligned discs, hp colours and pixel size as
//! [`super::points`], from the same point records.
//!
//! Reads: the cloud as a vertex buffer holding each point's record (five f32, the PLY record
//! as is: position at location 0, scalar and hp at location 1) three times in a row, one for
//! each vertex of the triangle around its disc, and a second one of the moving subset (every
//! [`lod_stride`]-th point), since a vertex buffer cannot be read at a stride chosen per frame.
//! Writes: colour and depth of the render target. Not instanced, for the reason the storage
//! pass is not: a software rasterizer (SwiftShader's WebGL2) shades vertices in batches within a
//! draw, and a three-vertex instance fills one batch with three (an orbit took 2.8 s a frame
//! instanced, in headless chromium). The cost is three copies of the cloud on the GPU.
//! z is drawn as stored: the frequency axis's per-bin table
//! ([`super::points::PointsGpu::set_freq`]) is a storage buffer, which WebGL2 has not.
//! One buffer holds the whole cloud (a vertex buffer is not bounded by a storage binding).

use wgpu::util::DeviceExt;

use crate::data::cloud::{POINT_BYTES, Point};
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::uniform_entry;
use crate::render::gpu::pipeline::{DrawPipeline, depth_opaque, opaque_target, primitives};
use crate::render::points::{PointStyle, lod_stride};
use crate::render::shaders;

/// Keep in sync with `PointStyleParams` in shaders/points_attributes.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PointStyleParams {
    size_px: f32,
    min_scalar: f32,
    _pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<PointStyleParams>() == 16);
const _: () = assert!(POINT_BYTES == 20);

/// A cloud's points as vertex buffers, each record three times.
pub struct AttributePointsGpu {
    points: wgpu::Buffer,
    /// Every `lod_stride(total, style, true)`-th point (the subset drawn while the camera moves).
    moving: wgpu::Buffer,
    moving_count: u32,
    pub total: u64,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl AttributePointsGpu {
    /// Uploads `points`, and the subset `style` draws while moving.
    pub fn upload(
        device: &wgpu::Device,
        pass: &AttributePointsPass,
        points: &[Point],
        style: &PointStyle,
    ) -> Self {
        let total = points.len() as u64;
        let stride = lod_stride(total, style, true) as usize;
        let buffer = |label: &str, chosen: &mut dyn Iterator<Item = &Point>| {
            let thrice: Vec<Point> = chosen.flat_map(|p| [*p; 3]).collect();
            let contents: &[u8] = if thrice.is_empty() {
                &[0; POINT_BYTES]
            } else {
                bytemuck::cast_slice(&thrice)
            };
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::VERTEX,
            });
            (buffer, (thrice.len() / 3) as u32)
        };
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("points_attributes::params"),
            size: std::mem::size_of::<PointStyleParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("points_attributes::bind_group"),
            layout: &pass.style_layout,
            entries: &crate::render::gpu::layouts::whole_buffer_entries(&[&params]),
        });
        let (all, _) = buffer("points_attributes::cloud", &mut points.iter());
        let (moving, moving_count) = buffer(
            "points_attributes::moving_subset",
            &mut points.iter().step_by(stride.max(1)),
        );
        Self {
            points: all,
            moving,
            moving_count,
            total,
            params,
            bind_group,
        }
    }
}

/// The points pipeline of vertex attributes, built once.
pub struct AttributePointsPass {
    pipeline: wgpu::RenderPipeline,
    style_layout: wgpu::BindGroupLayout,
}

impl AttributePointsPass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "points_attributes", &shaders::points_attributes());
        let style_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("points_attributes::style_layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("points_attributes::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&style_layout)],
            immediate_size: 0,
        });
        let pipeline = DrawPipeline {
            label: "points_attributes::pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: POINT_BYTES as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
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
    pub fn prepare(&self, queue: &wgpu::Queue, points: &AttributePointsGpu, style: &PointStyle) {
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
        points: &AttributePointsGpu,
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
        pass.draw(0..3 * count, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::cloud::{DataMode, PointCloud};
    use crate::render::colormap::PaletteUniforms;
    use crate::render::gpu::context::GpuContext;
    use crate::render::gpu::target::RenderTarget;
    use crate::render::scene::{RenderSettings, Renderer, SceneData, begin_main_pass};
    use crate::view::camera::Camera;
    use crate::view::frame_view::FrameView;

    /// A cloud of `n` points spread over the box, with every scalar and hp (a fixed sequence).
    fn spread_cloud(n: usize) -> PointCloud {
        let mut state = 38u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let points = (0..n)
            .map(|_| Point {
                position: [next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0],
                scalar: next(),
                hp: next(),
            })
            .collect();
        PointCloud::synthetic(points, DataMode::Song)
    }

    /// The variant of vertex attributes (WebGL2) draws exactly the picture of the
    /// storage-buffer points pass, at rest and while the camera moves (the same subset), quiet
    /// points hidden.
    #[test]
    fn attribute_points_draw_what_the_storage_pass_draws() {
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe where none)");
        let (device, queue) = (&gpu.device, &gpu.queue);
        let renderer = Renderer::new(device);
        let cloud = spread_cloud(90_000);
        let scene = SceneData::new(device, &renderer, &cloud);
        let mut settings = RenderSettings {
            show_box: false,
            ..Default::default()
        };
        settings.points.size_px = 3.0;
        settings.points.min_scalar = 0.2;
        assert!(lod_stride(cloud.len() as u64, &settings.points, true) > 1);
        let pass = AttributePointsPass::new(device, &renderer.frame);
        let attributes = AttributePointsGpu::upload(device, &pass, &cloud.points, &settings.points);
        for moving in [false, true] {
            let mut view = FrameView::fitted(
                Camera::default(),
                scene.world_from_data,
                scene.world_box(),
                320,
                200,
            );
            view.moving = moving;
            let render = |attribute_pass: bool| {
                let target = RenderTarget::new(device, view.width, view.height);
                let mut encoder = device.create_command_encoder(&Default::default());
                if attribute_pass {
                    renderer.frame.write(queue, &view);
                    renderer.frame.write_palette(
                        queue,
                        &PaletteUniforms::new(&settings.colours, settings.volume.preset),
                    );
                    pass.prepare(queue, &attributes, &settings.points);
                    let [r, g, b] = settings.colours.background.rgb().map(f64::from);
                    let clear = wgpu::Color { r, g, b, a: 1.0 };
                    let mut render_pass = begin_main_pass(&mut encoder, &target, Some(clear));
                    pass.draw(&mut render_pass, &renderer.frame, &attributes, moving);
                } else {
                    renderer.render(queue, &mut encoder, &target, Some(&scene), &view, &settings);
                }
                queue.submit([encoder.finish()]);
                target.read_rgba(device, queue).expect("read back")
            };
            let (storage, attributes) = (render(false), render(true));
            let background = storage
                .pixels()
                .filter(|p| p.0 == storage.get_pixel(0, 0).0);
            assert!(
                background.count() < storage.pixels().len() * 9 / 10,
                "the storage pass drew almost nothing (moving {moving})"
            );
            let differing = storage
                .pixels()
                .zip(attributes.pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differing, 0, "pixels differ (moving {moving})");
        }
    }
}
