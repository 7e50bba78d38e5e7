//! The loudscape window's wiring: `LoudscapeApp`'s state, opening the window, one frame (side
//! panel, transport bar, 3D view) and the camera input of the 3D view. The panels, hover
//! read-outs, data slots, persistence and screenshots each have their own file in `ui/`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32};
use eframe::egui_wgpu;

use crate::render::points::PointStyle;
use crate::render::scene::{RenderSettings, ViewKind};
use crate::render::surface::lod::{SurfaceDetail, detail_for};
use crate::ui::audio::AudioPanel;
use crate::ui::bridge::{ViewCallback, ViewResources};
use crate::ui::hover::paint_readings;
use crate::ui::labels;
use crate::ui::persistence::Remembered;
use crate::ui::shortcuts::{self, Action};
use crate::ui::state::{LoudscapeApp, SaveShot, ScreenshotState, Slot};
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

/// How long after the last input the view still counts as moving (drawn at reduced quality).
const SETTLE: Duration = Duration::from_millis(180);
/// While the camera moves, the Volume and Surface views render at a reduced resolution, chosen
/// so a frame takes about this long (the device's pace measured while moving).
const MOVING_FRAME_MS: f32 = 45.0;
/// How far (in wheel notches) the window's fit steps back from a tight fit of the box, so the
/// labels outside the box stay in view: 0.9^-1 = 11 % farther.
const LABEL_MARGIN_STEPS: f32 = 1.0;
/// The fewest points the Points view draws while moving (fewer no longer show the music's shape).
const MIN_MOVING_POINTS: u32 = 5_000;
/// The most it draws while moving, whatever the device's pace.
const MAX_MOVING_POINTS: u32 = 1 << 30;
/// The coarsest reduction while moving: one pixel in `MAX_MOVING_DIVISOR` per side.
const MAX_MOVING_DIVISOR: u32 = 4;
/// A press shorter than this still counts as a click. egui measures it in frame times, so on a
/// device where one frame takes over a second its default (0.8 s) lost clicks.
const MAX_CLICK_SECONDS: f64 = 4.0;

/// Options from the command line.
#[derive(Clone, Debug, Default)]
pub struct WindowOptions {
    pub files: Vec<PathBuf>,
    /// Save a screenshot of the window here once the data is shown, then close (for tests).
    pub screenshot: Option<PathBuf>,
    /// The view to open in (otherwise the remembered one, or Points).
    pub view: Option<ViewKind>,
    /// Compare the song with this one (B): `loudscape A --compare B`.
    pub compare: Option<PathBuf>,
    /// Start playback at this many seconds once the song's audio is ready.
    pub seek: Option<f64>,
    /// Keys to press once the data is shown (`?`, `Ctrl+S`; for tests: they go through the
    /// same key handling as real keys).
    pub press: Vec<String>,
    /// The "level as heard" preset to show a timeline with (a key of `normalize::PRESETS`).
    pub normalize: Option<&'static str>,
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
    // Destroyed from outside (the window manager, xdotool windowclose): a close, exit 0.
    let run = crate::ui::window_gone::run_until_window_gone(|| {
        eframe::run_native(
            "loudscape",
            native,
            Box::new(move |cc| {
                let render_state = cc
                    .wgpu_render_state
                    .as_ref()
                    .ok_or("no GPU render state: loudscape needs wgpu (Vulkan, Metal or DX12)")?;
                crate::render::gpu::context::check_limits(&render_state.device.limits())
                    .map_err(|reason| format!("the GPU is too small for loudscape: {reason}"))?;
                ViewResources::install(render_state);
                cc.egui_ctx
                    .options_mut(|o| o.input_options.max_click_duration = MAX_CLICK_SECONDS);
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
    });
    match run {
        Some(result) => result.map_err(|e| anyhow::anyhow!("cannot open the window: {e}")),
        None => Ok(()),
    }
}

impl LoudscapeApp {
    pub(super) fn new(options: WindowOptions, remembered: Option<Remembered>) -> Self {
        let persist = options.screenshot.is_none();
        let iso_sweep = options
            .screenshot
            .as_ref()
            .and_then(|_| crate::ui::state::iso_sweep::IsoSweep::from_env());
        let mut app = Self {
            song: None,
            timeline: None,
            active: Slot::Song,
            settings: RenderSettings::default(),
            camera: Camera::default(),
            fit_pending: true,
            loading: Vec::new(),
            messages: Default::default(),
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
            view_px: (1, 1),
            audio_for: Vec::new(),
            persist,
            keep_camera_loads: 0,
            surface_error: None,
            surface_empty: false,
            surface_busy: false,
            refining: None,
            iso_sweep,
            camera_fitted: false,
            busy: None,
            busy_shown: false,
            needs_repaint: false,
            moving_divisor: [1; 3],
            moving_points: PointStyle::default().max_points_moving,
            iso_dragging: false,
            surface_pace: Default::default(),
            surface_detail: Default::default(),
            surface_triangles: 0,
            slot_cameras: [None, None],
            renders_seen: (0, 0),
            open: crate::ui::state::open::OpenPanel {
                // A scripted run keeps a recent list only where it is told to.
                recent: crate::ui::recent::RecentFiles::load(
                    (persist || std::env::var_os("LOUDSCAPE_STATE_DIR").is_some())
                        .then(crate::ui::recent::default_store)
                        .flatten(),
                ),
                years: crate::ui::state::timeline_build::YearBook::load(
                    (persist || std::env::var_os("LOUDSCAPE_STATE_DIR").is_some())
                        .then(crate::ui::recent::default_store)
                        .flatten()
                        .map(|recent| recent.with_file_name("years.json")),
                ),
                ..Default::default()
            },
            scripted_presses: options.press,
            heard: crate::ui::normalize::heard_starting(options.normalize),
            deferred_events: Vec::new(),
            video_export: Default::default(),
            freq_axis: Default::default(),
            compare: None,
            pending_seek: options.seek,
            strip: Default::default(),
        };
        let compare = options.compare.clone();
        let files = app.apply_remembered(options.files, remembered);
        if let Some(view) = options.view {
            app.settings.view = view;
        }
        app.start_opening(files);
        if let Some(b) = compare {
            app.compare_with(b);
        }
        app
    }

    /// Frames the active cloud, keeping the viewing direction (F, "Fit").
    fn fit(&mut self) {
        if let Some(loaded) = self.active() {
            let (min, max) = loaded.world_box;
            let aspect = self.view_aspect;
            self.camera.fit(min, max, aspect);
            // Room around the box for the tick labels and axis titles drawn outside it (in a
            // small window a tight fit put them under the side panel).
            self.camera.zoom(-LABEL_MARGIN_STEPS);
            if self.compare.as_ref().is_some_and(|c| c.side_by_side()) {
                // Each half is narrow: one step more for the level axis's title.
                self.camera.zoom(-1.0);
            }
        }
    }

    /// The default viewing direction, fitted to the active cloud (R, "Reset view").
    pub(super) fn reset_view(&mut self) {
        self.camera = Camera::default();
        self.fit();
        self.camera_fitted = true;
    }

    /// Makes `slot` the active one. Each data mode keeps its own camera: the one left behind is
    /// remembered, the one switched to comes back as it was (or is fitted the first time).
    pub(super) fn switch_slot(&mut self, slot: Slot) {
        if self.active == slot {
            return;
        }
        // A camera still waiting for its first fit is not worth keeping.
        self.slot_cameras[self.active as usize] = (!self.fit_pending).then_some(self.camera);
        self.active = slot;
        self.hover = None;
        match self.slot_cameras[slot as usize] {
            Some(camera) => {
                self.camera = camera;
                self.fit_pending = false;
            }
            None => {
                self.camera = Camera::default();
                self.fit_pending = true;
            }
        }
    }

    fn view_3d(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        // Side by side, each half is a view of its own (one camera for both).
        let view_width = match &self.compare {
            Some(c) if c.side_by_side() && self.active == Slot::Song => {
                (rect.width() - crate::ui::compare_window::GAP) / 2.0
            }
            _ => rect.width(),
        };
        let width = (view_width * ppp).round().max(1.0) as u32;
        let height = (rect.height() * ppp).round().max(1.0) as u32;
        self.view_px = ((rect.width() * ppp).round().max(1.0) as u32, height);
        let aspect = width as f32 / height as f32;
        if (aspect - self.view_aspect).abs() > 1e-3 && self.camera_fitted {
            // The window was resized and the camera not moved by hand since it was fitted:
            // fit again so the data stays in view (an 800x600 window cut the labels off).
            self.fit_pending = true;
        }
        self.view_aspect = aspect;
        if self.fit_pending && self.active().is_some() {
            self.fit();
            self.fit_pending = false;
            self.camera_fitted = true;
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
        let mut fitted_now = false;
        if shortcuts::pressed(ui.ctx(), Action::Fit) {
            self.fit();
            (moved, fitted_now) = (true, true);
        }
        if shortcuts::pressed(ui.ctx(), Action::ResetView) {
            self.reset_view();
            (moved, fitted_now) = (true, true);
        }
        let now = Instant::now();
        if moved {
            self.last_motion = Some(now);
            self.camera_fitted = fitted_now;
        }
        let moving = self.last_motion.is_some_and(|t| now - t < SETTLE);
        // The volume and the surface are drawn while moving too, at a resolution the device can
        // keep up with: the divisor follows the pace of the frames while moving.
        let kind = self.settings.view as usize;
        // The points view draws a subset while moving, as many points as the pace allows.
        if moving {
            let busy = ui.ctx().requested_repaint_last_pass();
            let dt = ui.ctx().input(|i| i.unstable_dt) * 1000.0;
            if self.settings.view == ViewKind::Points {
                self.moving_points = next_moving_points(self.moving_points, busy.then_some(dt));
            } else {
                self.moving_divisor[kind] =
                    next_moving_divisor(self.moving_divisor[kind], busy.then_some(dt));
            }
        }
        // Level of detail: the coarse surface stands in while moving or dragging the isovalue
        // when frames of the full one are too slow (render::surface::lod).
        if self.settings.view == ViewKind::Surface {
            if moving || self.iso_dragging {
                let busy = ui.ctx().requested_repaint_last_pass();
                let dt = ui.ctx().input(|i| i.unstable_dt) * 1000.0;
                self.surface_pace.observe(
                    busy.then_some(dt),
                    self.surface_detail == SurfaceDetail::Full,
                    self.surface_triangles,
                );
            }
            self.surface_detail = detail_for(
                self.surface_pace.full_too_slow(),
                moving,
                self.iso_dragging,
                self.surface_busy,
            );
        }
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
        let compare_shown = self.compare.as_ref().is_some_and(|c| c.shown());
        if response.clicked() && !compare_shown {
            self.click();
        }
        if response.clicked() || response.secondary_clicked() {
            // What the click changed (the seek position, the selected song) shows at once.
            ui.ctx().request_repaint();
        }
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        if self.settings.view == ViewKind::Points {
            settings.points.max_points_moving = self.moving_points;
        }
        if self.settings.view == ViewKind::Surface {
            settings.surface_detail = self.surface_detail;
        }
        let mut render_view = view;
        if moving && self.settings.view != ViewKind::Points {
            let divisor = self.moving_divisor[kind].max(1);
            render_view.width = width.div_ceil(divisor).max(1);
            render_view.height = height.div_ceil(divisor).max(1);
        }
        let painter = ui.painter_at(rect);
        let hover_pos = response.hover_pos();
        if self.paint_compare(&painter, rect, &view, &render_view, &settings, hover_pos) {
            return;
        }
        let active = self.active();
        let callback = ViewCallback {
            view: render_view,
            settings,
            cloud_id: active.map(|l| l.id),
        };
        painter.add(egui_wgpu::Callback::new_paint_callback(rect, callback));
        if let Some(loaded) = active {
            if self.settings.show_box {
                let background = self.settings.colours.background;
                labels::paint_on(&painter, rect, &view, &loaded.labels, background);
            }
            // The same legend as saved pictures carry (name, colour key).
            let legend = crate::ui::legends::picture_legend(&loaded.cloud, &self.settings);
            crate::ui::legends::paint_picture(&painter, rect, &legend);
            // While the camera moves the read-out would describe where the cursor was.
            if let (Some((_, hover)), Some(pos), false) =
                (&self.hover, response.hover_pos(), moving)
            {
                paint_readings(&painter, rect, pos, &hover.readings);
            }
            if self.settings.view == ViewKind::Surface && self.surface_empty && !self.surface_busy {
                // In the view, not only under the slider, whose tooltip covered it.
                painter.text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    format!(
                        "no surface at isovalue {:.2}: the density crosses it nowhere; lower it",
                        self.settings.surface.iso_value
                    ),
                    egui::FontId::proportional(16.0),
                    crate::ui::style::WARNING,
                );
            }
            if self.surface_busy {
                busy_badge(&painter, rect, "extracting surface…");
            } else if let Some(done) = self.refining {
                let percent = (done * 100.0).floor();
                busy_badge(&painter, rect, &format!("refining points… {percent:.0} %"));
            }
        } else {
            let text = if self.loading.is_empty() {
                "Drop a song or a loudscape .ply file here, or run: loudscape song.ogg [timeline.ply]"
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
    /// The frame is cleared to the panels' colour, which the panels then leave unpainted
    /// ([`crate::ui::style::panel_frame`]).
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        visuals.panel_fill.to_normalized_gamma_f32()
    }

    fn raw_input_hook(&mut self, ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        // Events held back after a Tab last frame come first (`shortcuts::split_after_focus_move`).
        if !self.deferred_events.is_empty() {
            let mut events = std::mem::take(&mut self.deferred_events);
            events.append(&mut raw_input.events);
            raw_input.events = events;
        }
        // Scripted presses (tests), once the data is shown (whole, not the points so far of a
        // song being extracted) or nothing is loading. A compare's B loaded first too.
        let compare_ready = self.compare.as_ref().is_none_or(|c| c.receiver.is_none());
        if !self.scripted_presses.is_empty()
            && ((self.active().is_some() && !self.previewing()) || self.loading.is_empty())
            && self.scripted_input_ready()
            && compare_ready
        {
            for name in std::mem::take(&mut self.scripted_presses) {
                if self.scripted_setting(&name)
                    || self.scripted_compare(&name)
                    || self.scripted_shot_size(&name)
                    || self.scripted_video_export(&name)
                {
                    continue;
                }
                match shortcuts::key_event(&name) {
                    Some(event) => raw_input.events.push(event),
                    None => self.messages.error(format!("--press {name}: no such key")),
                }
            }
        }
        self.deferred_events = shortcuts::split_after_focus_move(&mut raw_input.events);
        if !self.deferred_events.is_empty() {
            ctx.request_repaint();
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.persist {
            eframe::set_value(storage, eframe::APP_KEY, &self.remembered());
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        // A frame's time counts only when it followed the last one at once (a repaint was asked
        // for), so time spent waiting for input is not shown as frame time.
        if ctx.requested_repaint_last_pass() {
            let dt = ctx.input(|i| i.unstable_dt) * 1000.0;
            self.frame_ms = if self.frame_ms == 0.0 {
                dt
            } else {
                self.frame_ms * 0.8 + dt * 0.2
            };
        }
        let before = self.shown_state();
        self.poll_loading(&ctx, frame);
        self.apply_heard(frame);
        self.apply_freq_axis(frame);
        self.poll_compare(&ctx, frame);
        self.poll_video_export(&ctx);
        self.fetch_grid(frame);
        let surface_status = frame
            .wgpu_render_state()
            .zip(self.active().map(|l| l.id))
            .map(|(render_state, id)| ViewResources::surface_status(render_state, id));
        self.surface_busy = self.settings.view == ViewKind::Surface
            && surface_status.as_ref().is_some_and(|status| status.2);
        self.surface_triangles = surface_status
            .and_then(|status| status.0)
            .map_or(0, |counts| counts.triangles());
        // Set again by the isovalue slider (or a scripted sweep) while it is dragged.
        self.iso_dragging = false;
        if self.surface_busy {
            // Come back for the finished surface; the frames in between only composite.
            ctx.request_repaint_after(Duration::from_millis(30));
        }
        self.refining = frame
            .wgpu_render_state()
            .and_then(|render_state| ViewResources::refining(render_state, &ctx));
        if self.refining.is_some() {
            // The next slice of the points (ui/progressive.rs).
            ctx.request_repaint();
        }
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
        // A drop with Shift held is B of an A/B compare.
        let shift = ctx.input(|i| i.modifiers.shift);
        if shift && self.song.is_some() {
            for path in dropped {
                self.compare_with(path);
            }
        } else if !dropped.is_empty() {
            self.start_opening(dropped);
        }

        let panel_width = side_panel_width(ctx.content_rect().width());
        egui::Panel::left("controls")
            .frame(crate::ui::style::panel_frame(ui.style()))
            .resizable(false)
            .exact_size(panel_width)
            .show(ui, |ui| {
                // Narrower than its rows in a small window: they scroll sideways too.
                let scroll = if panel_width < SIDE_PANEL_WIDTH {
                    egui::ScrollArea::both()
                } else {
                    egui::ScrollArea::vertical()
                };
                scroll.show(ui, |ui| self.controls(ui));
            });
        self.audio.poll(&ctx);
        self.compare_keys(&ctx);
        if self.active == Slot::Song && shortcuts::pressed(&ctx, Action::PlayPause) {
            self.audio.toggle();
        }
        if shortcuts::pressed(&ctx, Action::SavePng) {
            self.save_shot.requested = true;
        }
        if shortcuts::pressed(&ctx, Action::Reextract) {
            self.reextract_shown_song();
        }
        if shortcuts::pressed(&ctx, Action::Open) {
            self.open_dialog_or_say_why(false);
        }
        self.shortcuts_overlay(&ctx);
        if self.active == Slot::Song && self.song.is_some() {
            egui::Panel::bottom("transport")
                .frame(crate::ui::style::panel_frame(ui.style()))
                .show(ui, |ui| {
                    ui.add_space(3.0);
                    self.audio.bar(ui);
                    ui.add_space(2.0);
                });
            if let Some(song) = &self.song {
                self.strip.sync(song.id, &song.cloud);
            }
            if self.strip.has_curves() {
                let (strip, audio) = (&self.strip, &mut self.audio);
                egui::Panel::bottom("loudness_strip")
                    .frame(crate::ui::style::panel_frame(ui.style()))
                    .show(ui, |ui| {
                        if let Some(t) = strip.show(ui, audio.time_s().unwrap_or(0.0)) {
                            audio.seek(t);
                        }
                    });
            }
        }
        // Under the 3D view, above the transport bar: what the app is telling the user.
        self.status_area(ui);
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.view_3d(ui));
        if std::mem::take(&mut self.save_shot.requested) {
            self.save_screenshot(frame);
        }
        self.remember_audio_choice();
        if self.step_iso_sweep(frame) {
            self.handle_screenshot(&ctx);
        } else {
            ctx.request_repaint();
        }
        if self.shown_state() != before {
            // A control changed what the panels or the view show: draw it now, not at the next
            // mouse move (the panels were drawn before the change).
            ctx.request_repaint();
        }
        if let Some(render_state) = frame.wgpu_render_state() {
            let renders = ViewResources::renders(render_state);
            if renders != self.renders_seen.0 {
                self.renders_seen = (renders, self.frame_index);
            }
        }
    }
}

impl LoudscapeApp {
    /// What a frame shows that a control can change, to ask for a repaint when it did.
    fn shown_state(&self) -> (RenderSettings, Slot, Option<usize>, bool, Camera) {
        (
            self.settings.clone(),
            self.active,
            self.selected_song,
            self.fit_pending,
            self.camera,
        )
    }
}

/// A spinner and `text` in the top-left corner of the 3D view, over a dark plate.
fn busy_badge(painter: &egui::Painter, rect: egui::Rect, text: &str) {
    let font = egui::FontId::proportional(14.0);
    let galley = painter.layout_no_wrap(text.into(), font, Color32::from_gray(220));
    let origin = rect.min + egui::vec2(12.0, 10.0);
    let spinner = 14.0;
    let plate = egui::Rect::from_min_size(
        origin,
        egui::vec2(
            spinner + 8.0 + galley.size().x,
            galley.size().y.max(spinner),
        ),
    )
    .expand(5.0);
    painter.rect_filled(plate, 4.0, labels::LABEL_PLATE);
    // The spinner: an arc turning with time (egui's Spinner needs a Ui of its own).
    let time = painter.ctx().input(|i| i.time);
    let centre = origin + egui::vec2(spinner * 0.5, plate.height() * 0.5 - 5.0);
    let start = time * 4.0;
    let points: Vec<egui::Pos2> = (0..=20)
        .map(|i| {
            let angle = start + f64::from(i) / 20.0 * std::f64::consts::PI * 1.5;
            centre + spinner * 0.45 * egui::vec2(angle.cos() as f32, angle.sin() as f32)
        })
        .collect();
    painter.add(egui::Shape::line(
        points,
        egui::Stroke::new(2.0, Color32::from_rgb(230, 190, 110)),
    ));
    painter.galley(
        origin
            + egui::vec2(
                spinner + 8.0,
                (plate.height() - 10.0 - galley.size().y) * 0.5,
            ),
        galley,
        Color32::from_gray(220),
    );
}

/// The side panel's width in a window wide enough.
const SIDE_PANEL_WIDTH: f32 = 270.0;

/// The side panel's width in a window `window_width` points wide: [`SIDE_PANEL_WIDTH`], but at
/// most 40 % of a small window (at 500 points it took more than half), never under 180.
pub(super) fn side_panel_width(window_width: f32) -> f32 {
    (window_width * 0.4).clamp(180.0, SIDE_PANEL_WIDTH)
}

/// The divisor of the moving resolution after a frame that took `frame_ms` (None: the frame
/// did not follow the last at once, so its time says nothing about the device): one step
/// coarser when frames are slower than [`MOVING_FRAME_MS`], one finer when well under it.
pub(super) fn next_moving_divisor(divisor: u32, frame_ms: Option<f32>) -> u32 {
    match frame_ms {
        Some(ms) if ms > MOVING_FRAME_MS => (divisor + 1).min(MAX_MOVING_DIVISOR),
        Some(ms) if ms < MOVING_FRAME_MS * 0.4 => divisor.saturating_sub(1).max(1),
        _ => divisor.max(1),
    }
}

/// The points drawn while moving after a frame that took `frame_ms` (None: says nothing about
/// the device): fewer when frames are slower than [`MOVING_FRAME_MS`], more when well under it,
/// never below [`MIN_MOVING_POINTS`]. On a fast device it grows past any cloud's size, so every
/// point is drawn while moving too.
pub(super) fn next_moving_points(points: u32, frame_ms: Option<f32>) -> u32 {
    let next = match frame_ms {
        Some(ms) if ms > MOVING_FRAME_MS => points as f32 * 0.75,
        Some(ms) if ms < MOVING_FRAME_MS * 0.6 => points as f32 * 1.25,
        _ => points as f32,
    };
    (next as u32).clamp(MIN_MOVING_POINTS, MAX_MOVING_POINTS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_points_follow_the_pace_and_stay_in_range() {
        let mut n = PointStyle::default().max_points_moving;
        for _ in 0..40 {
            n = next_moving_points(n, Some(400.0));
        }
        assert_eq!(
            n, MIN_MOVING_POINTS,
            "slow frames shrink the subset to the floor"
        );
        assert_eq!(next_moving_points(n, None), n, "idle frames say nothing");
        assert_eq!(next_moving_points(n, Some(MOVING_FRAME_MS * 0.8)), n);
        let mut grown = n;
        for _ in 0..5 {
            grown = next_moving_points(grown, Some(5.0));
        }
        assert!(grown > 2 * n, "fast frames grow it: {n} -> {grown}");
        for _ in 0..200 {
            grown = next_moving_points(grown, Some(5.0));
        }
        assert_eq!(grown, MAX_MOVING_POINTS);
    }

    #[test]
    fn the_side_panel_leaves_a_small_window_to_the_view() {
        assert_eq!(side_panel_width(1280.0), SIDE_PANEL_WIDTH);
        assert!(
            side_panel_width(500.0) <= 200.0,
            "{}",
            side_panel_width(500.0)
        );
        assert_eq!(side_panel_width(300.0), 180.0);
    }

    #[test]
    fn moving_divisor_follows_the_pace_and_stays_in_range() {
        let mut d = 1;
        for _ in 0..10 {
            d = next_moving_divisor(d, Some(400.0));
        }
        assert_eq!(d, MAX_MOVING_DIVISOR);
        assert_eq!(next_moving_divisor(d, None), d, "idle frames say nothing");
        assert_eq!(next_moving_divisor(d, Some(MOVING_FRAME_MS * 0.8)), d);
        for _ in 0..10 {
            d = next_moving_divisor(d, Some(5.0));
        }
        assert_eq!(d, 1);
    }
}
