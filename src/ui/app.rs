//! The loudscape window's wiring: `LoudscapeApp`'s state, opening the window, one frame (side
//! panel, transport bar, 3D view) and the camera input of the 3D view. The panels, hover
//! read-outs, data slots, persistence and screenshots each have their own file in `ui/`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32};
use eframe::egui_wgpu;

use crate::render::scene::{RenderSettings, ViewKind};
use crate::ui::audio::AudioPanel;
use crate::ui::bridge::{ViewCallback, ViewResources};
use crate::ui::hover::paint_readings;
use crate::ui::labels;
use crate::ui::persistence::Remembered;
use crate::ui::state::{LoudscapeApp, SaveShot, ScreenshotState, Slot};
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

/// How long after the last input the view still counts as moving (drawn at reduced quality).
const SETTLE: Duration = Duration::from_millis(180);
/// Volume frames slower than this at rest are replaced by the points while the camera moves.
const VOLUME_PROXY_MS: f32 = 80.0;

/// Options from the command line.
#[derive(Clone, Debug, Default)]
pub struct WindowOptions {
    pub files: Vec<PathBuf>,
    /// Save a screenshot of the window here once the data is shown, then close (for tests).
    pub screenshot: Option<PathBuf>,
    /// The view to open in (otherwise the remembered one, or Points).
    pub view: Option<ViewKind>,
}

/// Opens the window and runs until it closes.
pub fn run(options: WindowOptions) -> anyhow::Result<()> {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(crate::render::gpu::context::device_descriptor);
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("loudscape")
            .with_inner_size([1280.0, 800.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup),
            ..Default::default()
        },
        ..Default::default()
    };
    eframe::run_native(
        "loudscape",
        native,
        Box::new(move |cc| {
            let render_state = cc
                .wgpu_render_state
                .as_ref()
                .ok_or("no GPU render state: loudscape needs wgpu (Vulkan, Metal or DX12)")?;
            ViewResources::install(render_state);
            // Scripted screenshot runs (tests) start from defaults and remember nothing.
            let remembered = if options.screenshot.is_some() {
                None
            } else {
                cc.storage
                    .and_then(|s| eframe::get_value::<Remembered>(s, eframe::APP_KEY))
            };
            Ok(Box::new(LoudscapeApp::new(options, remembered)))
        }),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the window: {e}"))
}

impl LoudscapeApp {
    fn new(options: WindowOptions, remembered: Option<Remembered>) -> Self {
        let persist = options.screenshot.is_none();
        let mut app = Self {
            song: None,
            timeline: None,
            active: Slot::Song,
            settings: RenderSettings::default(),
            camera: Camera::default(),
            fit_pending: true,
            loading: Vec::new(),
            messages: Vec::new(),
            next_id: 1,
            last_motion: None,
            frame_index: 0,
            frame_ms: 0.0,
            view_aspect: 1.6,
            screenshot: options.screenshot.map(|path| ScreenshotState {
                path,
                frames_shown: 0,
                requested: false,
                done: Arc::new(AtomicBool::new(false)),
            }),
            audio: AudioPanel::new(persist),
            hover: None,
            hovered_song: None,
            selected_song: None,
            save_shot: SaveShot::default(),
            last_view: None,
            audio_for: Vec::new(),
            persist,
            keep_camera_loads: 0,
            surface_error: None,
            needs_repaint: false,
            volume_rest_ms: 0.0,
        };
        let files = app.apply_remembered(options.files, remembered);
        if let Some(view) = options.view {
            app.settings.view = view;
        }
        for file in files {
            app.start_loading(file);
        }
        app
    }

    fn fit(&mut self) {
        if let Some(loaded) = self.active() {
            let (min, max) = loaded.world_box;
            let aspect = self.view_aspect;
            self.camera.fit(min, max, aspect);
        }
    }

    fn view_3d(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        let width = (rect.width() * ppp).round().max(1.0) as u32;
        let height = (rect.height() * ppp).round().max(1.0) as u32;
        self.view_aspect = width as f32 / height as f32;
        if self.fit_pending && self.active().is_some() {
            self.fit();
            self.fit_pending = false;
        }

        // Camera input.
        let mut moved = false;
        let delta = response.drag_delta() * ppp;
        if response.dragged_by(egui::PointerButton::Primary) {
            self.camera.orbit(delta.x, delta.y, height as f32);
            moved = true;
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            self.camera.pan(delta.x, delta.y, height as f32);
            moved = true;
        }
        if response.hovered() {
            let scroll = ui.ctx().input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera.zoom(scroll / 50.0);
                moved = true;
            }
        }
        if ui.ctx().input(|i| i.key_pressed(egui::Key::F)) && !ui.ctx().egui_wants_keyboard_input()
        {
            self.fit();
            moved = true;
        }
        let now = Instant::now();
        if moved {
            self.last_motion = Some(now);
        }
        let moving = self.last_motion.is_some_and(|t| now - t < SETTLE);
        // When volume frames are too slow to orbit with (software rasterizers), show the points
        // while the camera moves and the volume again once it settles.
        if self.settings.view == ViewKind::Volume && !moving {
            let dt = ui.ctx().input(|i| i.unstable_dt) * 1000.0;
            self.volume_rest_ms = if self.volume_rest_ms == 0.0 {
                dt
            } else {
                self.volume_rest_ms * 0.8 + dt * 0.2
            };
        }
        self.settings.points_while_moving = self.volume_rest_ms > VOLUME_PROXY_MS;
        if moving {
            ui.ctx().request_repaint();
        } else if self.last_motion.take().is_some() {
            // One more frame at full quality once the camera settles.
            ui.ctx().request_repaint();
        }

        let frame_index = self.frame_index;
        self.frame_index = self.frame_index.wrapping_add(1);
        let active = self.active();
        let world_from_data = active.map_or(glam::Mat4::IDENTITY, |l| l.world_from_data);
        let view = FrameView {
            camera: self.camera,
            world_from_data,
            width,
            height,
            frame_index,
            moving,
        };
        self.last_view = Some(view);
        let hover_px = response
            .hover_pos()
            .map(|p| glam::Vec2::new((p.x - rect.min.x) * ppp, (p.y - rect.min.y) * ppp));
        let song_before = self.hovered_song;
        self.update_hover(hover_px, &view, moving);
        if self.hovered_song != song_before {
            // The side panel, drawn before the view, shows the new song next frame.
            ui.ctx().request_repaint();
        }
        if response.clicked() {
            self.click();
        }
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        let active = self.active();
        let callback = ViewCallback {
            view,
            settings,
            cloud_id: active.map(|l| l.id),
        };
        let painter = ui.painter_at(rect);
        painter.add(egui_wgpu::Callback::new_paint_callback(rect, callback));
        if let Some(loaded) = active {
            if self.settings.show_box {
                labels::paint(&painter, rect, &view, &loaded.labels);
            }
            if let (Some((_, hover)), Some(pos)) = (&self.hover, response.hover_pos()) {
                paint_readings(&painter, rect, pos, &hover.readings);
            }
        } else {
            let text = if self.loading.is_empty() {
                "Drop a loudscape .ply file here, or run: loudscape song.ply [timeline.ply]"
            } else {
                "Loading…"
            };
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                text,
                egui::FontId::proportional(18.0),
                Color32::from_gray(170),
            );
        }
    }
}

impl eframe::App for LoudscapeApp {
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.persist {
            eframe::set_value(storage, eframe::APP_KEY, &self.remembered());
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.frame_ms = self.frame_ms * 0.9 + ctx.input(|i| i.unstable_dt) * 1000.0 * 0.1;
        self.poll_loading(&ctx, frame);
        self.fetch_grid(frame);
        if std::mem::take(&mut self.needs_repaint) {
            ctx.request_repaint();
        }
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        for path in dropped {
            self.start_loading(path);
        }

        egui::Panel::left("controls")
            .resizable(false)
            .exact_size(270.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        self.audio.poll(&ctx);
        let keys_free = !ctx.egui_wants_keyboard_input();
        if keys_free && ctx.input(|i| i.key_pressed(egui::Key::Space)) && self.active == Slot::Song
        {
            self.audio.toggle();
        }
        if ctx.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND, egui::Key::S)) {
            self.save_shot.requested = true;
        }
        if self.active == Slot::Song && self.song.is_some() {
            egui::Panel::bottom("transport").show(ui, |ui| {
                ui.add_space(3.0);
                self.audio.bar(ui);
                ui.add_space(2.0);
            });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.view_3d(ui));
        if std::mem::take(&mut self.save_shot.requested) {
            self.save_screenshot(frame);
        }
        self.remember_audio_choice();
        self.handle_screenshot(&ctx);
    }
}
