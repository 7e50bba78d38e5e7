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
use crate::render::frame::FrameView;
use crate::render::scene::{RenderSettings, ViewKind, world_from_data};
use crate::ui::bridge::{ViewCallback, ViewResources};

/// How long after the last input the view still counts as moving (drawn at reduced quality).
const SETTLE: Duration = Duration::from_millis(180);

/// Options from the command line.
#[derive(Clone, Debug, Default)]
pub struct WindowOptions {
    pub files: Vec<PathBuf>,
    /// Save a screenshot of the window here once the data is shown, then close (for tests).
    pub screenshot: Option<PathBuf>,
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
            Ok(Box::new(LoudscapeApp::new(options)))
        }),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the window: {e}"))
}

impl LoudscapeApp {
    fn new(options: WindowOptions) -> Self {
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
        };
        for file in options.files {
            app.start_loading(file);
        }
        app
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
        let scene = crate::render::scene::data_box(&cloud);
        let world_from_data = world_from_data(cloud.meta.mode);
        let a = world_from_data.transform_point3(scene.0);
        let b = world_from_data.transform_point3(scene.1);
        let labels = {
            let render_data_box = scene;
            overlay::axis_labels_for_box(&cloud, render_data_box.0, render_data_box.1)
        };
        let loaded = Loaded {
            id,
            point_size: crate::render::points::PointStyle::size_for(cloud.points.len()),
            cloud: Arc::new(cloud),
            labels,
            world_from_data,
            world_box: (a.min(b), a.max(b)),
        };
        match slot {
            Slot::Song => self.song = Some(loaded),
            Slot::Timeline => self.timeline = Some(loaded),
        }
        self.active = slot;
        self.fit_pending = true;
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

        ui.add_space(6.0);
        ui.label(RichText::new("Points").strong());
        if let Some(size) = self.active().map(|l| l.point_size) {
            self.settings.points.size_px = size;
        }
        let size_changed = ui
            .add(egui::Slider::new(&mut self.settings.points.size_px, 1.0..=12.0).text("size (px)"))
            .changed();
        if size_changed {
            let size = self.settings.points.size_px;
            match self.active {
                Slot::Song => self.song.iter_mut().for_each(|l| l.point_size = size),
                Slot::Timeline => self.timeline.iter_mut().for_each(|l| l.point_size = size),
            }
        }
        ui.add(
            egui::Slider::new(&mut self.settings.points.min_scalar, 0.0..=1.0).text("min loudness"),
        );
        hp_legend(ui);

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
        let callback = ViewCallback {
            view,
            settings: self.settings.clone(),
            cloud_id: active.map(|l| l.id),
        };
        let painter = ui.painter_at(rect);
        painter.add(egui_wgpu::Callback::new_paint_callback(rect, callback));
        if let Some(loaded) = active {
            if self.settings.show_box {
                overlay::paint(&painter, rect, &view, &loaded.labels);
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
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.frame_ms = self.frame_ms * 0.9 + ctx.input(|i| i.unstable_dt) * 1000.0 * 0.1;
        self.poll_loading(&ctx, frame);
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
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.view_3d(ui));
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
        if i > 0 && (digits.len() - i) % 3 == 0 {
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
    let tmp = path.with_extension("png.tmp");
    img.save_with_format(&tmp, image::ImageFormat::Png)?;
    std::fs::rename(&tmp, path)?;
    Ok(())
}
