//! Text over the 3D view: axis tick labels and axis titles in physical units.
//!
//! The window paints these with its egui painter each frame; the headless renderer runs egui
//! once offscreen and draws the same shapes into the render target, so PNGs carry the same labels.

use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect};
use eframe::egui_wgpu;
use glam::Vec3;

use crate::axes::Axis;
use crate::cloud::PointCloud;
use crate::render::context::GpuContext;
use crate::render::frame::FrameView;
use crate::render::scene::SceneData;
use crate::render::target::{COLOR_FORMAT, RenderTarget};

/// A piece of text anchored at a point in data space.
#[derive(Clone, Debug)]
pub struct Label {
    pub anchor: Vec3,
    pub text: String,
    /// Pixel offset from the projected anchor.
    pub offset: egui::Vec2,
    pub align: Align2,
    pub title: bool,
}

/// "time (s)", or just "hp" for a unitless axis.
pub fn axis_title(axis: &Axis, fallback: &str) -> String {
    let name = if axis.label.is_empty() {
        fallback
    } else {
        &axis.label
    };
    if axis.unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({})", axis.unit)
    }
}

/// Tick labels and axis titles for the box drawn by the scene, on the same edges as its ticks.
pub fn axis_labels(cloud: &PointCloud, data: &SceneData) -> Vec<Label> {
    axis_labels_for_box(cloud, data.box_min, data.box_max)
}

/// Tick labels and axis titles for a box `[min, max]` in data space.
pub fn axis_labels_for_box(cloud: &PointCloud, min: Vec3, max: Vec3) -> Vec<Label> {
    let size = max - min;
    let axes = &cloud.meta.axes;
    let along = |t: f32, lo: f32, extent: f32| lo + (t + 1.0) * 0.5 * extent;
    let mut labels = Vec::new();
    let mut push_axis = |axis: &Axis,
                         fallback: &str,
                         place: &dyn Fn(f32) -> Vec3,
                         offset: egui::Vec2,
                         align: Align2| {
        for tick in axis.ticks(8) {
            labels.push(Label {
                anchor: place(tick.at),
                text: tick.label,
                offset,
                align,
                title: false,
            });
        }
        labels.push(Label {
            anchor: place(0.0),
            text: axis_title(axis, fallback),
            offset: offset * 3.2,
            align,
            title: true,
        });
    };
    push_axis(
        &axes.x,
        "x",
        &|t| Vec3::new(along(t, min.x, size.x), min.y, max.z),
        egui::vec2(0.0, 10.0),
        Align2::CENTER_TOP,
    );
    push_axis(
        &axes.y,
        "y",
        &|t| Vec3::new(min.x, along(t, min.y, size.y), max.z),
        egui::vec2(-10.0, 0.0),
        Align2::RIGHT_CENTER,
    );
    push_axis(
        &axes.z,
        "z",
        &|t| Vec3::new(max.x, min.y, along(t, min.z, size.z)),
        egui::vec2(10.0, 4.0),
        Align2::LEFT_TOP,
    );
    labels
}

/// Paints labels projected through `view` into `rect` (the 3D view's place on screen, points).
pub fn paint(painter: &egui::Painter, rect: Rect, view: &FrameView, labels: &[Label]) {
    let scale = rect.width() / view.width.max(1) as f32;
    let mut placed: Vec<Rect> = Vec::new();
    // Titles first, so ticks make way for them.
    let ordered = labels
        .iter()
        .filter(|l| l.title)
        .chain(labels.iter().filter(|l| !l.title));
    for label in ordered {
        let Some(pixel) = view.project(label.anchor) else {
            continue;
        };
        let pos = rect.min + egui::vec2(pixel.x, pixel.y) * scale + label.offset;
        if !rect.expand(40.0).contains(pos) {
            continue;
        }
        let (size, color) = if label.title {
            (14.0, Color32::from_rgb(225, 230, 238))
        } else {
            (12.0, Color32::from_rgb(160, 168, 182))
        };
        // Skip a label that would overlap one already placed (crowded ticks at some angles).
        let galley = painter.layout_no_wrap(label.text.clone(), FontId::proportional(size), color);
        let text_rect = label.align.anchor_size(pos, galley.size());
        if placed
            .iter()
            .any(|r: &Rect| r.expand(2.0).intersects(text_rect))
        {
            continue;
        }
        placed.push(text_rect);
        painter.galley(text_rect.min, galley, color);
    }
}

/// Draws the labels of `cloud` over what `target` holds, without a window.
pub fn draw_headless(
    gpu: &GpuContext,
    target: &RenderTarget,
    view: &FrameView,
    cloud: &PointCloud,
    data: &SceneData,
) {
    let labels = axis_labels(cloud, data);
    let (w, h) = (target.width, target.height);
    let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(w as f32, h as f32));
    let ctx = egui::Context::default();
    let input = egui::RawInput {
        screen_rect: Some(rect),
        ..Default::default()
    };
    let mut output = ctx.run_ui(input, |ui| {
        paint(ui.painter(), rect, view, &labels);
    });
    let shapes = std::mem::take(&mut output.shapes);
    let primitives = ctx.tessellate(shapes, 1.0);
    let mut renderer = egui_wgpu::Renderer::new(
        &gpu.device,
        COLOR_FORMAT,
        egui_wgpu::RendererOptions::default(),
    );
    for (id, deltas) in &output.textures_delta.set {
        for delta in deltas {
            renderer.update_texture(&gpu.device, &gpu.queue, *id, delta);
        }
    }
    // Applied above; the renderer is dropped at the end, which frees its textures.
    output.textures_delta.clear();
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [w, h],
        pixels_per_point: 1.0,
    };
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("overlay::labels"),
        });
    let extra =
        renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, &primitives, &screen);
    {
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("overlay::labels"),
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
}

/// Lines describing a cloud for the side panel: where it came from and its loudness metrics.
pub fn describe_cloud(cloud: &PointCloud) -> Vec<String> {
    let meta = &cloud.meta;
    let mut lines = Vec::new();
    match meta.mode {
        crate::cloud::DataMode::Song => lines.push("Song".to_string()),
        crate::cloud::DataMode::Timeline => {
            lines.push(format!("Timeline of {} songs", meta.songs.len()))
        }
        crate::cloud::DataMode::Generic => {
            lines.push("Generic point cloud (no loudscape metadata)".into())
        }
    }
    if let Some(source) = &meta.source {
        if let Some(path) = &source.path {
            lines.push(format!("source: {path}"));
        }
        let mut parts = Vec::new();
        if let Some(d) = source.duration_s {
            parts.push(format!("{d:.1} s"));
        }
        if let Some(rate) = source.sample_rate {
            parts.push(format!("{rate} Hz"));
        }
        if let Some(ch) = source.channels {
            parts.push(format!("{ch} ch"));
        }
        if !parts.is_empty() {
            lines.push(parts.join(", "));
        }
    }
    if let Some(m) = &meta.metrics {
        lines.extend(describe_metrics(m));
    }
    lines
}

/// Loudness metrics as "name: value unit" lines, leaving out the ones not measured.
pub fn describe_metrics(m: &crate::cloud::Metrics) -> Vec<String> {
    let rows = [
        ("integrated loudness", m.integrated_lufs, "LUFS"),
        ("loudness range", m.lra_lu, "LU"),
        ("sample peak", m.sample_peak_dbfs, "dBFS"),
        ("true peak", m.true_peak_dbtp, "dBTP"),
        ("PLR", m.plr_db, "dB"),
        ("crest factor, median", m.crest_median_db, "dB"),
        ("crest factor, 95th pct", m.crest_p95_db, "dB"),
    ];
    rows.iter()
        .filter_map(|(name, value, unit)| value.map(|v| format!("{name}: {v:.1} {unit}")))
        .collect()
}
