//! The window's A/B compare: B loaded beside the Song slot's cloud (A), both moved onto the
//! union of their axes, drawn side by side (two viewports, one camera: the same camera input
//! moves both) or as their difference grid, hover read-outs of A and B, and the A/B audio
//! switch (key B, or the panel's buttons) that keeps the playback position. What it keeps
//! between frames ([`CompareState`]) is `state/compare_window.rs`; here are its methods on
//! `LoudscapeApp`.
//!
//! GPU side: [`CompareResources`] sits in egui_wgpu's callback resources beside the bridge's
//! `ViewResources` (whose renderer it borrows) and holds the [`CompareScene`] and one offscreen
//! target per half; [`CompareCallback`] renders a half into its target only when what it shows
//! changed and composites it into its viewport.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Duration;

use eframe::egui::{self, Color32, RichText};
use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};

use crate::data::cloud::PointCloud;
use crate::data::compare::on_union_axes;
use crate::data::field::Field;
use crate::playback::{self, PlaybackError, Track};
use crate::render::compare::CompareScene;
use crate::render::composite::CompositePass;
use crate::render::gpu::target::RenderTarget;
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::scene::{RenderSettings, ViewKind};
use crate::ui::bridge::ViewResources;
use crate::ui::compare::paint_difference;
use crate::ui::compare_readouts::{compare_readings, difference_readings};
use crate::ui::compare_shot::difference_settings;
use crate::ui::hover::paint_readings;
use crate::ui::labels;
use crate::ui::state::compare_window::{CompareLayout, CompareState, DifferenceCopy, Listening};
use crate::ui::state::{LoudscapeApp, Slot};
use crate::view::frame_view::FrameView;

/// The B field's id (typed into before any compare exists).
pub(super) const COMPARE_FIELD: &str = "compare-b-field";

/// Points between the two halves of the side-by-side view.
pub(super) const GAP: f32 = 4.0;

/// Loads B on a thread, as the Open row loads any file.
fn load_b(path: PathBuf) -> Receiver<Result<PointCloud, String>> {
    let (sender, receiver) = channel();
    std::thread::spawn(move || {
        let settings = crate::extract::Settings::default();
        let shared = crate::ui::state::loading::Shared::default();
        let _ = sender.send(crate::ui::open::open_path(&path, &settings, &shared));
    });
    receiver
}

/// Decodes a cloud's source audio on a thread.
fn decode_audio(cloud: &PointCloud) -> Receiver<Result<Track, PlaybackError>> {
    let (sender, receiver) = channel();
    let found = playback::resolve_source(cloud);
    std::thread::spawn(move || {
        let _ = sender.send(found.and_then(|path| playback::decode(&path)));
    });
    receiver
}

impl LoudscapeApp {
    /// Starts comparing the Song slot's cloud with `path` (the command line's --compare, the
    /// panel's field or dialog, a drop with Shift held).
    pub(super) fn compare_with(&mut self, path: PathBuf) {
        self.open.compare_path = path.display().to_string();
        let mut state = CompareState::new(path.clone());
        if let Some(old) = &self.compare {
            state.layout = match old.layout {
                CompareLayout::Off => CompareLayout::SideBySide,
                other => other,
            };
            state.measure = old.measure;
        }
        state.receiver = Some(load_b(path));
        if self.listening_b() {
            // B's track is the one playing: bring A back first (position kept).
            self.listen(Listening::A);
        }
        self.compare = Some(state);
    }

    fn listening_b(&self) -> bool {
        self.compare
            .as_ref()
            .is_some_and(|c| c.listening == Listening::B)
    }

    /// Takes B when it has loaded, builds the GPU scene when A or B changed, the grids when the
    /// view needs them, and B's audio.
    pub(super) fn poll_compare(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        if let Some(seconds) = self.pending_seek
            && self.audio.time_s().is_some()
        {
            self.audio.seek(seconds);
            self.pending_seek = None;
        }
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        if let Some(receiver) = &state.receiver {
            match receiver.try_recv() {
                Ok(Ok(cloud)) => {
                    state.receiver = None;
                    state.b_loaded = Some(Arc::new(cloud));
                    state.built_for = None;
                }
                Ok(Err(message)) => {
                    state.receiver = None;
                    state.error = Some(message);
                }
                Err(TryRecvError::Empty) => ctx.request_repaint_after(Duration::from_millis(50)),
                Err(TryRecvError::Disconnected) => {
                    state.receiver = None;
                    state.error = Some(format!("{}: the loader stopped", state.path.display()));
                }
            }
        }
        if let Some(receiver) = &state.decoding {
            match receiver.try_recv() {
                Ok(Ok(track)) => {
                    state.decoding = None;
                    state.other_track = Some(track);
                }
                Ok(Err(e)) => {
                    state.decoding = None;
                    state.error = Some(format!("B's audio: {e}"));
                }
                Err(TryRecvError::Empty) => ctx.request_repaint_after(Duration::from_millis(50)),
                Err(TryRecvError::Disconnected) => state.decoding = None,
            }
        }
        if state.error != state.error_told {
            state.error_told = state.error.clone();
            if let Some(error) = &state.error {
                self.messages.error(format!("compare: {error}"));
            }
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let (Some(song), Some(b)) = (self.song.as_ref(), state.b_loaded.clone()) else {
            return;
        };
        if state.built_for != Some(song.id) {
            state.built_for = Some(song.id);
            state.difference = None;
            state.hover = None;
            match on_union_axes(&song.cloud, &b) {
                Ok((a, b_moved)) => {
                    state.labels = Some(labels::axis_labels_for_box(
                        &a,
                        glam::Vec3::splat(-1.0),
                        glam::Vec3::splat(1.0),
                    ));
                    CompareResources::build(render_state, a.clone(), b_moved.clone());
                    state.clouds = Some(Arc::new((a, b_moved)));
                    state.error = None;
                    if state.listening == Listening::A && state.other_track.is_none() {
                        state.decoding = Some(decode_audio(&b));
                    }
                }
                Err(e) => {
                    state.clouds = None;
                    state.error = Some(e.to_string());
                    CompareResources::clear(render_state);
                }
            }
            self.fit_pending = true;
        }
        let needs_grids = state.clouds.is_some()
            && match state.layout {
                CompareLayout::Off => false,
                CompareLayout::SideBySide => self.settings.view != ViewKind::Points,
                CompareLayout::Difference => true,
            };
        if !needs_grids {
            return;
        }
        let voxels = self.settings.voxels;
        if !CompareResources::grids_match(render_state, &voxels) {
            // Building blocks the window for a moment: say so first, build on the next frame.
            // (A flag of its own: the song's grid build, later in the same frame, cleared the
            // shared one every frame, so in side by side the grids were never built and both
            // halves drew points whatever the view.)
            if !state.grids_announced {
                self.busy = Some("building the compare grids…".into());
                state.grids_announced = true;
                self.needs_repaint = true;
                return;
            }
            state.grids_announced = false;
            self.busy = None;
            state.difference = None;
            if let Err(message) = CompareResources::ensure_grids(render_state, &voxels) {
                state.error = Some(message);
                return;
            }
        } else if std::mem::take(&mut state.grids_announced) {
            // Built meanwhile by another path (Save PNG renders the compare itself).
            self.busy = None;
        }
        CompareResources::set_measure(render_state, state.measure);
        let stale = state
            .difference
            .as_ref()
            .is_none_or(|d| d.measure != state.measure);
        if stale {
            state.difference = CompareResources::read_difference(render_state);
            state.hover = None;
        }
    }

    /// Switches the heard song to `to`, at the same position, playing if it was.
    pub(super) fn listen(&mut self, to: Listening) {
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        if state.listening == to {
            return;
        }
        let Some(track) = state.other_track.take() else {
            return;
        };
        state.other_track = self.audio.swap_track(track);
        state.listening = to;
        // The window tells stderr, as it does of loads: a log, not a script's input.
        eprintln!(
            "listening to {} at {:.3} s",
            if to == Listening::A { "A" } else { "B" },
            self.audio.position_s().unwrap_or(0.0)
        );
    }

    /// The compare section of the side panel.
    pub(super) fn compare_controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(6.0);
        ui.label(RichText::new("Compare (A/B)").strong());
        let mut start = None;
        ui.horizontal(|ui| {
            let field = &mut self.open.compare_path;
            let edit = ui.add(
                egui::TextEdit::singleline(field)
                    .id(egui::Id::unique(COMPARE_FIELD))
                    .hint_text("B: song or cloud")
                    .desired_width(130.0),
            );
            if edit.lost_focus()
                && ui.input(|i| i.key_pressed(egui::Key::Enter))
                && !field.trim().is_empty()
            {
                start = Some(PathBuf::from(field.trim()));
            }
            let open = self.compare.as_ref().is_none_or(|c| c.dialog.is_none());
            if ui
                .add_enabled(
                    open && self.song.is_some(),
                    egui::Button::new("Compare with…"),
                )
                .on_hover_text("B beside the song (A); or drop a file with Shift held")
                .clicked()
            {
                if !crate::ui::open::dialogs_available() {
                    self.messages.warn(format!(
                        "{}: type B's path in the compare field and press Enter",
                        crate::ui::open::NO_DIALOG
                    ));
                    return;
                }
                let receiver = crate::ui::open::open_dialog(false);
                let state = self
                    .compare
                    .get_or_insert_with(|| CompareState::new(PathBuf::new()));
                state.layout = CompareLayout::Off;
                state.dialog = Some(receiver);
            }
        });
        if let Some(state) = self.compare.as_mut()
            && let Some(receiver) = &state.dialog
        {
            match receiver.try_recv() {
                Ok(picked) => {
                    state.dialog = None;
                    start = start.or(picked.and_then(|paths| paths.into_iter().next()));
                }
                Err(TryRecvError::Disconnected) => state.dialog = None,
                Err(TryRecvError::Empty) => {
                    ui.ctx().request_repaint_after(Duration::from_millis(100));
                }
            }
        }
        if let Some(path) = start {
            if self.song.is_some() {
                self.compare_with(path);
            } else {
                self.messages
                    .warn("open a song (A) first, then compare it with B".to_string());
            }
        }
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        if state.receiver.is_some() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("loading B: {}", state.path.display()));
            });
        }
        if let Some(error) = &state.error {
            ui.colored_label(Color32::from_rgb(240, 120, 100), error);
        }
        if state.clouds.is_none() {
            return;
        }
        ui.horizontal(|ui| {
            for (layout, name) in [
                (CompareLayout::Off, "A only"),
                (CompareLayout::SideBySide, "Side by side"),
                (CompareLayout::Difference, "Difference"),
            ] {
                if ui
                    .add(egui::Button::selectable(state.layout == layout, name))
                    .clicked()
                {
                    state.layout = layout;
                    state.hover = None;
                    // The view changes: draw it now (a build is announced first).
                    ui.ctx().request_repaint();
                    self.fit_pending = true;
                }
            }
        });
        if state.layout == CompareLayout::Difference {
            ui.horizontal(|ui| {
                ui.label("measure");
                for measure in DifferenceMeasure::ALL {
                    if ui
                        .add(egui::Button::selectable(
                            state.measure == measure,
                            measure.name(),
                        ))
                        .on_hover_text(measure.describe())
                        .clicked()
                    {
                        state.measure = measure;
                        ui.ctx().request_repaint();
                    }
                }
            });
        }
        let mut switch = None;
        ui.horizontal(|ui| {
            ui.label("listen");
            let ready = state.other_track.is_some();
            for (side, name) in [(Listening::A, "A"), (Listening::B, "B")] {
                let response = ui
                    .add_enabled(
                        ready || state.listening == side,
                        egui::Button::selectable(state.listening == side, name),
                    )
                    .on_hover_text("key B switches, at the same position");
                if response.clicked() {
                    switch = Some(side);
                }
            }
            if state.decoding.is_some() {
                ui.spinner();
            }
        });
        if let Some(side) = switch {
            self.listen(side);
        }
    }

    /// The scripted `--press compare=off|side|difference` of tests: the compare's layout.
    pub(super) fn scripted_compare(&mut self, name: &str) -> bool {
        let layout = match name.strip_prefix("compare=") {
            Some("off") => CompareLayout::Off,
            Some("side") => CompareLayout::SideBySide,
            Some("difference") => CompareLayout::Difference,
            _ => return false,
        };
        if let Some(state) = self.compare.as_mut() {
            state.layout = layout;
            self.fit_pending = true;
        }
        true
    }

    /// Key B: the other song, at the same position.
    pub(super) fn compare_keys(&mut self, ctx: &egui::Context) {
        let Some(state) = self.compare.as_ref() else {
            return;
        };
        if state.clouds.is_none() {
            return;
        }
        if crate::ui::shortcuts::pressed(ctx, crate::ui::shortcuts::Action::SwapAb) {
            let to = match state.listening {
                Listening::A => Listening::B,
                Listening::B => Listening::A,
            };
            self.listen(to);
        }
    }

    /// Draws the compare into `rect` when it is shown (then the normal view is not drawn) and
    /// its hover read-outs. `view` is one half's view in side by side, the whole in difference.
    pub(super) fn paint_compare(
        &mut self,
        painter: &egui::Painter,
        rect: egui::Rect,
        view: &FrameView,
        render_view: &FrameView,
        settings: &RenderSettings,
        hover: Option<egui::Pos2>,
    ) -> bool {
        if self.active != Slot::Song {
            return false;
        }
        let Some(state) = self.compare.as_mut() else {
            return false;
        };
        if !state.shown() {
            return false;
        }
        let Some(clouds) = state.clouds.clone() else {
            return false;
        };
        let names = [&clouds.0, &clouds.1].map(|c| {
            c.path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        let ppp = painter.ctx().pixels_per_point();
        let mut readings = None;
        match state.layout {
            CompareLayout::SideBySide => {
                let half = (rect.width() - GAP) / 2.0;
                let rects = [
                    egui::Rect::from_min_size(rect.min, egui::vec2(half, rect.height())),
                    egui::Rect::from_min_size(
                        rect.min + egui::vec2(half + GAP, 0.0),
                        egui::vec2(half, rect.height()),
                    ),
                ];
                for (side, half_rect) in rects.into_iter().enumerate() {
                    painter.add(egui_wgpu::Callback::new_paint_callback(
                        half_rect,
                        CompareCallback {
                            side,
                            view: *render_view,
                            settings: settings.clone(),
                        },
                    ));
                    // Its title and the colour key of what it draws, as saved pictures carry.
                    let cloud = if side == 0 { &clouds.0 } else { &clouds.1 };
                    let title = format!("{}: {}", ["A", "B"][side], names[side]);
                    let legend = crate::picture::compare::half_legend(cloud, settings, &title);
                    let labels = state.labels.as_ref().filter(|_| self.settings.show_box);
                    crate::ui::legends::paint_with_labels(
                        painter, half_rect, view, labels, &legend,
                    );
                }
                if let Some(pos) = hover
                    && !view.moving
                {
                    let side = usize::from(pos.x >= rects[1].min.x);
                    let px = glam::Vec2::new(
                        (pos.x - rects[side].min.x) * ppp,
                        (pos.y - rects[side].min.y) * ppp,
                    );
                    readings = Some((pos, compare_readings(&clouds, side, view, px)));
                }
            }
            CompareLayout::Difference => {
                painter.add(egui_wgpu::Callback::new_paint_callback(
                    rect,
                    CompareCallback {
                        side: 2,
                        view: *render_view,
                        settings: difference_settings(settings),
                    },
                ));
                if let Some(labels) = &state.labels
                    && self.settings.show_box
                {
                    labels::paint(painter, rect, view, labels);
                }
                paint_difference(
                    painter,
                    rect,
                    &format!("B - A: {} against {}", names[1], names[0]),
                    state.difference.as_ref().map(|c| (c.measure, c.range)),
                );
                if let Some(copy) = &state.difference
                    && let Some(pos) = hover
                    && !view.moving
                {
                    let px =
                        glam::Vec2::new((pos.x - rect.min.x) * ppp, (pos.y - rect.min.y) * ppp);
                    readings = Some((pos, difference_readings(&clouds.0, copy, view, px)));
                }
            }
            CompareLayout::Off => {}
        }
        if let Some((pos, lines)) = readings {
            paint_readings(painter, rect, pos, &lines);
        }
        true
    }
}

/// One half's offscreen target and what it holds.
struct HalfTarget {
    target: Option<RenderTarget>,
    composite: CompositePass,
    last: Option<(FrameViewKey, RenderSettings, u64)>,
}

/// The parts of a view that change its picture (the frame counter does not).
#[derive(Clone, Debug, PartialEq)]
struct FrameViewKey {
    camera: crate::view::camera::Camera,
    size: (u32, u32),
    moving: bool,
}

/// The compare's GPU state, in egui_wgpu's callback resources.
pub struct CompareResources {
    pub(super) scene: Option<CompareScene>,
    halves: [HalfTarget; 3],
    /// Bumped when the scene or its grids change.
    revision: u64,
}

impl CompareResources {
    pub(super) fn with<T>(
        render_state: &egui_wgpu::RenderState,
        f: impl FnOnce(&mut CompareResources, &ViewResources) -> T,
    ) -> Option<T> {
        let mut renderer = render_state.renderer.write();
        let resources = &mut renderer.callback_resources;
        if resources.get::<CompareResources>().is_none() {
            let device = &render_state.device;
            let half = || HalfTarget {
                target: None,
                composite: CompositePass::new(device, render_state.target_format),
                last: None,
            };
            resources.insert(CompareResources {
                scene: None,
                halves: [half(), half(), half()],
                revision: 0,
            });
        }
        let mut compare = resources.remove::<CompareResources>()?;
        let result = resources
            .get::<ViewResources>()
            .map(|view| f(&mut compare, view));
        resources.insert(compare);
        result
    }

    fn build(render_state: &egui_wgpu::RenderState, a: PointCloud, b: PointCloud) {
        Self::with(render_state, |compare, view| {
            compare.scene = Some(CompareScene::from_union(
                &render_state.device,
                &view.renderer,
                a,
                b,
            ));
            compare.revision += 1;
        });
    }

    fn clear(render_state: &egui_wgpu::RenderState) {
        Self::with(render_state, |compare, _| {
            compare.scene = None;
            compare.revision += 1;
        });
    }

    fn grids_match(
        render_state: &egui_wgpu::RenderState,
        voxels: &crate::render::grid::voxelize::VoxelSettings,
    ) -> bool {
        Self::with(render_state, |compare, _| {
            compare.scene.as_ref().is_none_or(|scene| {
                scene.grids.is_some() && scene.data_a.grid_matches(&scene.a, voxels)
            })
        })
        .unwrap_or(true)
    }

    fn ensure_grids(
        render_state: &egui_wgpu::RenderState,
        voxels: &crate::render::grid::voxelize::VoxelSettings,
    ) -> Result<(), String> {
        Self::with(render_state, |compare, view| {
            let Some(scene) = compare.scene.as_mut() else {
                return Ok(());
            };
            let built = scene
                .ensure_grids(
                    &render_state.device,
                    &render_state.queue,
                    &view.renderer,
                    voxels,
                )
                .map_err(|e| e.to_string())?;
            if built {
                compare.revision += 1;
            }
            Ok(())
        })
        .unwrap_or(Ok(()))
    }

    fn set_measure(render_state: &egui_wgpu::RenderState, measure: DifferenceMeasure) {
        Self::with(render_state, |compare, view| {
            if let Some(scene) = compare.scene.as_mut()
                && scene.grids.as_ref().is_some_and(|g| g.measure != measure)
            {
                scene.set_measure(
                    &render_state.device,
                    &render_state.queue,
                    &view.renderer,
                    measure,
                );
                compare.revision += 1;
            }
        });
    }

    fn read_difference(render_state: &egui_wgpu::RenderState) -> Option<DifferenceCopy> {
        Self::with(render_state, |compare, _| {
            let grids = compare.scene.as_ref()?.grids.as_ref()?;
            let (device, queue) = (&render_state.device, &render_state.queue);
            let shown = &grids.grids.shown;
            let density = shown.read_field(device, queue, &shown.density).ok()?;
            let hp_mean = shown.read_field(device, queue, &shown.hp_mean).ok()?;
            Some(DifferenceCopy {
                shown: Field {
                    dims: shown.dims,
                    box_min: shown.box_min,
                    box_max: shown.box_max,
                    density,
                    hp_mean,
                },
                difference: grids.difference_cpu.clone(),
                columns: grids.columns_cpu.clone(),
                measure: grids.measure,
                range: grids.range(),
            })
        })
        .flatten()
    }
}

/// One half of the compare (0 A, 1 B) or the difference (2).
struct CompareCallback {
    side: usize,
    view: FrameView,
    settings: RenderSettings,
}

impl CallbackTrait for CompareCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(mut compare) = resources.remove::<CompareResources>() else {
            return Vec::new();
        };
        if let Some(view_resources) = resources.get::<ViewResources>() {
            let revision = compare.revision;
            let CompareResources { scene, halves, .. } = &mut compare;
            let half = &mut halves[self.side];
            let (w, h) = (self.view.width, self.view.height);
            if !half.target.as_ref().is_some_and(|t| t.has_size(w, h)) {
                let target = RenderTarget::new(device, w, h);
                half.composite.set_source(device, &target);
                half.target = Some(target);
                half.last = None;
            }
            let key = (
                FrameViewKey {
                    camera: self.view.camera,
                    size: (w, h),
                    moving: self.view.moving,
                },
                self.settings.clone(),
                revision,
            );
            let data = scene.as_ref().and_then(|s| match self.side {
                0 => Some(&s.data_a),
                1 => Some(&s.data_b),
                _ => s.grids.as_ref().map(|g| &g.data),
            });
            if half.last.as_ref() != Some(&key)
                && let Some(target) = half.target.as_ref()
            {
                view_resources.renderer.render(
                    queue,
                    encoder,
                    target,
                    data,
                    &self.view,
                    &self.settings,
                );
                let pending = data.is_some_and(|d| {
                    self.settings.view == ViewKind::Surface && d.surface.needs_another_frame()
                });
                half.last = (!pending).then_some(key);
            }
        }
        resources.insert(compare);
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(compare) = resources.get::<CompareResources>() {
            compare.halves[self.side].composite.draw(render_pass);
        }
    }
}
