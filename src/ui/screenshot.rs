//! Screenshots of the 3D view: `picture` renders them offscreen with their labels and legend
//! (drawn on the CPU, no egui) and saves them; this keeps the window's names for them, and
//! [`paint_headless`]: egui run once offscreen, its shapes drawn into a render target (for
//! checking what the window's painter draws).

use eframe::egui::{self, Pos2, Rect};
use eframe::egui_wgpu;

use crate::data::cloud::PointCloud;
pub use crate::picture::{Overlay, ScreenshotError, render_view, save_png, timestamped_name};
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::target::{COLOR_FORMAT, RenderTarget};
use crate::render::scene::{RenderSettings, SceneData};
use crate::view::frame_view::FrameView;

/// Draws the axis labels and the legend of `cloud` over what `target` holds (read back, drawn
/// on the CPU as `picture::draw_overlay` does, written back).
pub fn draw_overlay(
    gpu: &GpuContext,
    target: &RenderTarget,
    view: &FrameView,
    cloud: &PointCloud,
    data: &SceneData,
    settings: &RenderSettings,
    overlay: Overlay,
) {
    let mut image = match target.read_rgba(&gpu.device, &gpu.queue) {
        Ok(image) => image,
        Err(e) => {
            log::warn!("the picture's overlay is left out: {e}");
            return;
        }
    };
    crate::picture::draw_overlay(&mut image, view, cloud, data, settings, overlay);
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &target.color,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        image.as_raw(),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * target.width),
            rows_per_image: Some(target.height),
        },
        wgpu::Extent3d {
            width: target.width,
            height: target.height,
            depth_or_array_layers: 1,
        },
    );
}

/// Runs egui once offscreen over the whole of `target` (one point a pixel), lets `paint` draw
/// with its painter, and renders the shapes into `target` over what it holds.
pub fn paint_headless(
    gpu: &GpuContext,
    target: &RenderTarget,
    paint: impl FnOnce(&egui::Painter, Rect),
) {
    HeadlessPainter::new(gpu).paint(gpu, target, paint);
}

/// egui offscreen, kept between pictures (a video's frames): one context with its font atlas and
/// one renderer, instead of building both for every picture as [`paint_headless`] does. Draws
/// the same pixels.
pub struct HeadlessPainter {
    ctx: egui::Context,
    renderer: egui_wgpu::Renderer,
}

impl HeadlessPainter {
    pub fn new(gpu: &GpuContext) -> Self {
        let ctx = egui::Context::default();
        super::style::install_fonts(&ctx);
        Self {
            ctx,
            renderer: egui_wgpu::Renderer::new(
                &gpu.device,
                COLOR_FORMAT,
                egui_wgpu::RendererOptions::default(),
            ),
        }
    }

    /// Runs egui over the whole of `target` (one point a pixel), lets `paint` draw with its
    /// painter, and renders the shapes into `target` over what it holds.
    pub fn paint(
        &mut self,
        gpu: &GpuContext,
        target: &RenderTarget,
        paint: impl FnOnce(&egui::Painter, Rect),
    ) {
        self.paint_scaled(gpu, target, 1.0, paint);
    }

    /// As [`HeadlessPainter::paint`], `pixels_per_point` pixels a point (larger text and lines
    /// on a larger picture); `paint` gets the rect in points.
    pub fn paint_scaled(
        &mut self,
        gpu: &GpuContext,
        target: &RenderTarget,
        pixels_per_point: f32,
        paint: impl FnOnce(&egui::Painter, Rect),
    ) {
        let (w, h) = (target.width, target.height);
        let ppp = pixels_per_point.max(0.1);
        let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(w as f32 / ppp, h as f32 / ppp));
        let mut input = egui::RawInput {
            screen_rect: Some(rect),
            ..Default::default()
        };
        input
            .viewports
            .entry(egui::ViewportId::ROOT)
            .or_default()
            .native_pixels_per_point = Some(ppp);
        let mut paint = Some(paint);
        let mut output = self.ctx.run_ui(input, |ui| {
            if let Some(paint) = paint.take() {
                paint(ui.painter(), rect);
            }
        });
        let shapes = std::mem::take(&mut output.shapes);
        let primitives = self.ctx.tessellate(shapes, ppp);
        let renderer = &mut self.renderer;
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                renderer.update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point: ppp,
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("screenshot::overlay"),
            });
        let extra =
            renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, &primitives, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("screenshot::overlay"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &target.color_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            renderer.render(&mut pass, &primitives, &screen);
        }
        gpu.queue
            .submit(extra.into_iter().chain(std::iter::once(encoder.finish())));
        for id in &output.textures_delta.free {
            renderer.free_texture(id);
        }
        // Every delta was applied above.
        output.textures_delta.clear();
    }
}
