//! Screenshots of the 3D view: the same passes as the window, rendered offscreen at any size with
//! the axis labels and the legend (colour key, the song's or timeline's name; `ui::legends`)
//! drawn over them, saved as PNG through a temporary file and a rename (so a reader never sees
//! half a file). [`paint_headless`] runs egui once offscreen and draws its shapes into a render
//! target, for every overlay of a headless picture.

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use eframe::egui::{self, Pos2, Rect};
use eframe::egui_wgpu;
use thiserror::Error;

use crate::data::cloud::PointCloud;
use crate::files::TempFile;
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::target::{COLOR_FORMAT, RenderTarget};
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

#[derive(Debug, Error)]
pub enum ScreenshotError {
    #[error("cannot read the screenshot back from the GPU: {0}")]
    Readback(#[from] crate::render::gpu::readback::ReadbackError),
    #[error("{path}: cannot write the screenshot: {reason}")]
    Write { path: PathBuf, reason: String },
}

/// Renders the view (labels included when the settings show the box) and reads it back.
pub fn render_view(
    gpu: &GpuContext,
    renderer: &Renderer,
    scene: Option<(&PointCloud, &SceneData)>,
    view: &FrameView,
    settings: &RenderSettings,
) -> Result<image::RgbaImage, ScreenshotError> {
    let mut view = *view;
    view.moving = false;
    let target = crate::render::headless::render_frame(
        gpu,
        renderer,
        scene.map(|(_, data)| data),
        &view,
        settings,
    );
    if let Some((cloud, data)) = scene {
        let overlay = Overlay {
            labels: settings.show_box,
            legend: true,
        };
        draw_overlay(gpu, &target, &view, cloud, data, settings, overlay);
    }
    Ok(target.read_rgba(&gpu.device, &gpu.queue)?)
}

/// What is drawn over a headless picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overlay {
    /// Axis tick labels and titles.
    pub labels: bool,
    /// The colour key and the name (`ui::legends::paint_picture`).
    pub legend: bool,
}

/// Draws the axis labels and the legend of `cloud`, as `settings` show it, over what `target`
/// holds, in the ink of the settings' background.
pub fn draw_overlay(
    gpu: &GpuContext,
    target: &RenderTarget,
    view: &FrameView,
    cloud: &PointCloud,
    data: &SceneData,
    settings: &RenderSettings,
    overlay: Overlay,
) {
    if !overlay.labels && !overlay.legend {
        return;
    }
    let labels = crate::ui::labels::axis_labels(cloud, data);
    let legend = crate::ui::legends::picture_legend(cloud, settings);
    let background = settings.colours.background;
    paint_headless(gpu, target, |painter, rect| {
        if overlay.labels {
            crate::ui::labels::paint_on(painter, rect, view, &labels, background);
        }
        if overlay.legend {
            crate::ui::legends::paint_picture(painter, rect, &legend);
        }
    });
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
        Self {
            ctx: egui::Context::default(),
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

/// Writes `image` to `path` as PNG: first to `PATH.partial` beside it, then renamed; the partial
/// file is removed on every error path and on SIGTERM/SIGINT (see [`crate::files::TempFile`]).
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<(), ScreenshotError> {
    let write_error = |reason: String| ScreenshotError::Write {
        path: path.to_path_buf(),
        reason,
    };
    // A full disk reads as such, however the encoder put it.
    let io_error = |e: std::io::Error| write_error(crate::files::write_reason(&e));
    let mut tmp = TempFile::create(path, ".partial").map_err(io_error)?;
    {
        let mut out = std::io::BufWriter::new(tmp.file());
        image
            .write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| match e {
                image::ImageError::IoError(e) => io_error(e),
                e => write_error(e.to_string()),
            })?;
        std::io::Write::flush(&mut out).map_err(io_error)?;
    }
    tmp.persist(path).map_err(io_error)
}

/// `loudscape-20260123-142501.png` (UTC) for the given moment.
pub fn timestamped_name(now: SystemTime) -> PathBuf {
    let secs = now.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    PathBuf::from(format!(
        "loudscape-{year:04}{month:02}{day:02}-{:02}{:02}{:02}.png",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    ))
}

/// Days since 1970-01-01 to (year, month, day), proleptic Gregorian (Howard Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn names_carry_the_utc_time() {
        let t = UNIX_EPOCH + Duration::from_secs(1_700_000_000);
        assert_eq!(
            timestamped_name(t),
            PathBuf::from("loudscape-20231114-221320.png")
        );
        assert_eq!(
            timestamped_name(UNIX_EPOCH),
            PathBuf::from("loudscape-19700101-000000.png")
        );
    }
}
