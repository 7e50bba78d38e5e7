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
//! Surface (and, on WebGPU, Volume): both grids are built on the CPU in one box and on one
//! scale ([`voxelize_host::build_on_one_scale`]: the box and the scale the window's compare
//! builds on the GPU, where it reads the reference sums back, which a page cannot wait for), the
//! first frame after the view is chosen; each half on its own scale would make equal loudness
//! look unequal. On WebGPU each grid is uploaded into its half's scene, whose surface the
//! page's marching tetrahedra or dual contouring passes extract ([`super::surface`]) and whose
//! volume the ray march draws; on WebGL2 each half's surface is extracted by the CPU engine
//! ([`super::gl_surface`]) and the Volume view is off. One isovalue slider and one method serve
//! both halves. The canvas says the grids' build and the extractions
//! (`data-surface-timing`: milliseconds of both grids, of the last extraction of A and of B,
//! and A's and B's triangles).

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};
use glam::{Mat4, Vec3};
use wasm_bindgen::prelude::*;

use super::gl;
use super::surface::WebSurface;
use crate::data::cloud::PointCloud;
use crate::render::composite::Offscreen;
use crate::render::grid::VoxelGrid;
use crate::render::grid::voxelize_host;
use crate::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use crate::render::surface::SurfaceSettings;
use crate::render::surface::cpu::Instant;
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

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

/// What draws the halves: the window's passes (WebGPU), or the Points and Surface views
/// (WebGL2).
enum HalvesDrawing {
    Full {
        renderer: Renderer,
        scenes: [SceneData; 2],
        surfaces: [WebSurface; 2],
    },
    Downlevel([gl::GlRenderer; 2]),
}

/// GPU state of the compare page, in egui_wgpu's callback resources.
struct CompareResources {
    drawing: HalvesDrawing,
    /// Each half's offscreen target and its composite into the view.
    halves: [Offscreen; 2],
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
    render_state: eframe::egui_wgpu::RenderState,
    /// The adapter runs every pass (WebGPU); else the Volume view is off, for this reason.
    volume_off: Option<String>,
    /// Milliseconds of both grids' build (None: not built yet).
    grid_ms: Option<f64>,
    /// The surface each half draws (it lags the slider while an extraction runs).
    drawn_surface: [Option<SurfaceSettings>; 2],
    /// What the surfaces hold, or what is under way.
    surface_status: String,
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
            HalvesDrawing::Full {
                surfaces: [WebSurface::new(device), WebSurface::new(device)],
                renderer,
                scenes,
            }
        } else {
            HalvesDrawing::Downlevel(
                clouds
                    .each_ref()
                    .map(|cloud| gl::GlRenderer::new(device, cloud, &settings.points)),
            )
        };
        let half = || Offscreen::new(device, render_state.target_format);
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
            render_state: render_state.clone(),
            volume_off: full.err(),
            grid_ms: None,
            drawn_surface: [None; 2],
            surface_status: String::new(),
        })
    }

    /// Builds both grids on the CPU in one box and on one scale, and gives each half its own
    /// (see the module's header).
    fn build_grids(&mut self) {
        let started = Instant::now();
        let mode = self.clouds[0].meta.mode;
        let voxels = &self.settings.voxels;
        let dims = glam::UVec3::splat(voxels.resolution_for(mode));
        let (grids, (box_min, box_max)) = voxelize_host::build_on_one_scale(
            &self.clouds[0].points,
            &self.clouds[1].points,
            dims,
            voxels.smoothing_for(mode),
        );
        let grid_ms = started.elapsed().as_secs_f64() * 1e3;
        let state = &self.render_state;
        let mut renderer = state.renderer.write();
        let Some(res) = renderer.callback_resources.get_mut::<CompareResources>() else {
            return;
        };
        match &mut res.drawing {
            HalvesDrawing::Full {
                renderer,
                scenes,
                surfaces,
            } => {
                for ((scene, surface), grid) in scenes.iter_mut().zip(surfaces).zip(&grids) {
                    let grid = VoxelGrid::from_fields(
                        &state.device,
                        dims,
                        box_min,
                        box_max,
                        &grid.density,
                        &grid.hp_mean,
                    );
                    scene.set_grid(&state.device, renderer, grid, None, mode, voxels);
                    surface.reset();
                }
            }
            HalvesDrawing::Downlevel(halves) => {
                for (half, grid) in halves.iter_mut().zip(grids) {
                    let field = crate::data::field::Field {
                        dims,
                        box_min,
                        box_max,
                        density: grid.density,
                        hp_mean: grid.hp_mean,
                    };
                    half.surface.set_grid(&field, grid_ms);
                }
            }
        }
        self.grid_ms = Some(grid_ms);
        self.drawn_surface = [None; 2];
    }

    /// Builds both grids unless they are built, the frame after the one that says so. Returns
    /// whether the page should come back for another frame (to build them).
    fn ensure_grids(&mut self) -> bool {
        if self.grid_ms.is_some() {
            return false;
        }
        if self.surface_status.is_empty() {
            // Shown for a frame before the grids' build holds the page.
            self.surface_status = "building both voxel grids on the CPU…".to_string();
            return true;
        }
        self.build_grids();
        false
    }

    /// The Surface view's frame: both grids built the first frame after the view is chosen (the
    /// frame before says so), then each half's surface of the slider's isovalue and method
    /// asked of its extraction. Returns whether the page should come back for another frame.
    fn update_surfaces(&mut self) -> bool {
        if self.ensure_grids() {
            return true;
        }
        let wanted = self.settings.surface;
        let state = &self.render_state;
        let mut renderer = state.renderer.write();
        let Some(res) = renderer.callback_resources.get_mut::<CompareResources>() else {
            return false;
        };
        let mut again = false;
        let mut parts = Vec::new();
        let mut timing = vec![format!("{:.1}", self.grid_ms.unwrap_or(0.0))];
        let mut triangles = Vec::new();
        match &mut res.drawing {
            HalvesDrawing::Full {
                scenes, surfaces, ..
            } => {
                for (side, (scene, surface)) in scenes.iter().zip(surfaces).enumerate() {
                    let Some(grid) = scene.grid.as_ref() else {
                        continue;
                    };
                    let (drawn, busy) =
                        surface.update(&state.device, &state.queue, grid, &scene.surface, wanted);
                    self.drawn_surface[side] = drawn;
                    again |= busy || drawn != Some(wanted);
                    let count = surface.counts.map(|c| c.triangles());
                    triangles.push(count.map_or(String::new(), |c| c.to_string()));
                    timing.push(String::new());
                    parts.push(match (&surface.error, count) {
                        (Some(error), _) => error.clone(),
                        (None, Some(count)) => format!("{count} triangles"),
                        (None, None) => "extracting…".to_string(),
                    });
                }
            }
            HalvesDrawing::Downlevel(halves) => {
                for (side, half) in halves.iter_mut().enumerate() {
                    let count = half
                        .surface
                        .extract(&state.device, &state.queue, wanted, false)
                        .map(|(count, _)| count);
                    self.drawn_surface[side] = count.map(|_| wanted);
                    triangles.push(count.map_or(String::new(), |c| c.to_string()));
                    timing.push(format!("{:.1}", half.surface.extract_ms));
                    parts.push(match count {
                        Some(count) => {
                            format!("{count} triangles in {:.0} ms", half.surface.extract_ms)
                        }
                        None => "no grid".to_string(),
                    });
                }
            }
        }
        self.surface_status = format!(
            "Grids built on the CPU in {:.0} ms. A: {}; B: {}",
            self.grid_ms.unwrap_or(0.0),
            parts.first().map_or("", String::as_str),
            parts.get(1).map_or("", String::as_str),
        );
        timing.extend(triangles);
        let timing = timing.join(",");
        if self.canvas.get_attribute("data-surface-timing").as_deref() != Some(timing.as_str()) {
            self.canvas
                .set_attribute("data-surface-timing", &timing)
                .ok();
        }
        again
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
        let keys = ui.input(|i| {
            [
                (i.key_pressed(egui::Key::P), ViewKind::Points),
                (i.key_pressed(egui::Key::S), ViewKind::Surface),
                (i.key_pressed(egui::Key::V), ViewKind::Volume),
            ]
        });
        for (pressed, view) in keys {
            if pressed && (self.volume_off.is_none() || view != ViewKind::Volume) {
                self.settings.view = view;
            }
        }
        ui.horizontal(|ui| {
            ui.label("View:");
            for view in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
                let on = self.volume_off.is_none() || view != ViewKind::Volume;
                let button = ui.add_enabled(
                    on,
                    egui::Button::selectable(self.settings.view == view, view.name()),
                );
                let button = match &self.volume_off {
                    Some(reason) if !on => {
                        button.on_disabled_hover_text(format!("Off here: {reason}"))
                    }
                    _ => button,
                };
                if button.clicked() {
                    self.settings.view = view;
                }
            }
        });
        ui.separator();
        match self.settings.view {
            ViewKind::Surface => {
                ui.label(
                    "Surface: where the density of the points on a voxel grid crosses the \
                     isovalue, coloured by hp; both grids in one box and on one scale",
                );
                let _ = super::surface_method_and_isovalue(
                    ui,
                    &mut self.settings.surface,
                    &self.canvas,
                );
                ui.label(egui::RichText::new(&self.surface_status).small());
            }
            ViewKind::Volume => {
                ui.label(format!(
                    "Volume: density of the points on a voxel grid, both on one scale, coloured \
                     and made opaque by the {} transfer function",
                    self.settings.volume.preset.name()
                ));
                super::volume_controls(ui, &mut self.settings.volume, &self.canvas);
                if self.grid_ms.is_none() {
                    ui.label(egui::RichText::new(&self.surface_status).small());
                }
            }
            ViewKind::Points => {
                ui.label("Colour: harmonic-percussive ratio (hp)");
            }
        }
        if self.settings.view != ViewKind::Volume {
            super::hp_strip(ui, self.settings.colours.hp);
        }
        ui.separator();
        ui.label("Axes of both halves (the union of A's and B's):");
        super::axes_legend(ui, &self.clouds[0].meta.axes);
        ui.separator();
        ui.label(
            egui::RichText::new(
                "Drag: orbit both · right drag: pan · wheel: zoom · F: fit · R: reset view · P: \
                 points · S: surface · V: volume",
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
                let shown = self.settings.view;
                if shown == ViewKind::Volume && self.ensure_grids() {
                    ctx.request_repaint();
                }
                if shown == ViewKind::Surface && self.update_surfaces() {
                    ctx.request_repaint();
                }
                let painter = ui.painter();
                for (side, half) in halves.iter().enumerate() {
                    let mut settings = self.settings.clone();
                    match (shown, self.drawn_surface[side]) {
                        (ViewKind::Surface, Some(drawn)) => settings.surface = drawn,
                        (ViewKind::Surface, None) => settings.view = ViewKind::Points,
                        (ViewKind::Volume, _) if self.grid_ms.is_none() => {
                            settings.view = ViewKind::Points;
                        }
                        _ => {}
                    }
                    painter.add(egui_wgpu::Callback::new_paint_callback(
                        *half,
                        HalfPaint {
                            side,
                            view,
                            settings,
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
        let half = &mut res.halves[self.side];
        half.ensure_size(device, self.view.width, self.view.height);
        let Some(target) = half.target() else {
            return Vec::new();
        };
        match &res.drawing {
            HalvesDrawing::Full {
                renderer, scenes, ..
            } => renderer.render(
                queue,
                encoder,
                target,
                Some(&scenes[self.side]),
                &self.view,
                &self.settings,
            ),
            HalvesDrawing::Downlevel(points) => {
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
            res.halves[self.side].draw(render_pass);
        }
    }
}
