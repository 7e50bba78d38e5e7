//! The page of an A/B compare (`loudscape page A --compare B`): A and B side by side from one
//! camera, as the window's Compare view shows them.
//!
//! Reads: the page's two clouds, already on the union of their axes (`data::compare`, done
//! when the page was made, with B moved onto A's time and loudness as asked), and each half's
//! label. Writes: two offscreen targets, one a half, each composited into its half of the view
//! by its own egui paint callback ([`HalfPaint`]).
//!
//! How: on WebGPU one [`Renderer`] draws both halves, each from its own [`SceneData`] (the two
//! frames share the camera, the size and the settings, so the renderer's frame uniforms are the
//! same for both); on WebGL2 each half is a [`gl::GlRenderer`]. Drags, the wheel, F and R
//! move the one camera, so both halves turn together; the point under the cursor in either
//! half shows its values, headed by that half's label. The side panel holds both labels, the hp
//! colours, the union axes and what the page thinned. The halves' places are written on the
//! canvas (`data-compare-halves`, CSS pixels from its corner: `x,y,width,height` of A, `;`, of
//! B) for scripts and tests.
//!
//! Points view only: Surface and Volume would need both grids in one box and on one scale (as
//! `render --compare --compare-as` and the window build them, reading the reference sums back,
//! which a page cannot wait for); each half on its own scale would make equal loudness look
//! unequal. Their buttons say so.

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};
use glam::{Mat4, Vec3};
use wasm_bindgen::prelude::*;

use super::gl;
use crate::data::cloud::PointCloud;
use crate::render::composite::CompositePass;
use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

/// Why the compare page has no Surface or Volume view.
const POINTS_ONLY: &str = "the compare page shows points: a surface or a volume of A beside B \
    needs both grids on one scale, which the window and `render --compare --compare-as` build";

/// Starts the compare viewer on `canvas` with A's and B's page data (`names` in messages),
/// each half labelled (`label_a`, `label_b`); `note` says what the page thinned. Fails with one
/// line (the page shows it) as [`super::start`] does.
#[wasm_bindgen]
#[allow(clippy::too_many_arguments)]
pub async fn start_compare(
    canvas: web_sys::HtmlCanvasElement,
    data_a: Vec<u8>,
    data_b: Vec<u8>,
    name_a: String,
    name_b: String,
    label_a: String,
    label_b: String,
    note: String,
) -> Result<(), JsValue> {
    eframe::WebLogger::init(log::LevelFilter::Warn).ok();
    let decode = |data: &[u8], name: &str| {
        crate::data::page_cloud::decode(data, name).map_err(|e| JsValue::from_str(&e.to_string()))
    };
    let clouds = [decode(&data_a, &name_a)?, decode(&data_b, &name_b)?];
    drop((data_a, data_b));
    let runner = eframe::WebRunner::new();
    let page_canvas = canvas.clone();
    runner
        .start(
            canvas,
            super::web_options(),
            Box::new(move |cc| {
                let app = CompareApp::new(cc, clouds, [label_a, label_b], note, page_canvas)?;
                Ok(Box::new(app))
            }),
        )
        .await?;
    super::RUNNER.with(|r| *r.borrow_mut() = Some(runner));
    Ok(())
}

/// What draws the halves: the window's passes (WebGPU), or the Points view alone (WebGL2).
enum HalvesDrawing {
    Full {
        renderer: Renderer,
        scenes: [SceneData; 2],
    },
    PointsOnly([gl::GlRenderer; 2]),
}

/// One half's offscreen target and its composite into the view.
struct HalfTarget {
    target: Option<RenderTarget>,
    composite: CompositePass,
}

/// GPU state of the compare page, in egui_wgpu's callback resources.
struct CompareResources {
    drawing: HalvesDrawing,
    halves: [HalfTarget; 2],
}

/// The compare viewer: one camera, two clouds, their labels.
struct CompareApp {
    clouds: [PointCloud; 2],
    labels: [String; 2],
    note: String,
    canvas: web_sys::HtmlCanvasElement,
    camera: Camera,
    follow_fit: Option<f32>,
    world_from_data: Mat4,
    world_box: (Vec3, Vec3),
    settings: RenderSettings,
    frame_index: u32,
}

impl CompareApp {
    fn new(
        cc: &eframe::CreationContext<'_>,
        clouds: [PointCloud; 2],
        labels: [String; 2],
        note: String,
        canvas: web_sys::HtmlCanvasElement,
    ) -> Result<Self, String> {
        let render_state = cc
            .wgpu_render_state
            .as_ref()
            .ok_or("this browser offers neither a WebGPU nor a WebGL2 device")?;
        let device = &render_state.device;
        let full = gl::full_view_or_reason(&render_state.adapter, &device.limits());
        device.on_uncaptured_error(Arc::new(|error| log::error!("wgpu error: {error}")));
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        let mut settings = RenderSettings::default();
        let most = clouds[0].len().max(clouds[1].len());
        settings.points.size_px = crate::render::points::PointStyle::size_for(most);
        let mode = clouds[0].meta.mode;
        let world_from_data = crate::render::scene::world_from_data(mode);
        let (box_min, box_max) = crate::render::scene::data_box();
        let world_box = crate::render::scene::world_box(world_from_data, box_min, box_max);
        let drawing = if full.is_ok() {
            let renderer = Renderer::new(device);
            let scenes = clouds
                .each_ref()
                .map(|cloud| SceneData::new(device, &renderer, cloud));
            HalvesDrawing::Full { renderer, scenes }
        } else {
            HalvesDrawing::PointsOnly(
                clouds
                    .each_ref()
                    .map(|cloud| gl::GlRenderer::new(device, cloud, &settings.points)),
            )
        };
        let half = || HalfTarget {
            target: None,
            composite: CompositePass::new(device, render_state.target_format),
        };
        let resources = CompareResources {
            drawing,
            halves: [half(), half()],
        };
        render_state
            .renderer
            .write()
            .callback_resources
            .insert(resources);
        Ok(Self {
            clouds,
            labels,
            note,
            canvas,
            camera: Camera::default(),
            follow_fit: Some(f32::NAN),
            world_from_data,
            world_box,
            settings,
            frame_index: 0,
        })
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("A/B compare");
        for (label, cloud) in self.labels.iter().zip(&self.clouds) {
            ui.label(egui::RichText::new(label).strong());
            ui.label(format!("{} points", cloud.len()));
        }
        if !self.note.is_empty() {
            ui.label(egui::RichText::new(&self.note).small());
        }
        for (cloud, which) in self.clouds.iter().zip(["A", "B"]) {
            for line in cloud.warning_lines() {
                ui.colored_label(
                    egui::Color32::from_rgb(230, 180, 60),
                    format!("{which}: {line}"),
                );
            }
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("View:");
            for view in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
                let on = view == ViewKind::Points;
                let button = ui.add_enabled(
                    on,
                    egui::Button::selectable(self.settings.view == view, view.name()),
                );
                if !on {
                    button.on_disabled_hover_text(format!("Off here: {POINTS_ONLY}"));
                }
            }
        });
        ui.separator();
        ui.label("Colour: harmonic-percussive ratio (hp)");
        super::hp_strip(ui, self.settings.colours.hp);
        ui.separator();
        ui.label("Axes of both halves (the union of A's and B's):");
        super::axes_legend(ui, &self.clouds[0].meta.axes);
        ui.separator();
        ui.label(
            egui::RichText::new(
                "Drag: orbit both · right drag: pan · wheel: zoom · F: fit · R: reset view",
            )
            .small(),
        );
    }

    /// Writes the halves' places on the canvas (`data-compare-halves`), when they change.
    fn publish_halves(&self, halves: &[egui::Rect; 2]) {
        let place = halves
            .iter()
            .map(|r| format!("{},{},{},{}", r.left(), r.top(), r.width(), r.height()))
            .collect::<Vec<_>>()
            .join(";");
        if self.canvas.get_attribute("data-compare-halves").as_deref() != Some(place.as_str()) {
            self.canvas
                .set_attribute("data-compare-halves", &place)
                .ok();
        }
    }
}

/// The two halves of `rect`, A left and B right, a thin gap between them.
fn halves_of(rect: egui::Rect) -> [egui::Rect; 2] {
    const GAP: f32 = 2.0;
    let middle = rect.center().x;
    [
        egui::Rect::from_x_y_ranges(rect.left()..=middle - GAP / 2.0, rect.y_range()),
        egui::Rect::from_x_y_ranges(middle + GAP / 2.0..=rect.right(), rect.y_range()),
    ]
}

impl eframe::App for CompareApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        egui::Panel::right("legend")
            .resizable(false)
            .show(ui, |ui| self.side_panel(ui));
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                let rect = ui.max_rect();
                let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
                let halves = halves_of(rect);
                self.publish_halves(&halves);
                let scale = ctx.pixels_per_point();
                let width = (halves[0].width() * scale).round().max(1.0) as u32;
                let height = (rect.height() * scale).round().max(1.0) as u32;
                let aspect = width as f32 / height as f32;
                let moving = super::camera_input(
                    &mut self.camera,
                    &mut self.follow_fit,
                    self.world_box,
                    &ctx,
                    &response,
                    aspect,
                    height as f32,
                );
                if moving {
                    // One more frame at rest, with every point.
                    ctx.request_repaint();
                }
                self.frame_index = self.frame_index.wrapping_add(1);
                let view = FrameView {
                    camera: self.camera,
                    world_from_data: self.world_from_data,
                    width,
                    height,
                    frame_index: self.frame_index,
                    moving,
                };
                if !moving {
                    for (side, half) in halves.iter().enumerate() {
                        super::point_readout(
                            &response,
                            *half,
                            &view,
                            scale,
                            &self.clouds[side],
                            self.settings.points.min_scalar,
                            Some(&self.labels[side]),
                        );
                    }
                }
                let painter = ui.painter();
                for (side, half) in halves.iter().enumerate() {
                    painter.add(egui_wgpu::Callback::new_paint_callback(
                        *half,
                        HalfPaint {
                            side,
                            view,
                            settings: self.settings.clone(),
                        },
                    ));
                    painter.text(
                        half.left_top() + egui::vec2(10.0, 8.0),
                        egui::Align2::LEFT_TOP,
                        &self.labels[side],
                        egui::FontId::proportional(16.0),
                        egui::Color32::from_gray(235),
                    );
                }
                painter.vline(
                    rect.center().x,
                    rect.y_range(),
                    egui::Stroke::new(2.0, egui::Color32::from_gray(70)),
                );
            });
    }
}

/// One half of a frame: rendered offscreen in `prepare`, composited in `paint`.
struct HalfPaint {
    /// 0: A, 1: B.
    side: usize,
    view: FrameView,
    settings: RenderSettings,
}

impl CallbackTrait for HalfPaint {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(res) = resources.get_mut::<CompareResources>() else {
            return Vec::new();
        };
        let (width, height) = (self.view.width, self.view.height);
        let half = &mut res.halves[self.side];
        if !half
            .target
            .as_ref()
            .is_some_and(|t| t.has_size(width, height))
        {
            let target = RenderTarget::new(device, width, height);
            half.composite.set_source(device, &target);
            half.target = Some(target);
        }
        let Some(target) = &half.target else {
            return Vec::new();
        };
        match &res.drawing {
            HalvesDrawing::Full { renderer, scenes } => renderer.render(
                queue,
                encoder,
                target,
                Some(&scenes[self.side]),
                &self.view,
                &self.settings,
            ),
            HalvesDrawing::PointsOnly(points) => {
                points[self.side].render(queue, encoder, target, &self.view, &self.settings);
            }
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(res) = resources.get::<CompareResources>() {
            res.halves[self.side].composite.draw(render_pass);
        }
    }
}
