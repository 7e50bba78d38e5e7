//! The loudscape window's wiring: opening the window, `LoudscapeApp`'s start, and one frame
//! (side panel, transport bar, status area, then the 3D view of `view_3d.rs`). The panels,
//! hover read-outs, data slots, persistence and screenshots each have their own file in `ui/`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use eframe::egui;
use eframe::egui_wgpu;

use crate::render::scene::{RenderSettings, ViewKind};
use crate::ui::audio::AudioPanel;
use crate::ui::bridge::ViewResources;
use crate::ui::persistence::Remembered;
use crate::ui::shortcuts::{self, Action};
use crate::ui::state::{LoudscapeApp, SaveShot, ScreenshotState, Slot};
use crate::view::camera::Camera;

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
    /// Compare the song with these versions (B, C...; 7 at most):
    /// `loudscape A --compare B C`.
    pub compare: Vec<PathBuf>,
    /// Start playback at this many seconds once the song's audio is ready.
    pub seek: Option<f64>,
    /// Keys to press once the data is shown (`?`, `Ctrl+S`; for tests: they go through the
    /// same key handling as real keys).
    pub press: Vec<String>,
    /// The "level as heard" normalization to show a timeline with.
    pub normalize: crate::data::normalize::Normalization,
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
                crate::ui::style::install_fonts(&cc.egui_ctx);
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
            first_shown: Default::default(),
            settings: RenderSettings::default(),
            motion: Default::default(),
            loading: Vec::new(),
            messages: Default::default(),
            next_id: 1,
            clock: Default::default(),
            screenshot: options.screenshot.map(|path| ScreenshotState {
                path,
                frames_shown: 0,
                requested: false,
                done: Arc::new(AtomicBool::new(false)),
            }),
            audio: {
                let mut audio = AudioPanel::new(persist);
                if let Some(seconds) = options.seek {
                    audio.seek_when_loaded(seconds);
                }
                audio
            },
            hover: None,
            compare_hover: Default::default(),
            hovered_song: None,
            selected_song: None,
            save_shot: SaveShot::default(),
            last_view: None,
            view_px: (1, 1),
            persist,
            saved: None,
            surface: Default::default(),
            refining: None,
            iso_sweep,
            busy: None,
            busy_shown: false,
            volume_hold: Default::default(),
            needs_repaint: false,
            open: crate::ui::state::open::OpenPanel {
                // A scripted run keeps a recent list only where it is told to.
                recent: crate::ui::recent::RecentFiles::load(
                    (persist || std::env::var_os("LOUDSCAPE_STATE_DIR").is_some())
                        .then(crate::ui::recent::default_store)
                        .flatten(),
                ),
                ..Default::default()
            },
            timeline_build: crate::ui::state::timeline_build::TimelineBuilder::new(
                crate::ui::state::timeline_build::YearBook::load(
                    (persist || std::env::var_os("LOUDSCAPE_STATE_DIR").is_some())
                        .then(crate::ui::recent::default_store)
                        .flatten()
                        .map(|recent| recent.with_file_name("years.json")),
                ),
            ),
            scripted_presses: options.press,
            heard: crate::ui::normalize::heard_starting(options.normalize),
            deferred_events: Vec::new(),
            video_export: Default::default(),
            freq_axis: Default::default(),
            compare: None,
            strip: Default::default(),
        };
        let compare = options.compare.clone();
        let files = app.apply_remembered(options.files, remembered);
        if let Some(view) = options.view {
            app.settings.view = view;
        }
        app.start_opening(files);
        for version in compare {
            app.compare_with(version);
        }
        app
    }

    /// The default viewing direction, fitted to the active cloud (R, "Reset view").
    pub(super) fn reset_view(&mut self) {
        let target = self.fit_target();
        self.motion.reset(target);
    }

    /// Makes `slot` the active one. Each data mode keeps its own camera: the one left behind is
    /// remembered, the one switched to comes back as it was (or is fitted the first time).
    pub(super) fn switch_slot(&mut self, slot: Slot) {
        if self.active == slot {
            return;
        }
        self.motion.switch_slot(self.active, slot);
        self.active = slot;
        self.hover = None;
    }
}

/// The scripted press (`--press when-drawn`) that holds the presses after it until the view has
/// drawn its scene complete (every point of a large cloud).
const WHEN_DRAWN: &str = "when-drawn";

/// The scripted press (`--press close-window`) that asks the window to close as its close button
/// does (the window system's close request).
const CLOSE_WINDOW: &str = "close-window";

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
        // song being extracted) or nothing is loading. A compare's B loaded first too, and its
        // scene prepared (a Save PNG pressed then saves the compare, not A alone).
        let compare_ready = self
            .compare
            .as_ref()
            .is_none_or(|c| !c.loading() && c.scene_build.is_none());
        if !self.scripted_presses.is_empty()
            && ((self.active().is_some() && !self.previewing()) || self.loading.is_empty())
            && self.scripted_input_ready()
            && compare_ready
        {
            let mut presses = std::mem::take(&mut self.scripted_presses).into_iter();
            while let Some(name) = presses.next() {
                // The presses after `when-drawn` wait for the view at full detail.
                if name == WHEN_DRAWN {
                    if !self.save_shot.view_drawn {
                        self.scripted_presses = std::iter::once(name).chain(presses).collect();
                        ctx.request_repaint();
                        break;
                    }
                    continue;
                }
                if name == CLOSE_WINDOW {
                    raw_input
                        .viewports
                        .entry(egui::ViewportId::ROOT)
                        .or_default()
                        .events
                        .push(egui::ViewportEvent::Close);
                    continue;
                }
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
            let remembered = self.remembered();
            eframe::set_value(storage, eframe::APP_KEY, &remembered);
            self.saved = Some(remembered);
        }
    }

    fn auto_save_interval(&self) -> Duration {
        crate::ui::persistence::AUTO_SAVE
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.clock.observe(last_frame_ms(&ctx));
        let before = self.shown_state();
        self.poll_loading(&ctx, frame);
        self.apply_heard(frame);
        self.apply_freq_axis(frame);
        self.poll_compare(&ctx, frame);
        self.poll_video_export(&ctx);
        self.fetch_grid(frame);
        // The surface's status, read once a frame.
        let surface = frame
            .wgpu_render_state()
            .zip(self.active().map(|l| l.id))
            .and_then(|(render_state, id)| {
                ViewResources::read(render_state, |r| r.surface_status(id))
            })
            .unwrap_or_default();
        // The compare's two surfaces where it covers the view.
        let surface = self.compare_surface_status(frame).unwrap_or(surface);
        self.surface
            .extracted(surface.counts, surface.error.clone());
        self.surface.frame(
            self.settings.view == ViewKind::Surface && surface.extracting,
            surface.counts,
        );
        // The Volume and Surface views come back for a surface on the worker.
        self.needs_repaint |= surface.extracting && self.settings.view != ViewKind::Points;
        if self.surface.busy {
            // Come back for the finished surface; the frames in between only composite.
            ctx.request_repaint_after(Duration::from_millis(30));
        }
        self.refining = frame
            .wgpu_render_state()
            .and_then(|render_state| ViewResources::write(render_state, |r| r.refining(&ctx)))
            .flatten();
        // Where the compare covers the view, its halves' points are what fills in.
        if self.compare_covers_view() {
            self.refining = self.compare_refining(frame);
        }
        self.note_view_drawn(frame);
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
            .show(ui, |ui| self.side_panel(ui));
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
            if self.strip.has_curves() && shows_strip(ctx.content_rect().height()) {
                let time_s = self.audio.time_s().unwrap_or(0.0);
                let clicked = egui::Panel::bottom("loudness_strip")
                    .frame(crate::ui::style::panel_frame(ui.style()))
                    .show(ui, |ui| self.strip.show(ui, time_s))
                    .inner;
                if let Some(t) = clicked {
                    self.audio.seek(t);
                }
            }
        }
        // A switch to Volume made in the panel: its notice goes up before the status is drawn.
        self.step_volume_hold(&ctx);
        // Under the 3D view, above the transport bar: what the app is telling the user.
        self.status_area(ui);
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.view_3d(ui));
        // A save under way first: the frame that starts one is not counted as drawn meanwhile.
        self.poll_picture_save(&ctx);
        self.poll_save_wait(&ctx, frame);
        if std::mem::take(&mut self.save_shot.requested) {
            self.save_screenshot(&ctx, frame);
        }
        // After the save of this frame's Ctrl+S has started: a close in the same frame waits.
        self.close_after_save(&ctx);
        self.remember_audio_choice();
        self.ask_to_save(&ctx, frame);
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
            self.clock
                .rendered(ViewResources::read(render_state, |r| r.renders()).unwrap_or(0));
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
            self.motion.fit_pending(),
            self.motion.camera(),
        )
    }
}

/// The last frame's time in ms when it followed the one before at once (a repaint was asked
/// for); None when it waited for input, so its time says nothing about the device.
pub(super) fn last_frame_ms(ctx: &egui::Context) -> Option<f32> {
    ctx.requested_repaint_last_pass()
        .then(|| ctx.input(|i| i.unstable_dt) * 1000.0)
}

/// The side panel's width in a window wide enough.
const SIDE_PANEL_WIDTH: f32 = 270.0;

/// The side panel's width in a window `window_width` points wide: [`SIDE_PANEL_WIDTH`], but at
/// most 40 % of a small window (at 500 points it took more than half), never under 180.
pub(super) fn side_panel_width(window_width: f32) -> f32 {
    (window_width * 0.4).clamp(180.0, SIDE_PANEL_WIDTH)
}

/// Windows shorter than this leave the loudness strip out: at 500x400 the strip, the transport
/// bar and the status area took all but 30 points of the height and the 3D view showed nothing.
const STRIP_MIN_WINDOW_HEIGHT: f32 = 560.0;

/// Whether a window `window_height` points high shows the loudness strip under the view.
pub(super) fn shows_strip(window_height: f32) -> bool {
    window_height >= STRIP_MIN_WINDOW_HEIGHT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_window_keeps_most_of_its_height_for_the_view() {
        assert!(shows_strip(800.0) && shows_strip(600.0));
        assert!(!shows_strip(400.0), "no strip at 500x400");
        use crate::ui::messages::status_max_height;
        assert_eq!(status_max_height(1000.0), 110.0);
        assert!(status_max_height(400.0) <= 80.0);
        // What is left at 500x400 (transport ~45, status at most 80): over half the height.
        assert!(400.0 - 45.0 - status_max_height(400.0) > 200.0);
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
}
