//! The web page's viewer (`loudscape page`, built by `make web`): the app's own render passes
//! in eframe's web runner, on a canvas, from a cloud the page carries
//! ([`crate::data::page_cloud`]).
//!
//! [`start`] is what the page's script calls with the canvas and the cloud's bytes. The view is
//! one egui paint callback, as the window's (src/ui/bridge.rs): `prepare` renders the scene
//! with [`Renderer::render`] into an offscreen target sized to the view, `paint` composites it
//! into egui's frame. Drags orbit (primary) or pan (secondary), the wheel zooms, F fits and R
//! resets, as in the window; P, S and V (or the side panel) choose the Points, Surface or Volume
//! view. The grid of the Volume and Surface views is built on the GPU by the window's voxelize
//! pass when first shown; the Surface view's isosurface, at the side panel's method and
//! isovalue, is extracted by the window's marching tetrahedra or dual contouring passes
//! ([`surface`]). At rest, what is under the cursor shows in a tooltip with its units, as in the
//! window (`view::pick`): the point in the Points view, the first voxel along the cursor's ray
//! in the Surface and Volume views (on a CPU copy of the grid). A side panel holds the legend
//! (the hp colours, the axes with their units) and what the page thinned. A page with the
//! song's sound moves the playhead plane through the song as it plays ([`set_playhead`]).
//!
//! WebGPU where the browser has it, WebGL2 otherwise. WebGL2 has no compute passes, no storage
//! buffers and no indirect draws: there the view is [`gl::GlRenderer`] (the points as instances,
//! the box and the playhead), the Surface view's grid and isosurface are made on the CPU
//! ([`gl_surface`]), and the Volume view is off, its button saying why.
//! Where the browser has neither, the page's script says so before the viewer starts.

mod compare;
mod controls;
mod gl;
mod gl_surface;
mod surface;

use std::cell::RefCell;
use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};
use glam::{Mat4, Vec3};
use wasm_bindgen::prelude::*;

use crate::data::cloud::PointCloud;
use crate::render::composite::Offscreen;
use crate::render::grid::voxelize::{VoxelizePass, VoxelizeRequest};
use crate::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use crate::render::surface::SurfaceSettings;
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;
use controls::{
    axes_legend, camera_input, hp_strip, point_readout, show_readings, surface_method_and_isovalue,
    volume_controls,
};

thread_local! {
    /// The running viewer: kept for the page's lifetime.
    static RUNNER: RefCell<Option<eframe::WebRunner>> = const { RefCell::new(None) };
    /// The viewer's context, for the page's script to ask for a frame.
    static CONTEXT: RefCell<Option<egui::Context>> = const { RefCell::new(None) };
    /// Where the song's sound is, in seconds (None: the page carries no sound).
    static PLAYHEAD: std::cell::Cell<Option<f64>> = const { std::cell::Cell::new(None) };
}

/// The page's script tells where the song's sound is (seconds into the song) as it plays and
/// when it is moved: the view draws the playhead plane there, as the window does.
#[wasm_bindgen]
pub fn set_playhead(seconds: f64) {
    if !seconds.is_finite() {
        return;
    }
    PLAYHEAD.with(|p| p.set(Some(seconds.max(0.0))));
    CONTEXT.with(|c| {
        if let Some(ctx) = c.borrow().as_ref() {
            ctx.request_repaint();
        }
    });
}

/// Starts the viewer on `canvas` with the page's cloud `data` (named `name` in messages);
/// `note` says what the page thinned. Fails with one line (the page shows it) when the data
/// cannot be read or the browser offers neither a WebGPU nor a WebGL2 device.
#[wasm_bindgen]
pub async fn start(
    canvas: web_sys::HtmlCanvasElement,
    data: Vec<u8>,
    name: String,
    note: String,
) -> Result<(), JsValue> {
    eframe::WebLogger::init(log::LevelFilter::Warn).ok();
    let cloud = crate::data::page_cloud::decode(&data, &name)
        .map_err(|e| JsValue::from_str(&e.to_string()))?;
    drop(data);
    let runner = eframe::WebRunner::new();
    let page_canvas = canvas.clone();
    runner
        .start(
            canvas,
            web_options(),
            Box::new(move |cc| {
                let app = WebApp::new(cc, cloud, note, page_canvas)?;
                Ok(Box::new(app))
            }),
        )
        .await?;
    RUNNER.with(|r| *r.borrow_mut() = Some(runner));
    Ok(())
}

/// The web runner's options: WebGPU first; egui_wgpu drops it for WebGL2 where the browser
/// offers no WebGPU adapter.
fn web_options() -> eframe::WebOptions {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL;
    setup.device_descriptor = Arc::new(crate::render::gpu::context::device_descriptor);
    eframe::WebOptions {
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// GPU state of the page, in egui_wgpu's callback resources.
struct WebResources {
    drawing: Drawing,
    offscreen: Offscreen,
}

/// What draws the view: every pass of the window (WebGPU), or the Points and Surface views
/// (WebGL2).
enum Drawing {
    Full {
        renderer: Renderer,
        scene: SceneData,
        surface: surface::WebSurface,
    },
    Downlevel(gl::GlRenderer),
}

impl WebResources {
    /// The window's passes and scene and the page's surface extraction, on WebGPU.
    fn full(&mut self) -> Option<(&Renderer, &mut SceneData, &mut surface::WebSurface)> {
        match &mut self.drawing {
            Drawing::Full {
                renderer,
                scene,
                surface,
            } => Some((renderer, scene, surface)),
            Drawing::Downlevel(_) => None,
        }
    }

    /// The Surface view's CPU extraction, on WebGL2.
    fn gl_surface(&mut self) -> Option<&mut gl_surface::GlSurface> {
        match &mut self.drawing {
            Drawing::Downlevel(gl) => Some(&mut gl.surface),
            Drawing::Full { .. } => None,
        }
    }
}

/// The viewer: the camera, the settings and what the side panel says.
struct WebApp {
    render_state: egui_wgpu::RenderState,
    cloud: PointCloud,
    /// Why the grid (Volume and Surface views) cannot be built on the GPU: the adapter cannot
    /// (WebGL2: the Surface view's is built on the CPU, the Volume view is off), or a build
    /// failed.
    grid_error: Option<String>,
    /// The adapter runs every pass (WebGPU); else the Volume view is off.
    full: bool,
    /// The surface drawn (it lags the slider while an extraction runs); None before the first.
    drawn_surface: Option<SurfaceSettings>,
    /// The Surface view's read-out: triangles, or why the surface is incomplete.
    surface_status: String,
    /// The grid on the CPU, for the read-out over the Surface and Volume views (the window's
    /// picking, `view::pick`): built there on WebGL2, read back from the GPU on WebGPU.
    field: Option<crate::data::field::Field>,
    /// The isovalue slider is being dragged (WebGL2 extracts the coarse grid meanwhile).
    iso_dragging: bool,
    /// The grid's read-back while the browser has not mapped it (WebGPU).
    field_readback: Option<surface::GridReadback>,
    /// The page's canvas: the isovalue slider's rail is written on it (`data-iso-slider`, CSS
    /// pixels from the canvas's corner: x,y,width,height), for scripts and tests.
    canvas: web_sys::HtmlCanvasElement,
    note: String,
    camera: Camera,
    world_from_data: Mat4,
    world_box: (Vec3, Vec3),
    settings: RenderSettings,
    /// The view's aspect ratio the camera was last fitted at, while the camera follows the view's
    /// shape (from the start, and after F or R, until the user turns, pans or zooms): the side
    /// panel settles its width over the first frames and the browser window can be resized, and a
    /// fit to the first frame's wider view cut a long timeline's box at the left. NaN: fit now.
    follow_fit: Option<f32>,
    frame_index: u32,
}

impl WebApp {
    fn new(
        cc: &eframe::CreationContext<'_>,
        cloud: PointCloud,
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
        CONTEXT.with(|c| *c.borrow_mut() = Some(cc.egui_ctx.clone()));
        let mut settings = RenderSettings::default();
        settings.points.size_px = crate::render::points::PointStyle::size_for(cloud.len());
        let world_from_data = crate::render::scene::world_from_data(cloud.meta.mode);
        let (box_min, box_max) = crate::render::scene::data_box();
        let world_box = crate::render::scene::world_box(world_from_data, box_min, box_max);
        let drawing = if full.is_ok() {
            let renderer = Renderer::new(device);
            let scene = SceneData::new(device, &renderer, &cloud);
            Drawing::Full {
                surface: surface::WebSurface::new(device),
                renderer,
                scene,
            }
        } else {
            Drawing::Downlevel(gl::GlRenderer::new(device, &cloud, &settings.points))
        };
        let resources = WebResources {
            offscreen: Offscreen::new(device, render_state.target_format),
            drawing,
        };
        render_state
            .renderer
            .write()
            .callback_resources
            .insert(resources);
        Ok(Self {
            render_state: render_state.clone(),
            full: full.is_ok(),
            grid_error: full.err(),
            drawn_surface: None,
            surface_status: String::new(),
            field: None,
            iso_dragging: false,
            field_readback: None,
            canvas,
            cloud,
            note,
            camera: Camera::default(),
            world_from_data,
            world_box,
            settings,
            follow_fit: Some(f32::NAN),
            frame_index: 0,
        })
    }

    /// Builds the voxel grid the Volume and Surface views draw, once, on the GPU (the window's
    /// voxelize pass; its statistics are not read back, as a page cannot wait for the GPU).
    fn ensure_grid(&mut self) -> Result<(), String> {
        let state = &self.render_state;
        let mut renderer = state.renderer.write();
        let Some((pass_set, scene, surface)) = renderer
            .callback_resources
            .get_mut::<WebResources>()
            .and_then(WebResources::full)
        else {
            return Ok(());
        };
        if scene.grid.is_some() {
            return Ok(());
        }
        let mode = self.cloud.meta.mode;
        let voxels = &self.settings.voxels;
        let request = VoxelizeRequest::on_device(
            scene.points.chunk_buffers(),
            (self.cloud.bounds.min, self.cloud.bounds.max),
            voxels.resolution_for(mode),
            voxels.smoothing_for(mode),
        );
        let job = pass_set
            .voxelize
            .prepare(&state.device, &request)
            .map_err(|e| e.to_string())?;
        let mut encoder = state
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("web::voxelize"),
            });
        pass_set.voxelize.encode(&mut encoder, &job, None);
        state.queue.submit([encoder.finish()]);
        let grid = VoxelizePass::finish(job);
        self.field_readback = Some(surface::GridReadback::start(
            &state.device,
            &state.queue,
            &grid,
        ));
        scene.set_grid(&state.device, pass_set, grid, None, mode, voxels);
        surface.reset();
        self.drawn_surface = None;
        Ok(())
    }

    /// The Surface view's frame: the surface of the slider's isovalue asked of the extraction
    /// ([`surface::WebSurface::update`]); what is drawn is kept in `drawn_surface`. Returns
    /// whether the page should come back for another frame (an extraction is under way).
    fn update_surface(&mut self) -> bool {
        if !self.full {
            return self.update_gl_surface();
        }
        let state = &self.render_state;
        let mut renderer = state.renderer.write();
        let Some((_, scene, surface)) = renderer
            .callback_resources
            .get_mut::<WebResources>()
            .and_then(WebResources::full)
        else {
            return false;
        };
        let Some(grid) = scene.grid.as_ref() else {
            return false;
        };
        let (drawn, busy) = surface.update(
            &state.device,
            &state.queue,
            grid,
            &scene.surface,
            self.settings.surface,
        );
        self.drawn_surface = drawn;
        self.surface_status = match (&surface.error, surface.counts) {
            (Some(error), _) => error.clone(),
            (None, Some(counts)) if counts.found_nothing() => {
                "no surface: every voxel is below the isovalue".to_string()
            }
            (None, Some(counts)) => format!("{} triangles", counts.triangles()),
            (None, None) => "extracting…".to_string(),
        };
        busy || drawn != Some(self.settings.surface)
    }

    fn view_choice(&mut self, ui: &mut egui::Ui) {
        let keys = ui.input(|i| {
            [
                (i.key_pressed(egui::Key::P), ViewKind::Points),
                (i.key_pressed(egui::Key::S), ViewKind::Surface),
                (i.key_pressed(egui::Key::V), ViewKind::Volume),
            ]
        });
        for (pressed, view) in keys {
            if pressed && (self.full || view != ViewKind::Volume) {
                self.settings.view = view;
            }
        }
        ui.horizontal(|ui| {
            ui.label("View:");
            for view in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
                let on = self.full || view != ViewKind::Volume;
                let button = ui.add_enabled(
                    on,
                    egui::Button::selectable(self.settings.view == view, view.name()),
                );
                let button = match &self.grid_error {
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
        if !self.full {
            if let Some(reason) = &self.grid_error {
                ui.label(
                    egui::RichText::new(format!("No volume: {reason}."))
                        .small()
                        .color(egui::Color32::from_rgb(230, 180, 60)),
                );
            }
            if self.settings.view == ViewKind::Volume {
                self.settings.view = ViewKind::Points;
            }
            return;
        }
        if self.settings.view != ViewKind::Points
            && self.grid_error.is_none()
            && let Err(error) = self.ensure_grid()
        {
            self.grid_error = Some(error);
        }
        if let Some(error) = &self.grid_error {
            ui.colored_label(
                egui::Color32::from_rgb(230, 120, 90),
                format!("The voxel grid cannot be built: {error}"),
            );
            self.settings.view = ViewKind::Points;
        }
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading(crate::annotate::legend::picture_name(&self.cloud));
        ui.label(format!("{} points", self.cloud.len()));
        if !self.note.is_empty() {
            ui.label(egui::RichText::new(&self.note).small());
        }
        for line in self.cloud.warning_lines() {
            ui.colored_label(egui::Color32::from_rgb(230, 180, 60), line);
        }
        ui.separator();
        self.view_choice(ui);
        ui.separator();
        if self.settings.view == ViewKind::Surface {
            self.surface_controls(ui);
        } else if self.settings.view == ViewKind::Volume {
            ui.label(format!(
                "Volume: density of the points on a voxel grid, coloured and made opaque by \
                 the {} transfer function",
                self.settings.volume.preset.name()
            ));
            volume_controls(ui, &mut self.settings.volume, &self.canvas);
        } else {
            ui.label("Colour: harmonic-percussive ratio (hp)");
            hp_strip(ui, self.settings.colours.hp);
        }
        ui.separator();
        axes_legend(ui, &self.cloud.meta.axes);
        ui.separator();
        ui.label(
            egui::RichText::new(
                "Drag: orbit · right drag: pan · wheel: zoom · F: fit · R: reset view · P: points · \
                 S: surface · V: volume",
            )
            .small(),
        );
    }

    /// The Surface view's part of the side panel: the method, the isovalue slider
    /// ([`surface_method_and_isovalue`]) and what the surface holds.
    fn surface_controls(&mut self, ui: &mut egui::Ui) {
        ui.label(
            "Surface: where the density of the points on a voxel grid crosses the isovalue, \
             coloured by hp",
        );
        self.iso_dragging =
            surface_method_and_isovalue(ui, &mut self.settings.surface, &self.canvas);
        ui.label(egui::RichText::new(&self.surface_status).small());
        hp_strip(ui, self.settings.colours.hp);
    }

    /// The camera input of a frame; whether the view moves.
    fn camera_input(
        &mut self,
        ctx: &egui::Context,
        response: &egui::Response,
        aspect: f32,
        height: f32,
    ) -> bool {
        camera_input(
            &mut self.camera,
            &mut self.follow_fit,
            self.world_box,
            ctx,
            response,
            aspect,
            height,
        )
    }
}

impl WebApp {
    /// Takes the grid's read-back once the browser has mapped it. Returns whether the page
    /// should come back for another frame (it has not yet).
    fn collect_field(&mut self) -> bool {
        let Some(readback) = &self.field_readback else {
            return false;
        };
        match readback.take() {
            None => return true,
            Some(Ok(field)) => self.field = Some(field),
            Some(Err(e)) => log::warn!("the grid did not come back for the read-out: {e}"),
        }
        self.field_readback = None;
        false
    }

    /// The view at rest: what is under the cursor, with its units, in a tooltip (the window's
    /// picking and read-out texts, `view::pick`): the point in the Points view; in the Surface
    /// and Volume views, the first voxel along the cursor's ray at the isovalue (or the volume's
    /// pick density), or the time where the ray enters the box while the grid is not on the
    /// CPU. The text goes on the canvas too (`data-readout`: "name: value" lines), for scripts
    /// and tests.
    fn hover_readout(&self, response: &egui::Response, view: &FrameView, scale: f32) {
        if view.moving {
            return;
        }
        let shown = match self.settings.view {
            ViewKind::Points => point_readout(
                response,
                response.rect,
                view,
                scale,
                &self.cloud,
                self.settings.points.min_scalar,
                None,
            ),
            ViewKind::Surface | ViewKind::Volume => self.grid_readout(response, view, scale),
        };
        let text = shown
            .iter()
            .map(|r| format!("{}: {}", r.name, r.value))
            .collect::<Vec<_>>()
            .join("\n");
        if self.canvas.get_attribute("data-readout").as_deref() != Some(text.as_str()) {
            self.canvas.set_attribute("data-readout", &text).ok();
        }
    }

    /// The Surface and Volume views' read-out (see [`Self::hover_readout`]); the readings shown.
    fn grid_readout(
        &self,
        response: &egui::Response,
        view: &FrameView,
        scale: f32,
    ) -> Vec<crate::view::pick::Reading> {
        use crate::view::pick;
        let Some(pos) = response.hover_pos() else {
            return Vec::new();
        };
        let px = (pos - response.rect.min) * scale;
        let (origin, dir) = pick::cursor_ray(view, glam::Vec2::new(px.x, px.y));
        let threshold = match self.settings.view {
            ViewKind::Surface => self.settings.surface.iso_value,
            _ => pick::VOLUME_PICK_DENSITY,
        };
        let axes = &self.cloud.meta.axes;
        let (mut readings, x) =
            pick::grid_readout(self.field.as_ref(), axes, origin, dir, threshold);
        pick::name_readings(
            &mut readings,
            axes,
            self.cloud.meta.mode,
            &self.cloud.meta.songs,
            x,
        );
        show_readings(response, &readings, None);
        readings
    }
}

impl eframe::App for WebApp {
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
                let scale = ctx.pixels_per_point();
                let width = (rect.width() * scale).round().max(1.0) as u32;
                let height = (rect.height() * scale).round().max(1.0) as u32;
                let aspect = width as f32 / height as f32;
                let moving = self.camera_input(&ctx, &response, aspect, height as f32);
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
                if self.collect_field() {
                    ctx.request_repaint();
                }
                self.hover_readout(&response, &view, scale);
                let mut settings = self.settings.clone();
                if let Some(seconds) = PLAYHEAD.with(std::cell::Cell::get)
                    && self.cloud.meta.mode == crate::data::cloud::DataMode::Song
                {
                    // As playback::time_to_x, which the web build has not.
                    let x = self
                        .cloud
                        .meta
                        .axes
                        .x
                        .normalized_of(seconds)
                        .clamp(-1.0, 1.0) as f32;
                    settings.markers = vec![crate::render::markers::MarkerBox::playhead(x)];
                }
                if settings.view == ViewKind::Surface && (self.grid_error.is_none() || !self.full) {
                    if self.update_surface() {
                        ctx.request_repaint();
                    }
                    // The surface the mesh holds: the renderer starts no extraction of its own.
                    match self.drawn_surface {
                        Some(drawn) => settings.surface = drawn,
                        None => settings.view = ViewKind::Points,
                    }
                }
                ui.painter().add(egui_wgpu::Callback::new_paint_callback(
                    rect,
                    ViewPaint { view, settings },
                ));
            });
    }
}

/// One frame of the view: rendered offscreen in `prepare`, composited in `paint`.
struct ViewPaint {
    view: FrameView,
    settings: RenderSettings,
}

impl CallbackTrait for ViewPaint {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(res) = resources.get_mut::<WebResources>() else {
            return Vec::new();
        };
        res.offscreen
            .ensure_size(device, self.view.width, self.view.height);
        match (res.offscreen.target(), &res.drawing) {
            (
                Some(target),
                Drawing::Full {
                    renderer, scene, ..
                },
            ) => renderer.render(
                queue,
                encoder,
                target,
                Some(scene),
                &self.view,
                &self.settings,
            ),
            (Some(target), Drawing::Downlevel(gl)) => {
                gl.render(queue, encoder, target, &self.view, &self.settings);
            }
            (None, _) => {}
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(res) = resources.get::<WebResources>() {
            res.offscreen.draw(render_pass);
        }
    }
}
