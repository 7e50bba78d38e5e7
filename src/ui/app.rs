//! The loudscape window: a side panel of controls and the 3D view.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32, RichText};
use eframe::egui_wgpu;

use crate::camera::Camera;
use crate::cloud::{DataMode, PointCloud};
use crate::overlay;
use crate::pick::{self, CpuGrid, Reading};
use crate::render::frame::FrameView;
use crate::render::markers::MarkerBox;
use crate::render::scene::{RenderSettings, ViewKind, world_from_data};
use crate::ui::audio::AudioPanel;
use crate::ui::bridge::{ViewCallback, ViewResources};

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

/// Which of the two data slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Song,
    Timeline,
}

impl Slot {
    fn for_mode(mode: DataMode) -> Self {
        match mode {
            DataMode::Timeline => Slot::Timeline,
            DataMode::Song | DataMode::Generic => Slot::Song,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Slot::Song => "Song",
            Slot::Timeline => "Timeline",
        }
    }
}

struct Loaded {
    id: u64,
    /// Point size for this cloud (sparse timelines want larger discs than dense songs).
    point_size: f32,
    cloud: Arc<PointCloud>,
    labels: overlay::AxisLabels,
    world_from_data: glam::Mat4,
    world_box: (glam::Vec3, glam::Vec3),
    /// The voxel grid read back once for hover picking in the Surface and Volume views.
    cpu_grid: Option<CpuGrid>,
}

/// What is under the cursor, recomputed only when the cursor or the view changed.
#[derive(Clone, Debug, PartialEq)]
struct HoverKey {
    px: glam::Vec2,
    camera: Camera,
    size: (u32, u32),
    view: ViewKind,
    cloud_id: u64,
    min_scalar: f32,
}

#[derive(Clone, Debug, Default)]
struct Hover {
    readings: Vec<Reading>,
    /// Normalized x under the cursor (on the data, or where the ray enters the box).
    x: Option<f32>,
}

/// What the app remembers between runs.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Remembered {
    pub files: Vec<PathBuf>,
    pub view: Option<ViewKind>,
    pub camera: Option<Camera>,
    pub iso_value: Option<f32>,
    pub show_box: Option<bool>,
    /// Transfer function preset name (Classic, Ember, Glacial) and the volume's hp tint.
    #[serde(default)]
    pub transfer: Option<String>,
    #[serde(default)]
    pub hp_tint: Option<bool>,
    /// Surface method short name (mt, dc).
    #[serde(default)]
    pub surface_method: Option<String>,
    /// Audio picked by hand for a cloud whose recorded source moved: cloud path -> audio path.
    pub audio_for: Vec<(PathBuf, PathBuf)>,
}

struct Loading {
    path: PathBuf,
    receiver: Receiver<Result<PointCloud, String>>,
}

struct ScreenshotState {
    path: PathBuf,
    frames_shown: u32,
    requested: bool,
    done: Arc<AtomicBool>,
}

pub struct LoudscapeApp {
    song: Option<Loaded>,
    timeline: Option<Loaded>,
    active: Slot,
    settings: RenderSettings,
    camera: Camera,
    fit_pending: bool,
    loading: Vec<Loading>,
    messages: Vec<String>,
    next_id: u64,
    last_motion: Option<Instant>,
    frame_index: u32,
    frame_ms: f32,
    view_aspect: f32,
    screenshot: Option<ScreenshotState>,
    audio: AudioPanel,
    hover: Option<(HoverKey, Hover)>,
    hovered_song: Option<usize>,
    selected_song: Option<usize>,
    /// Screenshot path; empty saves `loudscape-<time>.png` in the current directory.
    shot_path: String,
    shot_custom_size: bool,
    shot_size: [u32; 2],
    shot_requested: bool,
    last_view: Option<FrameView>,
    audio_for: Vec<(PathBuf, PathBuf)>,
    /// Whether to remember state (off for scripted screenshot runs).
    persist: bool,
    /// Loads that keep the remembered camera instead of fitting.
    keep_camera_loads: usize,
    /// Why the surface could not be extracted, if it could not.
    surface_error: Option<String>,
    /// Draw again next frame (the surface is still growing its buffers).
    needs_repaint: bool,
    /// Smoothed time of a volume frame at rest (ms), to decide whether orbiting needs a stand-in.
    volume_rest_ms: f32,
}

/// Opens the window and runs until it closes.
pub fn run(options: WindowOptions) -> anyhow::Result<()> {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(crate::render::context::device_descriptor);
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
            shot_path: String::new(),
            shot_custom_size: false,
            shot_size: [1920, 1080],
            shot_requested: false,
            last_view: None,
            audio_for: Vec::new(),
            persist,
            keep_camera_loads: 0,
            surface_error: None,
            needs_repaint: false,
            volume_rest_ms: 0.0,
        };
        let mut files = options.files;
        if let Some(r) = remembered {
            if let Some(view) = r.view.filter(|v| v.available()) {
                app.settings.view = view;
            }
            if let Some(iso) = r.iso_value {
                app.settings.surface.iso_value = iso.clamp(0.0, 1.0);
            }
            if let Some(show) = r.show_box {
                app.settings.show_box = show;
            }
            if let Some(preset) = r
                .transfer
                .as_deref()
                .and_then(crate::render::transfer::TransferPreset::parse)
            {
                app.settings.volume.preset = preset;
            }
            if let Some(tint) = r.hp_tint {
                app.settings.volume.hp_tint = tint;
            }
            if let Some(method) = r
                .surface_method
                .as_deref()
                .and_then(crate::render::mesh::SurfaceMethod::parse)
            {
                app.settings.surface.method = method;
            }
            app.audio_for = r.audio_for;
            // The camera and the files go together: the view comes back as it was left.
            if files.is_empty() {
                files = r.files.into_iter().filter(|f| f.is_file()).collect();
                if let Some(camera) = r.camera
                    && !files.is_empty()
                {
                    app.camera = camera;
                    app.fit_pending = false;
                    app.keep_camera_loads = files.len();
                }
            }
        }
        if let Some(view) = options.view {
            app.settings.view = view;
        }
        for file in files {
            app.start_loading(file);
        }
        app
    }

    fn remembered(&self) -> Remembered {
        let files = [self.song.as_ref(), self.timeline.as_ref()]
            .into_iter()
            .flatten()
            .map(|l| std::path::absolute(&l.cloud.path).unwrap_or_else(|_| l.cloud.path.clone()))
            .collect();
        Remembered {
            files,
            view: Some(self.settings.view),
            camera: Some(self.camera),
            iso_value: Some(self.settings.surface.iso_value),
            show_box: Some(self.settings.show_box),
            transfer: Some(self.settings.volume.preset.name().to_string()),
            hp_tint: Some(self.settings.volume.hp_tint),
            surface_method: Some(self.settings.surface.method.short_name().to_string()),
            audio_for: self.audio_for.clone(),
        }
    }

    fn start_loading(&mut self, path: PathBuf) {
        let (sender, receiver) = channel();
        let thread_path = path.clone();
        std::thread::spawn(move || {
            let result = crate::cloud::load(&thread_path).map_err(|e| e.to_string());
            let _ = sender.send(result);
        });
        self.loading.push(Loading { path, receiver });
    }

    fn slot(&self, slot: Slot) -> Option<&Loaded> {
        match slot {
            Slot::Song => self.song.as_ref(),
            Slot::Timeline => self.timeline.as_ref(),
        }
    }

    fn active(&self) -> Option<&Loaded> {
        self.slot(self.active)
    }

    /// Moves finished loads into their slots and uploads them.
    fn poll_loading(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let mut finished = Vec::new();
        self.loading
            .retain(|loading| match loading.receiver.try_recv() {
                Ok(result) => {
                    finished.push((loading.path.clone(), result));
                    false
                }
                Err(std::sync::mpsc::TryRecvError::Empty) => true,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    finished.push((loading.path.clone(), Err("the loader stopped".into())));
                    false
                }
            });
        if !self.loading.is_empty() {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        for (path, result) in finished {
            match result {
                Ok(cloud) => self.install(render_state, cloud),
                Err(message) => {
                    log::error!("{message}");
                    self.messages.push(format!("{}: {message}", path.display()));
                    if message.contains(&path.display().to_string()) {
                        self.messages.pop();
                        self.messages.push(message);
                    }
                }
            }
        }
    }

    fn install(&mut self, render_state: &egui_wgpu::RenderState, cloud: PointCloud) {
        let slot = Slot::for_mode(cloud.meta.mode);
        let id = self.next_id;
        self.next_id += 1;
        if let Some(old) = self.slot(slot) {
            ViewResources::remove(render_state, old.id);
        }
        ViewResources::upload(render_state, id, &cloud);
        let (box_min, box_max) = crate::render::scene::data_box(&cloud);
        let world_from_data = world_from_data(cloud.meta.mode);
        let labels = overlay::axis_labels_for_box(&cloud, box_min, box_max);
        let loaded = Loaded {
            id,
            point_size: crate::render::points::PointStyle::size_for(cloud.points.len()),
            cloud: Arc::new(cloud),
            labels,
            world_from_data,
            world_box: crate::render::scene::world_box(world_from_data, box_min, box_max),
            cpu_grid: None,
        };
        if slot == Slot::Song {
            let remembered = self
                .audio_for
                .iter()
                .find(|(cloud, _)| {
                    std::path::absolute(&loaded.cloud.path).is_ok_and(|p| &p == cloud)
                })
                .map(|(_, audio)| audio.clone());
            self.audio.load_for(&loaded.cloud, remembered);
        } else {
            self.selected_song = None;
            self.hovered_song = None;
        }
        self.hover = None;
        match slot {
            Slot::Song => self.song = Some(loaded),
            Slot::Timeline => self.timeline = Some(loaded),
        }
        self.active = slot;
        if self.keep_camera_loads > 0 {
            self.keep_camera_loads -= 1;
        } else {
            self.fit_pending = true;
        }
    }

    fn fit(&mut self) {
        if let Some(loaded) = self.active() {
            let (min, max) = loaded.world_box;
            let aspect = self.view_aspect;
            self.camera.fit(min, max, aspect);
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("loudscape");
        ui.add_space(4.0);

        ui.label(RichText::new("Data").strong());
        ui.horizontal(|ui| {
            for slot in [Slot::Song, Slot::Timeline] {
                let present = self.slot(slot).is_some();
                let response = ui.add_enabled(
                    present,
                    egui::Button::selectable(self.active == slot, slot.name()),
                );
                let response = if present {
                    response
                } else {
                    response.on_disabled_hover_text(format!(
                        "No {} cloud loaded: open one with `loudscape song.ply timeline.ply` or drop a .ply here",
                        slot.name().to_lowercase()
                    ))
                };
                if response.clicked() && self.active != slot {
                    self.active = slot;
                    self.fit_pending = true;
                }
            }
        });

        ui.add_space(6.0);
        ui.label(RichText::new("View").strong());
        ui.horizontal(|ui| {
            for view in ViewKind::ALL {
                let response = ui.add_enabled(
                    view.available(),
                    egui::Button::selectable(self.settings.view == view, view.name()),
                );
                let response = response.on_disabled_hover_text(format!(
                    "The {} view is not yet available",
                    view.name()
                ));
                if response.clicked() {
                    self.settings.view = view;
                }
            }
        });

        if self.settings.view == ViewKind::Points {
            ui.add_space(6.0);
            ui.label(RichText::new("Points").strong());
            if let Some(size) = self.active().map(|l| l.point_size) {
                self.settings.points.size_px = size;
            }
            let size_changed = ui
                .add(
                    egui::Slider::new(&mut self.settings.points.size_px, 1.0..=12.0)
                        .text("size (px)"),
                )
                .changed();
            if size_changed {
                let size = self.settings.points.size_px;
                match self.active {
                    Slot::Song => self.song.iter_mut().for_each(|l| l.point_size = size),
                    Slot::Timeline => self.timeline.iter_mut().for_each(|l| l.point_size = size),
                }
            }
            ui.add(
                egui::Slider::new(&mut self.settings.points.min_scalar, 0.0..=1.0)
                    .text("min loudness"),
            );
            hp_legend(ui);
        }
        if self.settings.view != ViewKind::Points {
            self.grid_controls(ui);
        }
        if self.settings.view == ViewKind::Volume {
            self.volume_controls(ui);
        }
        if self.settings.view == ViewKind::Surface {
            self.surface_controls(ui);
            ui.label(RichText::new("Surface colour (mean hp)").small());
            gradient_legend(ui, |t| {
                crate::render::mesh::warm_cool(t).map(|c| (c * 255.0).round() as u8)
            });
            ui.horizontal(|ui| {
                ui.label(RichText::new("percussive").small());
                ui.add_space(60.0);
                ui.label(RichText::new("harmonic").small());
            });
        }

        ui.add_space(6.0);
        ui.label(RichText::new("Camera").strong());
        ui.horizontal(|ui| {
            if ui.button("Fit (F)").clicked() {
                self.fit_pending = true;
            }
            ui.checkbox(&mut self.settings.show_box, "axes");
        });
        ui.label(
            RichText::new("Left drag: orbit · right/middle drag: pan · wheel: zoom")
                .small()
                .weak(),
        );

        ui.add_space(6.0);
        self.screenshot_controls(ui);

        if self.active == Slot::Timeline {
            self.timeline_song(ui);
        }

        if let Some(loaded) = self.active() {
            ui.add_space(8.0);
            ui.separator();
            cloud_info(ui, &loaded.cloud);
        }

        for loading in &self.loading {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("loading {}", loading.path.display()));
            });
        }
        if !self.messages.is_empty() {
            ui.separator();
            let mut dismiss = false;
            for message in &self.messages {
                ui.colored_label(Color32::from_rgb(240, 120, 100), message);
            }
            if ui.small_button("dismiss").clicked() {
                dismiss = true;
            }
            if dismiss {
                self.messages.clear();
            }
        }

        ui.with_layout(egui::Layout::bottom_up(egui::Align::LEFT), |ui| {
            ui.label(
                RichText::new(format!("{:.1} ms/frame", self.frame_ms))
                    .small()
                    .weak(),
            );
        });
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
                overlay::paint(&painter, rect, &view, &loaded.labels);
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

    fn handle_screenshot(&mut self, ctx: &egui::Context) {
        let has_data = self.active().is_some();
        let Some(state) = self.screenshot.as_mut() else {
            return;
        };
        if state.done.load(Ordering::SeqCst) {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        if !has_data && self.loading.is_empty() && self.messages.is_empty() {
            // Nothing to wait for: take the empty window.
        } else if !has_data {
            if !self.messages.is_empty() {
                // Loading failed; still take the picture so the test sees the message.
            } else {
                ctx.request_repaint();
                return;
            }
        }
        state.frames_shown += 1;
        if state.frames_shown >= 3 && !state.requested {
            state.requested = true;
            let path = state.path.clone();
            let done = state.done.clone();
            let repaint = ctx.clone();
            ctx.request_screenshot(move |image| {
                if let Err(e) = save_color_image(&image, &path) {
                    eprintln!("loudscape: error: {}: {e}", path.display());
                }
                done.store(true, Ordering::SeqCst);
                repaint.request_repaint();
            });
        }
        ctx.request_repaint();
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
            self.shot_requested = true;
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
        if std::mem::take(&mut self.shot_requested) {
            self.save_screenshot(frame);
        }
        if let Some(track) = self.audio.track_path()
            && let Some(song) = &self.song
        {
            let cloud = std::path::absolute(&song.cloud.path).unwrap_or_default();
            let track = std::path::absolute(&track).unwrap_or(track);
            let recorded = crate::playback::resolve_source(&song.cloud)
                .ok()
                .and_then(|p| std::path::absolute(p).ok());
            let entry = self.audio_for.iter().position(|(c, _)| c == &cloud);
            match (entry, recorded.as_ref() == Some(&track)) {
                (Some(i), true) => {
                    self.audio_for.remove(i);
                }
                (Some(i), false) => self.audio_for[i].1 = track,
                (None, false) => self.audio_for.push((cloud, track)),
                (None, true) => {}
            }
        }
        self.handle_screenshot(&ctx);
    }
}

/// The hp palette as a strip with its two ends named.
fn hp_legend(ui: &mut egui::Ui) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(200.0, 12.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let steps = 50;
    for i in 0..steps {
        let t = i as f32 / (steps - 1) as f32;
        let [r, g, b] = crate::render::palette::hp_color_u8(t);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, rect.y_range()),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
    ui.horizontal(|ui| {
        ui.label(RichText::new("percussive").small());
        ui.add_space(60.0);
        ui.label(RichText::new("harmonic (hp)").small());
    });
}

/// What the file says about itself: source, size and loudness metrics.
fn cloud_info(ui: &mut egui::Ui, cloud: &PointCloud) {
    let name = cloud
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    ui.label(RichText::new(name).strong());
    ui.label(format!(
        "{} points",
        group_thousands(cloud.points.len() as u64)
    ));
    for line in crate::overlay::describe_cloud(cloud) {
        ui.label(RichText::new(line).small());
    }
}

fn group_thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

fn save_color_image(image: &egui::ColorImage, path: &Path) -> anyhow::Result<()> {
    let [w, h] = image.size;
    let mut rgba = Vec::with_capacity(w * h * 4);
    for pixel in &image.pixels {
        rgba.extend_from_slice(&pixel.to_array());
    }
    let img = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
        .ok_or_else(|| anyhow::anyhow!("screenshot has the wrong size"))?;
    Ok(crate::screenshot::save_png(&img, path)?)
}

impl LoudscapeApp {
    /// The playhead plane, the loop range and the hovered or selected timeline song.
    fn markers(&self) -> Vec<MarkerBox> {
        let mut markers = Vec::new();
        let Some(loaded) = self.active() else {
            return markers;
        };
        let axis = &loaded.cloud.meta.axes.x;
        match self.active {
            Slot::Song => {
                if let Some((a, b)) = self.audio.loop_shown() {
                    markers.push(MarkerBox::x_span(
                        crate::playback::time_to_x(axis, a),
                        crate::playback::time_to_x(axis, b),
                        [0.95, 0.8, 0.3, 0.06],
                        [0.95, 0.8, 0.3, 0.5],
                    ));
                }
                if let Some(t) = self.audio.time_s() {
                    markers.push(MarkerBox::playhead(crate::playback::time_to_x(axis, t)));
                }
            }
            Slot::Timeline => {
                let songs = &loaded.cloud.meta.songs;
                for (index, alpha) in [(self.selected_song, 0.16), (self.hovered_song, 0.09)] {
                    let Some(song) = index.and_then(|i| songs.get(i)) else {
                        continue;
                    };
                    if let (Some(a), Some(b)) = (song.x_min, song.x_max) {
                        markers.push(MarkerBox::x_span(
                            a as f32,
                            b as f32,
                            [1.0, 1.0, 1.0, alpha],
                            [1.0, 1.0, 1.0, 0.7],
                        ));
                    }
                }
            }
        }
        markers
    }

    /// Recomputes what is under the cursor when the cursor or the view changed.
    fn update_hover(&mut self, px: Option<glam::Vec2>, view: &FrameView, moving: bool) {
        let (Some(px), false) = (px, moving) else {
            if px.is_none() {
                self.hover = None;
                self.hovered_song = None;
            }
            return;
        };
        let Some(loaded) = self.active() else {
            self.hover = None;
            return;
        };
        let key = HoverKey {
            px,
            camera: view.camera,
            size: (view.width, view.height),
            view: self.settings.view,
            cloud_id: loaded.id,
            min_scalar: self.settings.points.min_scalar,
        };
        if self.hover.as_ref().is_some_and(|(k, _)| k == &key) {
            return;
        }
        let cloud = loaded.cloud.clone();
        let axes = &cloud.meta.axes;
        let (origin, dir) = pick::cursor_ray(view, px);
        let mut hover = Hover::default();
        match self.settings.view {
            ViewKind::Points => {
                let ppp_radius = 5.0;
                if let Some(i) = pick::pick_point(
                    &cloud.points,
                    view,
                    px,
                    ppp_radius,
                    self.settings.points.min_scalar,
                ) {
                    hover.readings = pick::point_readings(axes, &cloud.points[i]);
                    hover.x = Some(cloud.points[i].position[0]);
                }
            }
            ViewKind::Surface | ViewKind::Volume => {
                let threshold = if self.settings.view == ViewKind::Surface {
                    self.settings.surface.iso_value
                } else {
                    VOLUME_PICK_DENSITY
                };
                if let Some(hit) = loaded
                    .cpu_grid
                    .as_ref()
                    .and_then(|g| g.pick(origin, dir, threshold))
                {
                    hover.readings = pick::voxel_readings(axes, &hit);
                    hover.x = Some(hit.position.x);
                }
            }
        }
        if hover.x.is_none()
            && let Some((t, _)) =
                pick::ray_box(origin, dir, glam::Vec3::splat(-1.0), glam::Vec3::ONE)
        {
            let p = origin + dir * t;
            hover.x = Some(p.x.clamp(-1.0, 1.0));
            let first = pick::position_readings(axes, p);
            hover.readings = first.into_iter().take(1).collect();
        }
        self.hovered_song = match (self.active, hover.x) {
            (Slot::Timeline, Some(x)) => pick::song_at(&cloud.meta.songs, x),
            _ => None,
        };
        if let Some(song) = self.hovered_song.and_then(|i| cloud.meta.songs.get(i)) {
            hover.readings.insert(
                0,
                Reading {
                    name: "song".into(),
                    value: song_title(song),
                },
            );
        }
        self.hover = Some((key, hover));
    }

    /// A click on the data: seek there (Song) or select the song (Timeline).
    fn click(&mut self) {
        let Some(x) = self.hover.as_ref().and_then(|(_, h)| h.x) else {
            return;
        };
        match self.active {
            Slot::Song => {
                if let Some(loaded) = self.song.as_ref() {
                    let t = crate::playback::x_to_time(&loaded.cloud.meta.axes.x, x);
                    self.audio.seek(t);
                }
            }
            Slot::Timeline => self.selected_song = self.hovered_song,
        }
    }

    /// Builds the active cloud's voxel grid when the view needs one (only when the cloud or the
    /// grid settings changed), and reads it back once for hovering.
    fn fetch_grid(&mut self, frame: &eframe::Frame) {
        if self.settings.view == ViewKind::Points {
            return;
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let voxels = self.settings.voxels;
        let slot = match self.active {
            Slot::Song => self.song.as_mut(),
            Slot::Timeline => self.timeline.as_mut(),
        };
        let Some(loaded) = slot else {
            return;
        };
        let mut failure = None;
        match ViewResources::ensure_grid(render_state, loaded.id, &loaded.cloud, &voxels) {
            Ok(true) => loaded.cpu_grid = None,
            Ok(false) => {}
            Err(message) => failure = Some(message),
        }
        if loaded.cpu_grid.is_none() && ViewResources::has_grid(render_state, loaded.id) {
            loaded.cpu_grid = ViewResources::read_grid(render_state, loaded.id);
        }
        if let Some(message) = failure
            && !self.messages.contains(&message)
        {
            self.messages.push(message);
        }
        let (_, error, again) = ViewResources::surface_status(render_state);
        self.surface_error = error;
        if again {
            self.needs_repaint = true;
        }
    }

    fn grid_controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(6.0);
        ui.label(RichText::new("Voxel grid").strong());
        let mode = self.active().map_or(DataMode::Song, |l| l.cloud.meta.mode);
        let mut resolution = self.settings.voxels.resolution_for(mode);
        let changed = ui
            .add(
                egui::Slider::new(
                    &mut resolution,
                    crate::render::voxelize::MIN_RESOLUTION
                        ..=crate::render::voxelize::MAX_RESOLUTION,
                )
                .step_by(16.0)
                .text("voxels/side"),
            )
            .on_hover_text("128 for songs and 224 for timelines by default; rebuilt on release")
            .drag_stopped();
        if changed {
            self.settings.voxels.resolution = Some(resolution);
        }
        let mut sigma = self.settings.voxels.smoothing_sigma;
        if ui
            .add(egui::Slider::new(&mut sigma, 0.0..=3.0).text("smoothing σ"))
            .drag_stopped()
        {
            self.settings.voxels.smoothing_sigma = sigma;
        }
    }

    fn volume_controls(&mut self, ui: &mut egui::Ui) {
        use crate::render::transfer::TransferPreset;
        ui.add_space(6.0);
        ui.label(RichText::new("Volume").strong());
        let volume = &mut self.settings.volume;
        ui.horizontal(|ui| {
            for preset in TransferPreset::ALL {
                ui.selectable_value(&mut volume.preset, preset, preset.name());
            }
        });
        transfer_legend(ui, volume.preset);
        ui.add(egui::Slider::new(&mut volume.density_scale, 0.1..=4.0).text("density"));
        ui.add(egui::Slider::new(&mut volume.opacity_scale, 0.1..=4.0).text("opacity scale"));
        ui.add(
            egui::Slider::new(&mut volume.step_voxels, 0.25..=4.0)
                .logarithmic(true)
                .text("step (voxels)"),
        )
        .on_hover_text("Smaller steps: finer detail, slower frames");
        ui.horizontal(|ui| {
            ui.checkbox(&mut volume.hp_tint, "hp tint")
                .on_hover_text("Colour by mean hp: red percussive to blue harmonic");
            ui.checkbox(&mut volume.shading, "shading");
        });
    }

    fn surface_controls(&mut self, ui: &mut egui::Ui) {
        use crate::render::mesh::SurfaceMethod;
        ui.add_space(6.0);
        ui.label(RichText::new("Surface").strong());
        let surface = &mut self.settings.surface;
        ui.horizontal(|ui| {
            for method in SurfaceMethod::ALL {
                ui.selectable_value(&mut surface.method, method, method.name());
            }
        });
        ui.add(egui::Slider::new(&mut surface.iso_value, 0.0..=1.0).text("isovalue"))
            .on_hover_text("The loudness density the surface encloses");
        ui.checkbox(&mut surface.lit, "lit from above");
        if let Some(error) = &self.surface_error {
            ui.colored_label(Color32::from_rgb(240, 120, 100), error);
        }
    }

    fn screenshot_controls(&mut self, ui: &mut egui::Ui) {
        ui.label(RichText::new("Screenshot").strong());
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.active().is_some(), egui::Button::new("Save PNG"))
                .on_hover_text("Ctrl+S (Cmd+S): the 3D view as a PNG")
                .clicked()
            {
                self.shot_requested = true;
            }
            ui.checkbox(&mut self.shot_custom_size, "size");
        });
        if self.shot_custom_size {
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut self.shot_size[0]).range(16..=8192));
                ui.label("×");
                ui.add(egui::DragValue::new(&mut self.shot_size[1]).range(16..=8192));
                ui.label("px");
            });
        }
        ui.add(
            egui::TextEdit::singleline(&mut self.shot_path)
                .hint_text("loudscape-<time>.png")
                .desired_width(230.0),
        );
    }

    /// Renders the current view offscreen (window size or the chosen size) and saves it.
    fn save_screenshot(&mut self, frame: &eframe::Frame) {
        let (Some(render_state), Some(mut view)) = (frame.wgpu_render_state(), self.last_view)
        else {
            return;
        };
        let Some(loaded) = self.active() else {
            return;
        };
        if self.shot_custom_size {
            view.width = self.shot_size[0].max(1);
            view.height = self.shot_size[1].max(1);
        }
        let path = if self.shot_path.trim().is_empty() {
            crate::screenshot::timestamped_name(std::time::SystemTime::now())
        } else {
            PathBuf::from(self.shot_path.trim())
        };
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        let result =
            ViewResources::screenshot(render_state, loaded.id, &loaded.cloud, &view, &settings)
                .and_then(|image| crate::screenshot::save_png(&image, &path));
        match result {
            Ok(()) => self.messages.push(format!(
                "saved {} ({}×{})",
                path.display(),
                view.width,
                view.height
            )),
            Err(e) => self.messages.push(e.to_string()),
        }
    }

    /// The hovered or selected timeline song: who, when, how loud, and its own Song cloud.
    fn timeline_song(&mut self, ui: &mut egui::Ui) {
        let Some(loaded) = self.timeline.as_ref() else {
            return;
        };
        let cloud = loaded.cloud.clone();
        let index = self.hovered_song.or(self.selected_song);
        ui.add_space(6.0);
        ui.label(RichText::new("Song").strong());
        let Some(song) = index.and_then(|i| cloud.meta.songs.get(i)) else {
            ui.label(
                RichText::new("Hover a song's span to see it; click to keep it.")
                    .small()
                    .weak(),
            );
            return;
        };
        ui.label(RichText::new(song_title(song)).strong());
        for line in song
            .metrics
            .as_ref()
            .map(overlay::describe_metrics)
            .unwrap_or_default()
        {
            ui.label(RichText::new(line).small());
        }
        if let Some(path) = song_cloud_path(&cloud, song) {
            if ui
                .button("Open in Song mode")
                .on_hover_text(path.display().to_string())
                .clicked()
            {
                self.start_loading(path);
            }
        } else {
            ui.label(
                RichText::new("No Song cloud of it next to the song or the timeline.")
                    .small()
                    .weak(),
            );
        }
    }
}

/// Density at which a hover ray stops in the Volume view.
const VOLUME_PICK_DENSITY: f32 = 0.1;

/// "Title — Artist (1984)".
fn song_title(song: &crate::cloud::SongInfo) -> String {
    let mut text = if song.title.is_empty() {
        "untitled".to_string()
    } else {
        song.title.clone()
    };
    if !song.artist.is_empty() {
        text.push_str(&format!(" — {}", song.artist));
    }
    if let Some(year) = song.year {
        text.push_str(&format!(" ({year})"));
    }
    text
}

/// The song's own Song cloud: same stem .ply next to the song's audio, or next to the timeline.
fn song_cloud_path(timeline: &PointCloud, song: &crate::cloud::SongInfo) -> Option<PathBuf> {
    let audio = PathBuf::from(song.path.as_ref()?);
    let stem = audio.file_stem()?;
    let mut name = stem.to_os_string();
    name.push(".ply");
    let folder = timeline.path.parent().unwrap_or(Path::new(""));
    let candidates = [
        audio.with_file_name(&name),
        folder
            .join(audio.parent().unwrap_or(Path::new("")))
            .join(&name),
        folder.join(&name),
    ];
    candidates
        .into_iter()
        .find(|p| p.is_file() && p != &timeline.path)
}

/// The read-out next to the cursor.
fn paint_readings(
    painter: &egui::Painter,
    rect: egui::Rect,
    pos: egui::Pos2,
    readings: &[Reading],
) {
    if readings.is_empty() {
        return;
    }
    let text = readings
        .iter()
        .map(|r| format!("{}: {}", r.name, r.value))
        .collect::<Vec<_>>()
        .join("\n");
    let galley =
        painter.layout_no_wrap(text, egui::FontId::monospace(12.0), Color32::from_gray(230));
    let size = galley.size() + egui::vec2(12.0, 8.0);
    let mut min = pos + egui::vec2(16.0, 12.0);
    if min.x + size.x > rect.right() {
        min.x = pos.x - 16.0 - size.x;
    }
    if min.y + size.y > rect.bottom() {
        min.y = pos.y - 12.0 - size.y;
    }
    let frame = egui::Rect::from_min_size(min, size);
    painter.rect_filled(frame, 4.0, Color32::from_black_alpha(200));
    painter.galley(min + egui::vec2(6.0, 4.0), galley, Color32::from_gray(230));
}

/// A horizontal colour strip for a palette over [0, 1].
fn gradient_legend(ui: &mut egui::Ui, color: impl Fn(f32) -> [u8; 3]) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(200.0, 12.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let steps = 50;
    for i in 0..steps {
        let t = i as f32 / (steps - 1) as f32;
        let [r, g, b] = color(t);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, rect.y_range()),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
}

/// The transfer function's colour and opacity over density 0..1, over a checker so opacity shows.
fn transfer_legend(ui: &mut egui::Ui, preset: crate::render::transfer::TransferPreset) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(200.0, 12.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let steps = 50;
    let colours = preset.legend(steps);
    for (i, [r, g, b, a]) in colours.into_iter().enumerate() {
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        let cell = egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, rect.y_range());
        painter.rect_filled(cell, 0.0, Color32::from_gray(40));
        painter.rect_filled(cell, 0.0, Color32::from_rgba_unmultiplied(r, g, b, a));
    }
    ui.horizontal(|ui| {
        ui.label(RichText::new("density 0").small());
        ui.add_space(120.0);
        ui.label(RichText::new("1").small());
    });
}
