//! The window's A/B compare as it is kept between frames (the `compare` field of
//! `LoudscapeApp`): B's path, its loading thread and loaded cloud, A and B moved onto the union
//! axes, the layout (A only, side by side, difference), the difference measure, which song is
//! heard and the other decoded track, the difference grid's CPU copy for read-outs, the axis
//! labels and the compare dialog; and what the state decides by itself: what a finished load
//! or decode leaves, which error to tell, when the scene is built again and the grids are
//! needed, a new compare's layout, and the panel's choices. What the compare does with the
//! window is `ui/compare_window.rs` (loading B, the GPU scene, key B), `ui/compare_panel.rs`
//! (the side panel's section) and `ui/compare_view.rs` (the two viewports and read-outs).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::task::Poll;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::playback::{PlaybackError, Track};
use crate::render::compare::BuiltGrids;
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::grid::voxelize::VoxelSettings;
use crate::render::scene::ViewKind;
use crate::render::surface::SurfaceMethod;
use crate::ui::labels::AxisLabels;
use crate::ui::state::loading::Shared;

/// How the compare is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum CompareLayout {
    /// The normal view of A alone.
    Off,
    SideBySide,
    Difference,
}

/// Which song is heard (the two sides the alignment maps between).
pub(in crate::ui) use super::alignment::Listening;

/// The window's compare state (one field of `LoudscapeApp`).
pub(in crate::ui) struct CompareState {
    pub(in crate::ui) path: PathBuf,
    pub(in crate::ui) receiver: Option<Receiver<Result<PointCloud, String>>>,
    /// What B's loading thread shares with the window: the extractor's stage and Cancel, shown
    /// as A's are.
    pub(in crate::ui) shared: Shared,
    /// A and B on the union axes, as the GPU scene holds them (for hover and labels).
    pub(in crate::ui) clouds: Option<Arc<(PointCloud, PointCloud)>>,
    pub(in crate::ui) b_loaded: Option<Arc<PointCloud>>,
    /// The Song slot's cloud id the GPU scene was built for.
    pub(in crate::ui) built_for: Option<u64>,
    pub(in crate::ui) layout: CompareLayout,
    pub(in crate::ui) measure: DifferenceMeasure,
    pub(in crate::ui) listening: Listening,
    /// The decoded song not playing now (A's while B plays and the other way round).
    pub(in crate::ui) other_track: Option<Track>,
    pub(in crate::ui) decoding: Option<Receiver<Result<Track, PlaybackError>>>,
    /// The difference's CPU copy for read-outs: the shown grid and the signed values.
    pub(in crate::ui) difference: Option<DifferenceCopy>,
    pub(in crate::ui) error: Option<String>,
    /// The grids being built on a thread, when they are.
    pub(in crate::ui) grid_build: Option<GridBuild>,
    /// The surfaces last told on stderr: method, isovalue bits, A's and B's triangles.
    pub(in crate::ui) surface_told: Option<(SurfaceMethod, u32, u32, u32)>,
    /// The voxel settings whose grids failed to build (not tried again until they change).
    pub(in crate::ui) grids_failed: Option<VoxelSettings>,
    /// The error last told in the window's messages (each new one is told once).
    pub(in crate::ui) error_told: Option<String>,
    pub(in crate::ui) labels: Option<AxisLabels>,
    /// The compare dialog's answer.
    pub(in crate::ui) dialog: Option<Receiver<Option<Vec<PathBuf>>>>,
    /// A and B aligned in time and matched in loudness (`state/alignment.rs`).
    pub(in crate::ui) alignment: super::alignment::CompareAlignment,
}

/// The compare's grids built on a thread (`render::compare::build_grids`): the voxel settings
/// they are built with, where the answer comes, and the frames the window drew meanwhile.
pub(in crate::ui) struct GridBuild {
    pub(in crate::ui) voxels: VoxelSettings,
    pub(in crate::ui) receiver: Receiver<Result<BuiltGrids, String>>,
    pub(in crate::ui) frames: u32,
    pub(in crate::ui) started: std::time::Instant,
}

/// What a frame does about the compare's grids ([`CompareState::grid_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum GridStep {
    /// Built for the settings shown: draw them.
    Ready,
    /// None for these settings and none coming: start a build.
    Start,
    /// A build for these settings runs: come back.
    Wait,
    /// The build for these settings failed (its error is told): nothing to do.
    Failed,
}

/// The difference's CPU copy for read-outs: the shown grid, the signed values per voxel and per
/// column, and the measure and range they were read for.
pub(in crate::ui) struct DifferenceCopy {
    pub(in crate::ui) shown: Field,
    pub(in crate::ui) difference: Vec<f32>,
    pub(in crate::ui) columns: Vec<f32>,
    pub(in crate::ui) measure: DifferenceMeasure,
    pub(in crate::ui) range: f32,
}

impl CompareState {
    pub(in crate::ui) fn new(path: PathBuf) -> Self {
        Self {
            path,
            receiver: None,
            shared: Shared::default(),
            clouds: None,
            b_loaded: None,
            built_for: None,
            layout: CompareLayout::SideBySide,
            measure: DifferenceMeasure::Density,
            listening: Listening::A,
            other_track: None,
            decoding: None,
            difference: None,
            error: None,
            error_told: None,
            grid_build: None,
            grids_failed: None,
            surface_told: None,
            labels: None,
            dialog: None,
            alignment: Default::default(),
        }
    }

    /// Whether the view shows the compare now.
    pub(in crate::ui) fn shown(&self) -> bool {
        self.layout != CompareLayout::Off && self.clouds.is_some()
    }

    pub(in crate::ui) fn side_by_side(&self) -> bool {
        self.layout == CompareLayout::SideBySide && self.clouds.is_some()
    }

    /// A compare with `path` started while `old` was there: it keeps the old one's measure and
    /// layout, "A only" turning to side by side (B was asked for to be seen).
    pub(in crate::ui) fn after(old: Option<&CompareState>, path: PathBuf) -> Self {
        let mut state = Self::new(path);
        if let Some(old) = old {
            state.layout = match old.layout {
                CompareLayout::Off => CompareLayout::SideBySide,
                other => other,
            };
            state.measure = old.measure;
        }
        state
    }

    /// Takes B's cloud (or why it failed) once its load has finished; true while it loads.
    pub(in crate::ui) fn poll_load(&mut self) -> bool {
        let Some(receiver) = &self.receiver else {
            return false;
        };
        match receiver.try_recv() {
            Ok(Ok(cloud)) => {
                self.b_loaded = Some(Arc::new(cloud));
                // A new B: the scene is built again.
                self.built_for = None;
            }
            Ok(Err(message)) => self.error = Some(message),
            Err(TryRecvError::Empty) => return true,
            Err(TryRecvError::Disconnected) => {
                self.error = Some(format!("{}: the loader stopped", self.path.display()));
            }
        }
        self.receiver = None;
        false
    }

    /// Whether B's load was cancelled (its row's Cancel).
    pub(in crate::ui) fn cancelled(&self) -> bool {
        self.shared
            .cancel
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Takes B's decoded audio (or why it failed) once decoded; true while it decodes.
    pub(in crate::ui) fn poll_decoding(&mut self) -> bool {
        let Some(receiver) = &self.decoding else {
            return false;
        };
        match receiver.try_recv() {
            Ok(Ok(track)) => self.other_track = Some(track),
            Ok(Err(e)) => self.error = Some(format!("B's audio: {e}")),
            Err(TryRecvError::Empty) => return true,
            Err(TryRecvError::Disconnected) => {}
        }
        self.decoding = None;
        false
    }

    /// What B's cloud says about its input, as the window tells it: `B NAME: MESSAGE` (NAME the
    /// file asked for, as the status overlay names A's; a timeline's song where one is named).
    pub(in crate::ui) fn b_warning_lines(&self) -> Vec<String> {
        let Some(b) = &self.b_loaded else {
            return Vec::new();
        };
        let name = self.path.file_name().map_or_else(
            || self.path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        b.warnings()
            .iter()
            .map(|w| format!("B {}: {}", w.path.as_deref().unwrap_or(&name), w.message))
            .collect()
    }

    /// The error to tell the window's messages: each new one once.
    pub(in crate::ui) fn error_to_tell(&mut self) -> Option<String> {
        if self.error == self.error_told {
            return None;
        }
        self.error_told = self.error.clone();
        self.error.clone()
    }

    /// Whether the GPU scene must be built for the Song slot's cloud `song_id` (B or A changed
    /// since it was built); then it counts as built for it and the old difference is dropped.
    pub(in crate::ui) fn rebuild_for(&mut self, song_id: u64) -> bool {
        if self.built_for == Some(song_id) {
            return false;
        }
        self.built_for = Some(song_id);
        self.difference = None;
        // A build for the old scene has nothing to give the new one.
        self.grid_build = None;
        self.grids_failed = None;
        true
    }

    /// What this frame does about the grids, `built` saying whether the scene has them for
    /// `voxels`: a build for other settings is dropped (its answer is not waited for).
    pub(in crate::ui) fn grid_step(&mut self, voxels: &VoxelSettings, built: bool) -> GridStep {
        if built {
            return GridStep::Ready;
        }
        if let Some(build) = &mut self.grid_build {
            if build.voxels == *voxels {
                build.frames += 1;
                return GridStep::Wait;
            }
            self.grid_build = None;
        }
        if self.grids_failed == Some(*voxels) {
            return GridStep::Failed;
        }
        GridStep::Start
    }

    /// Waits for a build started on a thread with `voxels`.
    pub(in crate::ui) fn building(
        &mut self,
        voxels: VoxelSettings,
        receiver: Receiver<Result<BuiltGrids, String>>,
    ) {
        self.grids_failed = None;
        self.grid_build = Some(GridBuild {
            voxels,
            receiver,
            frames: 0,
            started: std::time::Instant::now(),
        });
    }

    /// Whether grids are being built on a thread.
    pub(in crate::ui) fn grids_building(&self) -> bool {
        self.grid_build.is_some()
    }

    /// The build's answer once it came, with the frames drawn while it ran and how long it
    /// took; a failure (or a
    /// thread that ended without answering) is kept as the compare's error and not tried again
    /// for the same settings.
    pub(in crate::ui) fn poll_grid_build(
        &mut self,
    ) -> Option<(BuiltGrids, u32, std::time::Duration)> {
        let build = self.grid_build.as_ref()?;
        let answer = match build.receiver.try_recv() {
            Ok(answer) => answer,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => Err("the compare grids' build stopped".into()),
        };
        let build = self.grid_build.take()?;
        match answer {
            Ok(built) => Some((built, build.frames, build.started.elapsed())),
            Err(message) => {
                self.grids_failed = Some(build.voxels);
                self.error = Some(message);
                None
            }
        }
    }

    /// Whether what is shown draws from the voxel grids: the difference, or side by side in
    /// the Volume and Surface views.
    pub(in crate::ui) fn needs_grids(&self, view: ViewKind) -> bool {
        self.clouds.is_some()
            && match self.layout {
                CompareLayout::Off => false,
                CompareLayout::SideBySide => view != ViewKind::Points,
                CompareLayout::Difference => true,
            }
    }

    /// Whether the difference's CPU copy is missing or was read for another measure.
    pub(in crate::ui) fn difference_stale(&self) -> bool {
        self.difference
            .as_ref()
            .is_none_or(|d| d.measure != self.measure)
    }

    /// Whether the panel's `side` button can be pressed: the side heard, or the other once its
    /// audio is decoded.
    pub(in crate::ui) fn can_listen(&self, side: Listening) -> bool {
        self.other_track.is_some() || self.listening == side
    }

    /// The compare dialog opened: the view shows A alone until B is picked.
    pub(in crate::ui) fn await_dialog(&mut self, receiver: Receiver<Option<Vec<PathBuf>>>) {
        self.layout = CompareLayout::Off;
        self.dialog = Some(receiver);
    }

    /// The file picked in the compare dialog once it closed (`None`: nothing picked, or no
    /// dialog); pending while it is open.
    pub(in crate::ui) fn poll_dialog(&mut self) -> Poll<Option<PathBuf>> {
        let Some(receiver) = &self.dialog else {
            return Poll::Ready(None);
        };
        let picked = match receiver.try_recv() {
            Ok(picked) => picked.and_then(|paths| paths.into_iter().next()),
            Err(TryRecvError::Disconnected) => None,
            Err(TryRecvError::Empty) => return Poll::Pending,
        };
        self.dialog = None;
        Poll::Ready(picked)
    }
}

impl CompareLayout {
    /// The layout a scripted `--press compare=NAME` names (`off`, `side`, `difference`).
    pub(in crate::ui) fn named(name: &str) -> Option<Self> {
        match name {
            "off" => Some(CompareLayout::Off),
            "side" => Some(CompareLayout::SideBySide),
            "difference" => Some(CompareLayout::Difference),
            _ => None,
        }
    }
}

/// B's path as typed in the panel's field, when Enter was pressed there with something typed.
pub(in crate::ui) fn typed_path(field: &str, entered: bool) -> Option<PathBuf> {
    let path = field.trim();
    (entered && !path.is_empty()).then(|| PathBuf::from(path))
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc::channel;

    use super::*;
    use crate::data::cloud::DataMode;

    fn cloud(points: usize) -> PointCloud {
        PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(points, 7),
            DataMode::Song,
        )
    }

    fn loading(
        path: &str,
    ) -> (
        CompareState,
        std::sync::mpsc::Sender<Result<PointCloud, String>>,
    ) {
        let mut state = CompareState::new(PathBuf::from(path));
        let (sender, receiver) = channel();
        state.receiver = Some(receiver);
        (state, sender)
    }

    #[test]
    fn a_finished_load_leaves_b_and_asks_for_a_new_scene() {
        let (mut state, sender) = loading("b.ply");
        state.built_for = Some(3);
        assert!(state.poll_load(), "nothing sent yet: still loading");
        assert!(state.receiver.is_some());
        sender.send(Ok(cloud(50))).unwrap();
        assert!(!state.poll_load());
        assert!(state.receiver.is_none());
        assert_eq!(state.b_loaded.as_ref().map(|b| b.len()), Some(50));
        assert_eq!(
            state.built_for, None,
            "the scene is built again for the new B"
        );
        assert_eq!(state.error, None);
        assert!(!state.poll_load(), "nothing more to take");
    }

    /// B's warnings (truncated, clipped...) are told as A's are, naming the file asked for
    /// (for audio B's cloud is a cache file of no meaning to the user).
    #[test]
    fn bs_warnings_are_told_by_the_name_it_was_asked_by() {
        let (mut state, sender) = loading("/music/b_louder.ogg");
        assert!(state.b_warning_lines().is_empty(), "nothing loaded yet");
        let mut b = cloud(50);
        b.meta.warnings.push(crate::data::cloud::CloudWarning {
            kind: "clipping".into(),
            message: "clipped: 3 run(s)".into(),
            path: None,
        });
        sender.send(Ok(b)).unwrap();
        assert!(!state.poll_load());
        assert_eq!(
            state.b_warning_lines(),
            ["B b_louder.ogg: clipped: 3 run(s)"]
        );
    }

    #[test]
    fn a_failed_or_abandoned_load_leaves_an_error_that_is_told_once() {
        let (mut state, sender) = loading("b.ply");
        sender
            .send(Err("b.ply: not a loudscape cloud".into()))
            .unwrap();
        assert!(!state.poll_load());
        assert!(state.b_loaded.is_none() && state.receiver.is_none());
        assert_eq!(
            state.error_to_tell().as_deref(),
            Some("b.ply: not a loudscape cloud")
        );
        assert_eq!(state.error_to_tell(), None, "told once");

        let (mut state, sender) = loading("gone.ogg");
        drop(sender);
        assert!(!state.poll_load());
        assert_eq!(
            state.error.as_deref(),
            Some("gone.ogg: the loader stopped"),
            "a loader that died names the file"
        );
        state.error = Some("another".into());
        assert_eq!(state.error_to_tell().as_deref(), Some("another"));
        state.error = None;
        assert_eq!(state.error_to_tell(), None, "no error has nothing to tell");
    }

    #[test]
    fn failed_audio_is_an_error_and_a_dropped_decoder_only_stops_waiting() {
        let mut state = CompareState::new(PathBuf::from("b.ogg"));
        let (sender, receiver) = channel();
        state.decoding = Some(receiver);
        assert!(state.poll_decoding());
        sender
            .send(Err(PlaybackError::Open {
                path: PathBuf::from("b.ogg"),
                reason: "truncated".into(),
            }))
            .unwrap();
        assert!(!state.poll_decoding());
        assert!(state.decoding.is_none() && state.other_track.is_none());
        let error = state.error.clone().unwrap_or_default();
        assert!(
            error.starts_with("B's audio: b.ogg") && error.contains("truncated"),
            "{error}"
        );

        let mut state = CompareState::new(PathBuf::from("b.ogg"));
        let (sender, receiver) = channel::<Result<Track, PlaybackError>>();
        state.decoding = Some(receiver);
        drop(sender);
        assert!(!state.poll_decoding());
        assert!(state.decoding.is_none() && state.error.is_none());
    }

    #[test]
    fn a_new_compare_keeps_the_measure_and_shows_b() {
        let fresh = CompareState::after(None, PathBuf::from("b.ply"));
        assert_eq!(fresh.layout, CompareLayout::SideBySide);
        assert_eq!(fresh.measure, DifferenceMeasure::Density);
        assert_eq!(fresh.path, PathBuf::from("b.ply"));

        let mut old = CompareState::new(PathBuf::from("old.ply"));
        old.layout = CompareLayout::Off;
        old.measure = DifferenceMeasure::ALL[1];
        let next = CompareState::after(Some(&old), PathBuf::from("b.ply"));
        assert_eq!(
            next.layout,
            CompareLayout::SideBySide,
            "A only turns to B beside it"
        );
        assert_eq!(next.measure, DifferenceMeasure::ALL[1]);
        assert!(next.b_loaded.is_none() && next.clouds.is_none());

        old.layout = CompareLayout::Difference;
        let next = CompareState::after(Some(&old), PathBuf::from("b.ply"));
        assert_eq!(next.layout, CompareLayout::Difference);
    }

    #[test]
    fn the_scene_is_built_once_per_song_and_the_grids_only_where_drawn() {
        let mut state = CompareState::new(PathBuf::from("b.ply"));
        assert!(
            !state.needs_grids(ViewKind::Volume),
            "nothing to compare yet"
        );
        assert!(!state.shown() && !state.side_by_side());
        state.clouds = Some(Arc::new((cloud(10), cloud(12))));
        assert!(state.rebuild_for(1));
        assert!(!state.rebuild_for(1), "built for this song already");
        assert!(state.rebuild_for(2), "another song in A");

        assert!(state.shown() && state.side_by_side());
        assert!(!state.needs_grids(ViewKind::Points));
        assert!(state.needs_grids(ViewKind::Volume));
        assert!(state.needs_grids(ViewKind::Surface));
        state.layout = CompareLayout::Difference;
        assert!(state.needs_grids(ViewKind::Points));
        assert!(state.shown() && !state.side_by_side());
        state.layout = CompareLayout::Off;
        assert!(!state.needs_grids(ViewKind::Volume));
        assert!(!state.shown());
    }

    #[test]
    fn grids_are_built_once_per_settings_and_a_failure_is_not_retried() {
        let mut state = CompareState::new(PathBuf::from("b.ply"));
        let voxels = VoxelSettings::default();
        assert_eq!(state.grid_step(&voxels, true), GridStep::Ready);
        assert_eq!(state.grid_step(&voxels, false), GridStep::Start);
        let (sender, receiver) = channel();
        state.building(voxels, receiver);
        assert!(state.grids_building());
        assert_eq!(state.grid_step(&voxels, false), GridStep::Wait);
        assert_eq!(state.grid_step(&voxels, false), GridStep::Wait);
        assert!(state.poll_grid_build().is_none(), "nothing sent yet");
        assert_eq!(state.grid_build.as_ref().map(|b| b.frames), Some(2));
        sender
            .send(Err("b.ply: voxelizing: too large".into()))
            .unwrap();
        assert!(state.poll_grid_build().is_none());
        assert!(!state.grids_building());
        assert_eq!(state.error.as_deref(), Some("b.ply: voxelizing: too large"));
        assert_eq!(
            state.grid_step(&voxels, false),
            GridStep::Failed,
            "not started again every frame"
        );
        let mut other = voxels;
        other.smoothing_sigma = Some(other.smoothing_for(crate::data::cloud::DataMode::Song) + 0.5);
        assert_eq!(state.grid_step(&other, false), GridStep::Start);

        // A build for other settings is dropped; a thread that died is an error.
        let (sender, receiver) = channel();
        state.building(voxels, receiver);
        assert_eq!(state.grid_step(&other, false), GridStep::Start);
        assert!(!state.grids_building());
        drop(sender);
        let (sender, receiver) = channel::<Result<BuiltGrids, String>>();
        state.building(other, receiver);
        drop(sender);
        assert!(state.poll_grid_build().is_none());
        assert!(
            state
                .error
                .as_deref()
                .is_some_and(|e| e.contains("stopped")),
            "{:?}",
            state.error
        );

        // A new scene drops the build of the old one.
        let (_sender, receiver) = channel();
        state.building(voxels, receiver);
        assert!(state.rebuild_for(9));
        assert!(!state.grids_building());
    }

    #[test]
    fn the_difference_copy_is_read_again_for_another_measure() {
        let mut state = CompareState::new(PathBuf::from("b.ply"));
        assert!(state.difference_stale(), "none read yet");
        state.difference = Some(DifferenceCopy {
            shown: Field {
                dims: glam::UVec3::ONE,
                box_min: glam::Vec3::ZERO,
                box_max: glam::Vec3::ONE,
                density: vec![0.0],
                hp_mean: vec![0.0],
            },
            difference: vec![0.0],
            columns: vec![0.0],
            measure: state.measure,
            range: 1.0,
        });
        assert!(!state.difference_stale());
        state.measure = DifferenceMeasure::ALL[1];
        assert!(state.difference_stale());
        state.measure = DifferenceMeasure::ALL[0];
        state.built_for = Some(1);
        assert!(state.rebuild_for(2));
        assert!(
            state.difference_stale(),
            "a new scene drops the old difference"
        );
    }

    #[test]
    fn the_panel_starts_b_from_the_field_or_the_dialog() {
        assert_eq!(typed_path("  b.ogg ", true), Some(PathBuf::from("b.ogg")));
        assert_eq!(typed_path("b.ogg", false), None, "only on Enter");
        assert_eq!(typed_path("   ", true), None, "nothing typed");

        let mut state = CompareState::new(PathBuf::new());
        assert_eq!(state.poll_dialog(), Poll::Ready(None), "no dialog");
        let (sender, receiver) = channel();
        state.await_dialog(receiver);
        assert_eq!(state.layout, CompareLayout::Off, "A alone while picking");
        assert_eq!(state.poll_dialog(), Poll::Pending);
        sender
            .send(Some(vec![PathBuf::from("b.ply"), PathBuf::from("c.ply")]))
            .unwrap();
        assert_eq!(
            state.poll_dialog(),
            Poll::Ready(Some(PathBuf::from("b.ply")))
        );
        assert!(state.dialog.is_none());

        let (sender, receiver) = channel();
        state.await_dialog(receiver);
        sender.send(None).unwrap();
        assert_eq!(state.poll_dialog(), Poll::Ready(None), "cancelled");
    }

    #[test]
    fn the_panel_switches_sides_only_to_decoded_audio() {
        let state = CompareState::new(PathBuf::from("b.ply"));
        assert!(state.can_listen(Listening::A), "the side heard");
        assert!(!state.can_listen(Listening::B), "B's audio not decoded");
        assert_eq!(Listening::A.other(), Listening::B);
        assert_eq!(Listening::B.other(), Listening::A);
    }

    #[test]
    fn scripted_layouts_are_named_as_the_tests_press_them() {
        assert_eq!(CompareLayout::named("off"), Some(CompareLayout::Off));
        assert_eq!(
            CompareLayout::named("side"),
            Some(CompareLayout::SideBySide)
        );
        assert_eq!(
            CompareLayout::named("difference"),
            Some(CompareLayout::Difference)
        );
        assert_eq!(CompareLayout::named("sides"), None);
    }
}
