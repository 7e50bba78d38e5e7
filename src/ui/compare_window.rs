//! The window's compare: versions B, C... (up to 8 in all) loaded beside the Song slot's cloud
//! (A), A and the version beside it moved onto the union of their axes and built into the
//! compare's GPU scene, its grids when the view needs them, and the audio switch (key B steps
//! A -> B -> C -> A, or the panel's buttons) that keeps the moment of the music. What it keeps between frames ([`CompareState`]) and decides by itself is
//! `state/compare_window.rs`; the side panel's section is `compare_panel.rs`, the two viewports
//! and read-outs `compare_view.rs`, and the GPU side the bridge's `bridge/compare.rs`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use eframe::egui;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::playback::{self, PlaybackError, Track};
use crate::render::compare::{BuiltGrids, OwnGridPasses};
use crate::render::grid::VoxelGrid;
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::grid::voxelize::VoxelSettings;
use crate::render::scene::ViewKind;
use crate::render::surface::state::ExtractionStatus;
use crate::ui::bridge::CompareResources;
use crate::ui::state::compare_window::{
    CompareLayout, CompareState, DifferenceCopy, GRIDS_BUSY, GridStep, Listening,
};
use crate::ui::state::loading::Shared;
use crate::ui::state::{LoudscapeApp, Slot};

/// The B field's id (typed into before any compare exists).
pub(super) const COMPARE_FIELD: &str = "compare-b-field";

/// Loads B on a thread, as the Open row loads any file; its progress and Cancel go through
/// `shared` (no points while it is extracted: `shared.preview` is off).
fn load_b(path: PathBuf, shared: Shared) -> Receiver<Result<PointCloud, String>> {
    let (sender, receiver) = channel();
    std::thread::spawn(move || {
        let settings = crate::extract::Settings::default();
        let _ = sender.send(crate::ui::open::open_path(&path, &settings, &shared));
    });
    receiver
}

/// Builds the compare's grids of `clouds` (A and B on their union axes) on a thread with
/// passes of its own (their pipelines compiled there too), so the window keeps drawing.
fn build_grids(
    render_state: &eframe::egui_wgpu::RenderState,
    clouds: Arc<(PointCloud, PointCloud)>,
    voxels: VoxelSettings,
    measure: DifferenceMeasure,
) -> Receiver<Result<BuiltGrids, String>> {
    let (sender, receiver) = channel();
    let (device, queue) = (render_state.device.clone(), render_state.queue.clone());
    let spawned = std::thread::Builder::new()
        .name("compare-grids".into())
        .spawn(move || {
            let passes = OwnGridPasses::new(&device);
            let (a, b) = &*clouds;
            let built = crate::render::compare::build_grids(
                &device,
                &queue,
                &passes.passes(),
                a,
                b,
                &voxels,
                measure,
            );
            let _ = sender.send(built.map_err(|e| e.to_string()));
        });
    // No thread: the receiver's sender is gone, which the state tells as an error.
    if let Err(e) = spawned {
        log::warn!("no thread for the compare grids: {e}");
    }
    receiver
}

/// What the difference's read-back for the read-outs needs, taken from the scene under the
/// renderer's lock: the shown grid's buffers and the CPU copies the build left.
struct DifferenceJob {
    device: wgpu::Device,
    queue: wgpu::Queue,
    shown: VoxelGrid,
    difference: Vec<f32>,
    columns: Vec<f32>,
    measure: DifferenceMeasure,
    range: f32,
}

/// The scene's difference to read back (None without grids).
fn difference_job(
    compare: &CompareResources,
    render_state: &eframe::egui_wgpu::RenderState,
) -> Option<DifferenceJob> {
    let grids = compare.scene.as_ref()?.grids.as_ref()?;
    let shown = &grids.grids.shown;
    Some(DifferenceJob {
        device: render_state.device.clone(),
        queue: render_state.queue.clone(),
        shown: VoxelGrid {
            dims: shown.dims,
            box_min: shown.box_min,
            box_max: shown.box_max,
            density: shown.density.clone(),
            hp_mean: shown.hp_mean.clone(),
        },
        difference: grids.difference_cpu.clone(),
        columns: grids.columns_cpu.clone(),
        measure: grids.measure,
        range: grids.range(),
    })
}

impl DifferenceJob {
    /// Reads the shown grid back on a thread; None comes when it could not be.
    fn spawn(self) -> Receiver<Option<DifferenceCopy>> {
        let (sender, receiver) = channel();
        let spawned = std::thread::Builder::new()
            .name("compare-difference-read".into())
            .spawn(move || {
                let read = |buffer| self.shown.read_field(&self.device, &self.queue, buffer);
                let copy = match (read(&self.shown.density), read(&self.shown.hp_mean)) {
                    (Ok(density), Ok(hp_mean)) => Some(DifferenceCopy {
                        shown: Field {
                            dims: self.shown.dims,
                            box_min: self.shown.box_min,
                            box_max: self.shown.box_max,
                            density,
                            hp_mean,
                        },
                        difference: self.difference,
                        columns: self.columns,
                        measure: self.measure,
                        range: self.range,
                    }),
                    (Err(e), _) | (_, Err(e)) => {
                        log::warn!("the difference could not be read back: {e}");
                        None
                    }
                };
                let _ = sender.send(copy);
            });
        // No thread: the receiver's sender is gone, which the state takes as nothing read.
        if let Err(e) = spawned {
            log::warn!("no thread for the difference's read-back: {e}");
        }
        receiver
    }
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
    /// Compares the Song slot's cloud with `path` too (the command line's --compare, the
    /// panel's field or dialog, a drop with Shift held): B first, then C, D... up to 8
    /// versions in all.
    pub(super) fn compare_with(&mut self, path: PathBuf) {
        self.open.compare_path = path.display().to_string();
        let state = self.compare.get_or_insert_with(CompareState::empty);
        match state.add(path.clone()) {
            Ok(added) => state.start_loading(added, |shared| load_b(path, shared)),
            Err(e) => {
                if state.is_empty() {
                    self.compare = None;
                }
                self.messages.warn(format!("compare: {e}"));
            }
        }
    }

    /// Takes B when it has loaded, builds the GPU scene when A or B changed, the grids when the
    /// view needs them, and B's audio.
    pub(super) fn poll_compare(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        self.poll_alignment(ctx);
        let previewing = self.previewing();
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        // Either still on its way: come back for it.
        let had_versions = !state.is_empty();
        let (loading, loaded_now) = state.poll_load();
        for &version in &loaded_now {
            // What the version's extractor found wrong in its input, in sight while the
            // compare (with A) is: the loader wrote it on stderr only.
            if let Some(song) = &self.song {
                for line in state.warning_lines(version) {
                    self.messages.warn_about(&song.cloud.path, line);
                }
            }
            // Its audio, for key B (A's own stays with the player).
            state.decode_audio_of(version, decode_audio);
        }
        if state.is_empty() && state.dialog.is_none() {
            // No version left (it failed, or Cancel on its row: nothing to call an error), or
            // the dialog closed with none picked: no compare.
            let error = state.error_to_tell();
            self.compare = None;
            match error {
                Some(error) => self.messages.error(format!("compare: {error}")),
                None if had_versions => self.messages.info("compare: loading cancelled"),
                None => {}
            }
            return;
        }
        let decoding = state.poll_decoding();
        if loading || decoding {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
        if let Some(error) = state.error_to_tell() {
            self.messages.error(format!("compare: {error}"));
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let (Some(song), Some(b)) = (self.song.as_ref(), state.beside_loaded()) else {
            return;
        };
        let first_build = state.built_for.is_none_or(|(id, _, _)| id != song.id);
        if state.rebuild_for(song.id) {
            // A and the version beside it (on A's time when the alignment has come, matched
            // when asked) moved onto their union axes on a thread (compare_scene.rs); an older
            // preparation's answer is not waited for.
            state.scene_build = Some(crate::ui::compare_scene::start(
                render_state.device.clone(),
                song.cloud.clone(),
                b,
                &state.alignment,
                state.beside,
                state.matched_shown(),
                first_build,
            ));
        }
        if let Some(build) = &state.scene_build {
            let Some(answer) = build.poll() else {
                // The scene shown stays until the new one comes; no grids are built for it.
                state.set_grids_pending(true);
                ctx.request_repaint_after(Duration::from_millis(30));
                return;
            };
            let first = build.first;
            state.scene_build = None;
            match answer {
                Ok(prepared) => {
                    let uploading = std::time::Instant::now();
                    let (a, b_moved) = prepared.clouds;
                    let buffers = prepared.buffers;
                    // The old scene goes on the thread that made the new one.
                    let old = CompareResources::write(render_state, |compare, view| {
                        compare.build(view, a, b_moved, buffers)
                    })
                    .flatten();
                    let old_clouds = state.clouds.take();
                    state.scene_built(prepared.shared, prepared.labels);
                    // Freeing the scene shown before (two copies of every point) is no work for
                    // this frame either.
                    let _ = std::thread::Builder::new()
                        .name("compare-scene-drop".into())
                        .spawn(move || drop((old, old_clouds)));
                    // A log line, as loads are told: tests wait for it.
                    eprintln!(
                        "compare: A and {} shown{} (prepared and uploaded in {:.0} ms on a \
                         thread, installed in {:.0} ms)",
                        state.beside.letter(),
                        if state.matched_shown() {
                            " (matched)"
                        } else {
                            ""
                        },
                        prepared.took.as_secs_f64() * 1000.0,
                        uploading.elapsed().as_secs_f64() * 1000.0
                    );
                }
                Err(e) => {
                    state.scene_failed(e);
                    CompareResources::write(render_state, |compare, _| compare.clear());
                }
            }
            // One camera: another version beside A keeps the view where it is, and a
            // reopened window the camera it was left with.
            if state.fit_scene(first, !previewing, song.id) {
                self.motion.request_fit();
            }
        }
        // Grids built on a thread arrive here; the window keeps drawing meanwhile.
        if let Some((built, frames, took)) = state.poll_grid_build() {
            let dims = built.grids.dims;
            let installing = std::time::Instant::now();
            CompareResources::write(render_state, |compare, view| {
                compare.install_grids(view, built)
            });
            state.grids_installed();
            // A log line, as loads are told: tests read it (the frame count ends it).
            eprintln!(
                "compare: grids built ({}x{}x{}) in {:.2} s, installed in {:.0} ms, while the \
                 window drew {frames} frames",
                dims.x,
                dims.y,
                dims.z,
                took.as_secs_f64(),
                installing.elapsed().as_secs_f64() * 1000.0
            );
        }
        if state.grid_build.is_none() && self.busy.as_deref() == Some(GRIDS_BUSY) {
            self.busy = None;
        }
        if !state.needs_grids(self.settings.view) {
            state.set_grids_pending(false);
            return;
        }
        let voxels = self.settings.voxels;
        let built =
            CompareResources::write(render_state, |compare, _| compare.grids_match(&voxels))
                .unwrap_or(true);
        let step = state.grid_step(&voxels, built);
        state.set_grids_pending(step != GridStep::Ready && step != GridStep::Failed);
        match step {
            GridStep::Ready => {}
            GridStep::Failed => return,
            GridStep::Align => {
                // The points stand in, and the status line says the grids are on their way.
                if self.busy.is_none() {
                    self.busy = Some(GRIDS_BUSY.into());
                }
                ctx.request_repaint_after(Duration::from_millis(30));
                return;
            }
            GridStep::Wait => {
                ctx.request_repaint_after(Duration::from_millis(30));
                return;
            }
            GridStep::Start => {
                ctx.request_repaint_after(Duration::from_millis(30));
                let (Some(clouds), Some(measure)) = (
                    state.clouds.clone(),
                    CompareResources::write(render_state, |compare, _| compare.measure()).flatten(),
                ) else {
                    return;
                };
                state.forget_difference();
                state.building(voxels, build_grids(render_state, clouds, voxels, measure));
                self.busy = Some(GRIDS_BUSY.into());
                ctx.request_repaint_after(Duration::from_millis(30));
                return;
            }
        }
        // The measure shown and, when the read-outs' copy is stale, its read-back started on a
        // thread (the GPU's copy is waited for there): one lock.
        let stale = state.difference_stale();
        let job = CompareResources::write(render_state, |compare, view| {
            compare.set_measure(view, state.measure);
            stale
                .then(|| difference_job(compare, render_state))
                .flatten()
        })
        .flatten();
        if let Some(job) = job {
            state.reading_difference(job.spawn());
        }
        let matched = state.matched_shown();
        if state.difference_reading.is_some() {
            ctx.request_repaint_after(Duration::from_millis(30));
        }
        if let Some(copy) = state.poll_difference_read() {
            // A log line, as loads are told: tests read the range.
            eprintln!(
                "compare: difference read ({}{}, range {:.3})",
                copy.measure.name(),
                if matched { ", matched" } else { "" },
                copy.range
            );
        }
    }

    /// Whether the compare is drawn in place of the Song slot's view.
    pub(super) fn compare_covers_view(&self) -> bool {
        self.active == Slot::Song && self.compare.as_ref().is_some_and(|c| c.shown())
    }

    /// The fraction of the compare halves' points drawn while they fill in at rest
    /// (`ui/compare_refine.rs`); None when both are complete.
    pub(super) fn compare_refining(&self, frame: &eframe::Frame) -> Option<f32> {
        // The difference draws no halves: what they left unfinished is not on screen.
        if !self.compare.as_ref().is_some_and(|c| c.side_by_side()) {
            return None;
        }
        let render_state = frame.wgpu_render_state()?;
        let (refining, finished) = CompareResources::write(render_state, |compare, _| {
            (compare.refining(), compare.refine_finished())
        })?;
        if let Some(done) = finished {
            // A log line, as loads are told: tests wait for it (and read from the budget whether
            // an orbit refines again).
            eprintln!(
                "compare: points refined in {} frames, at most {} points a frame, budget now {}",
                done.frames, done.most_points, done.budget
            );
        }
        refining
    }

    /// The compare's two surfaces as one status, where the compare covers the Surface view
    /// (None elsewhere: the active cloud's surface is the one shown). When both halves show
    /// the surface asked for, says so once on stderr with their triangles (a log, as loads are
    /// told; tests compare it with a fresh extraction).
    pub(super) fn compare_surface_status(
        &mut self,
        frame: &eframe::Frame,
    ) -> Option<ExtractionStatus> {
        if self.settings.view != ViewKind::Surface || !self.compare_covers_view() {
            return None;
        }
        let render_state = frame.wgpu_render_state()?;
        let settings = self.settings.surface;
        let Some(surfaces) =
            CompareResources::write(render_state, |compare, _| compare.surface_status(&settings))
                .flatten()
        else {
            // Its grids are still coming: nothing extracted yet.
            return Some(ExtractionStatus::default());
        };
        let state = self.compare.as_mut()?;
        if let [Some(a), Some(b)] = surfaces.triangles
            && !surfaces.status.extracting
        {
            let told = (settings.method, settings.iso_value.to_bits(), a, b);
            if state.tell_surfaces(told) {
                eprintln!(
                    "compare surface: A {a} triangles, B {b} triangles ({}, isovalue {:.3})",
                    settings.method.name(),
                    settings.iso_value
                );
            }
        }
        Some(surfaces.status)
    }

    /// Switches the heard version to `to`, at the same moment of the music, playing if it
    /// was, at `to`'s matching gain; side by side then shows A and `to` (A and the last
    /// version heard when `to` is A).
    pub(super) fn listen(&mut self, to: Listening) {
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        let from_version = state.listening;
        if from_version == to {
            return;
        }
        let Some(track) = state.take_track(to) else {
            return;
        };
        // The same moment of the music in `to` (through each version's alignment to A).
        let mut from = None;
        let alignment = &state.alignment;
        let previous = self.audio.swap_track_at(track, |t| {
            from = Some(t);
            alignment.target_time(from_version, to, t)
        });
        state.put_track(from_version, previous);
        state.heard(to);
        let gain = state.alignment.gain_db(to);
        self.audio.set_gain_db(gain);
        // The window tells stderr, as it does of loads: a log, not a script's input.
        eprintln!(
            "listening to {} at {:.3} s{}; gain {gain:+.1} dB",
            to.letter(),
            self.audio.position_s().unwrap_or(0.0),
            crate::ui::compare_align::switch_words(&state.alignment, from_version, to, from)
        );
    }

    /// The scripted `--press compare=off|side|difference` of tests: the compare's layout;
    /// `measure=density|level|matched`, the difference's measure; and `surface=mt|dc`, the
    /// surface method (as the panel's buttons set them).
    pub(super) fn scripted_compare(&mut self, name: &str) -> bool {
        if let Some(measure) = name.strip_prefix("measure=") {
            let picked = match measure {
                "matched" => None,
                other => match DifferenceMeasure::parse(other) {
                    Some(measure) => Some(measure),
                    None => return false,
                },
            };
            if let Some(state) = self.compare.as_mut() {
                state.pick_measure(picked);
            }
            return true;
        }
        if let Some(method) = name
            .strip_prefix("surface=")
            .and_then(crate::render::surface::SurfaceMethod::parse)
        {
            self.settings.surface.method = method;
            return true;
        }
        let Some(layout) = name.strip_prefix("compare=").and_then(CompareLayout::named) else {
            return false;
        };
        if let Some(state) = self.compare.as_mut() {
            state.set_layout(layout);
            self.motion.request_fit();
        }
        true
    }

    /// Key B: the next version (A -> B -> C -> A), at the same moment of the music.
    pub(super) fn compare_keys(&mut self, ctx: &egui::Context) {
        let Some(state) = self.compare.as_ref() else {
            return;
        };
        if state.clouds.is_none() {
            return;
        }
        if crate::ui::shortcuts::pressed(ctx, crate::ui::shortcuts::Action::SwapAb)
            && let Some(next) = state.next_heard()
        {
            self.listen(next);
            // The panel shows the side now heard (it was drawn before the key was read).
            ctx.request_repaint();
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::Instant;

    use super::*;
    use crate::ui::app::WindowOptions;

    /// Polls `state` until B's load has finished (a minute at most).
    fn loaded(mut state: CompareState) -> CompareState {
        let start = Instant::now();
        while state.poll_load().0 {
            assert!(start.elapsed().as_secs() < 60, "B never finished loading");
            std::thread::sleep(Duration::from_millis(5));
        }
        state
    }

    fn load(path: &Path) -> CompareState {
        let mut state = CompareState::new(path.to_path_buf());
        state.start_loading(Listening::B, |shared| load_b(path.to_path_buf(), shared));
        loaded(state)
    }

    #[test]
    fn b_is_the_cloud_its_file_holds() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format");
        let expected: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(fixtures.join("song_v2.expected.json")).unwrap(),
        )
        .unwrap();
        let state = load(&fixtures.join("song_v2.ply"));
        assert_eq!(state.error, None);
        let b = state.beside_loaded().expect("B loaded");
        assert_eq!(Some(b.len() as u64), expected["point_count"].as_u64());
        assert_eq!(b.path, fixtures.join("song_v2.ply"));
        assert_eq!(state.built_for, None, "the scene is still to be built");
    }

    #[test]
    fn a_b_that_does_not_load_says_which_file_and_shows_nothing() {
        let path = std::env::temp_dir().join(format!(
            "loudscape-compare-b-not-a-cloud-{}.ply",
            std::process::id()
        ));
        std::fs::write(&path, b"this is not a point cloud\n").unwrap();
        let state = load(&path);
        std::fs::remove_file(&path).unwrap();
        let error = state.error.clone().expect("an error");
        assert!(error.contains(&path.display().to_string()), "{error}");
        assert!(state.is_empty() && !state.shown());
    }

    #[test]
    fn a_scripted_layout_refits_the_compare_and_other_presses_pass_through() {
        let mut app = LoudscapeApp::new(
            WindowOptions {
                screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
                ..Default::default()
            },
            None,
        );
        assert!(
            app.scripted_compare("compare=side"),
            "no compare: taken, nothing to do"
        );
        assert!(app.compare.is_none());
        app.compare = Some(CompareState::new(PathBuf::from("b.ply")));
        app.motion.size_view(
            1.6,
            Some(crate::ui::state::view_motion::FitBox {
                min: glam::Vec3::splat(-1.0),
                max: glam::Vec3::splat(1.0),
                half: false,
            }),
        );
        assert!(!app.motion.fit_pending());
        assert!(app.scripted_compare("compare=difference"));
        assert_eq!(
            app.compare.as_ref().map(|c| c.layout),
            Some(CompareLayout::Difference)
        );
        assert!(app.motion.fit_pending(), "the new layout is fitted");
        assert!(app.scripted_compare("measure=matched"));
        assert!(app.compare.as_ref().is_some_and(|c| c.matched));
        assert!(app.scripted_compare("measure=level"));
        assert!(app.compare.as_ref().is_some_and(|c| !c.matched));
        assert!(!app.scripted_compare("measure=loudest"));
        assert!(!app.scripted_compare("compare=sideways"));
        assert!(!app.scripted_compare("Ctrl+S"));
    }
}
