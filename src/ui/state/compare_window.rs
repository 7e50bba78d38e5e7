//! The window's compare as it is kept between frames (the `compare` field of
//! `LoudscapeApp`): the versions compared with A (B, C... up to 8 in all), each with its
//! loading thread, loaded cloud and decoded track; A and the version shown beside it moved
//! onto the union axes, the layout (A only, side by side, difference), the difference measure,
//! which version is heard, the difference grid's CPU copy for read-outs, the axis labels and
//! the compare dialog; and what the state decides by itself: what a finished load or decode
//! leaves, which error to tell, when the scene is built again and the grids are needed, a
//! version added, and the panel's choices. What the compare does with the window is
//! `ui/compare_window.rs` (loading a version, the GPU scene, key B), `ui/compare_panel.rs`
//! (the side panel's section) and `ui/compare_view.rs` (the two viewports and read-outs).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::task::Poll;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::playback::{PlaybackError, Track};
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::grid::voxelize::VoxelSettings;
use crate::render::scene::{RenderSettings, ViewKind};
use crate::render::surface::SurfaceMethod;
use crate::ui::labels::AxisLabels;
use crate::ui::state::loading::Shared;

/// The status line while the compare's grids are built.
pub(in crate::ui) const GRIDS_BUSY: &str = "building the compare grids…";

/// What the Difference view says while its read-outs' copy is read back.
pub(in crate::ui) const DIFFERENCE_BUSY: &str = "reading the difference for the read-outs…";

/// How the compare is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum CompareLayout {
    /// The normal view of A alone.
    Off,
    SideBySide,
    Difference,
}

/// Which version is heard (0 is A; the versions the alignment maps between).
pub(in crate::ui) use super::alignment::{Listening, MAX_VERSIONS};
pub(in crate::ui) use super::compare_grids::{GridBuild, GridStep};

/// One version compared with A: its file, its loading thread (whose stage and Cancel the
/// window shows as A's), its cloud once loaded, and its decoded audio while another version
/// plays.
pub(in crate::ui) struct Version {
    pub(in crate::ui) path: PathBuf,
    pub(in crate::ui) receiver: Option<Receiver<Result<PointCloud, String>>>,
    pub(in crate::ui) shared: Shared,
    pub(in crate::ui) loaded: Option<Arc<PointCloud>>,
    /// Its decoded song while not playing (taken by the player while it plays).
    pub(in crate::ui) track: Option<Track>,
    pub(in crate::ui) decoding: Option<Receiver<Result<Track, PlaybackError>>>,
}

impl Version {
    pub(in crate::ui) fn new(path: PathBuf) -> Self {
        Self {
            path,
            receiver: None,
            shared: Shared::default(),
            loaded: None,
            track: None,
            decoding: None,
        }
    }

    /// The file's name as the user asked for it (for audio the cloud is a cache file).
    pub(in crate::ui) fn name(&self) -> String {
        self.path.file_name().map_or_else(
            || self.path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    }
}

/// The window's compare state (one field of `LoudscapeApp`).
pub(in crate::ui) struct CompareState {
    /// B, C...: the versions compared with A, in the order they were asked for.
    pub(in crate::ui) versions: Vec<Version>,
    /// The version drawn beside A (1 is B): the one heard, or the last one heard while A is.
    pub(in crate::ui) beside: Listening,
    /// A and the version beside it on the union axes, as the GPU scene holds them (for hover
    /// and labels).
    pub(in crate::ui) clouds: Option<Arc<(PointCloud, PointCloud)>>,
    /// The Song slot's cloud id, the version beside A and whether its levels were matched to
    /// A's loudness, as the GPU scene was built.
    pub(in crate::ui) built_for: Option<(u64, Listening, bool)>,
    pub(in crate::ui) layout: CompareLayout,
    pub(in crate::ui) measure: DifferenceMeasure,
    /// The difference's "matched" measure: level-weighted, with the version's levels shifted
    /// by its matching gain against A (what remains is dynamics and tonal balance).
    pub(in crate::ui) matched: bool,
    pub(in crate::ui) listening: Listening,
    /// A's decoded song while another version plays.
    pub(in crate::ui) a_track: Option<Track>,
    /// The difference's CPU copy for read-outs: the shown grid and the signed values.
    pub(in crate::ui) difference: Option<DifferenceCopy>,
    /// The difference's read-back running on a thread (the GPU's copy waited for there, not
    /// in a frame), when it runs.
    pub(in crate::ui) difference_reading: Option<Receiver<Option<DifferenceCopy>>>,
    pub(in crate::ui) error: Option<String>,
    /// The grids being built on a thread, when they are.
    pub(in crate::ui) grid_build: Option<GridBuild>,
    /// The scene being prepared on a thread (`ui/compare_scene.rs`), when it is.
    pub(in crate::ui) scene_build: Option<super::compare_scene::SceneBuild>,
    /// Whether the GPU scene holds grids (for some voxel settings): without them the halves
    /// draw their points in every view.
    pub(in crate::ui) has_grids: bool,
    /// The surfaces last told on stderr: method, isovalue bits, A's and B's triangles.
    pub(in crate::ui) surface_told: Option<(SurfaceMethod, u32, u32, u32)>,
    /// The voxel settings whose grids failed to build (not tried again until they change).
    pub(in crate::ui) grids_failed: Option<VoxelSettings>,
    /// Whether the view asked for still waits for its grids (a scene just rebuilt, a build
    /// not yet started or running): a scripted screenshot waits for it.
    pub(in crate::ui) grids_pending: bool,
    /// The error last told in the window's messages (each new one is told once).
    pub(in crate::ui) error_told: Option<String>,
    pub(in crate::ui) labels: Option<AxisLabels>,
    /// The compare dialog's answer.
    pub(in crate::ui) dialog: Option<Receiver<Option<Vec<PathBuf>>>>,
    /// A and B aligned in time and matched in loudness (`state/alignment.rs`).
    pub(in crate::ui) alignment: super::alignment::CompareAlignment,
    /// The camera came back with the compare (a reopened window): the scenes built while A
    /// arrives, and built again for the same A (the alignment coming, a nudge), keep it, as the
    /// window was left, instead of fitting the compare.
    pub(in crate::ui) keep_camera: bool,
    /// The whole A's song id the restored camera is kept for (set by its first scene).
    kept_for: Option<u64>,
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
    /// A compare with no version yet (the dialog is open).
    pub(in crate::ui) fn empty() -> Self {
        Self {
            versions: Vec::new(),
            beside: Listening::B,
            clouds: None,
            built_for: None,
            layout: CompareLayout::SideBySide,
            measure: DifferenceMeasure::Density,
            matched: false,
            listening: Listening::A,
            a_track: None,
            difference: None,
            difference_reading: None,
            error: None,
            error_told: None,
            grid_build: None,
            scene_build: None,
            has_grids: false,
            grids_failed: None,
            grids_pending: false,
            surface_told: None,
            labels: None,
            dialog: None,
            alignment: Default::default(),
            keep_camera: false,
            kept_for: None,
        }
    }

    /// Whether the view shows the compare now.
    pub(in crate::ui) fn shown(&self) -> bool {
        self.layout != CompareLayout::Off && self.clouds.is_some()
    }

    pub(in crate::ui) fn side_by_side(&self) -> bool {
        self.layout == CompareLayout::SideBySide && self.clouds.is_some()
    }

    /// A compare of A with the version at `path` (B).
    #[cfg(test)]
    pub(in crate::ui) fn new(path: PathBuf) -> Self {
        let mut state = Self::empty();
        state.versions.push(Version::new(path));
        state
    }

    /// Adds the version at `path` (C after B...); "A only" turns to side by side (it was asked
    /// for to be seen). B stays beside A (the panel shows a version added by hand:
    /// [`CompareState::show`]). Its index, or why not: a version already compared, or
    /// [`MAX_VERSIONS`] reached.
    pub(in crate::ui) fn add(&mut self, path: PathBuf) -> Result<Listening, String> {
        if let Some(i) = self.versions.iter().position(|v| v.path == path) {
            return Err(format!(
                "{} is already compared (as {})",
                path.display(),
                Listening(i + 1).letter()
            ));
        }
        if self.count() >= MAX_VERSIONS {
            return Err(format!(
                "{}: at most {MAX_VERSIONS} versions are compared at once",
                path.display()
            ));
        }
        self.versions.push(Version::new(path));
        let added = Listening(self.versions.len());
        if self.layout == CompareLayout::Off {
            self.layout = CompareLayout::SideBySide;
        }
        Ok(added)
    }

    /// Shows the compare as `layout` (the panel's buttons, a scripted press).
    pub(in crate::ui) fn set_layout(&mut self, layout: CompareLayout) {
        self.layout = layout;
    }

    /// Version `version`'s cloud is loaded on a thread that answers on what `load` returns
    /// (given the version's shared stage and Cancel).
    pub(in crate::ui) fn start_loading(
        &mut self,
        version: Listening,
        load: impl FnOnce(Shared) -> Receiver<Result<PointCloud, String>>,
    ) {
        if let Some(v) = version
            .0
            .checked_sub(1)
            .and_then(|i| self.versions.get_mut(i))
        {
            v.receiver = Some(load(v.shared.clone()));
        }
    }

    /// Decodes the audio of `version` (for key B) with `decode` when it has loaded, is not
    /// heard and has no track yet.
    pub(in crate::ui) fn decode_audio_of(
        &mut self,
        version: Listening,
        decode: impl FnOnce(&PointCloud) -> Receiver<Result<Track, PlaybackError>>,
    ) {
        if self.listening == version {
            return;
        }
        if let Some(v) = version
            .0
            .checked_sub(1)
            .and_then(|i| self.versions.get_mut(i))
            && let Some(cloud) = &v.loaded
            && v.track.is_none()
        {
            v.decoding = Some(decode(cloud));
        }
    }

    /// The GPU scene holds A and the version beside it as `clouds` (on the union axes), with
    /// these axis labels.
    pub(in crate::ui) fn scene_built(
        &mut self,
        clouds: Arc<(PointCloud, PointCloud)>,
        labels: AxisLabels,
    ) {
        self.labels = Some(labels);
        self.clouds = Some(clouds);
        self.error = None;
    }

    /// The scene could not be built (`error`: the clouds have no union axes).
    pub(in crate::ui) fn scene_failed(&mut self, error: String) {
        self.clouds = None;
        self.has_grids = false;
        self.error = Some(error);
    }

    /// The window's camera was restored with this compare (a reopened window).
    pub(in crate::ui) fn camera_restored(&mut self) {
        self.keep_camera = true;
    }

    /// Whether the scene built now for A's song `song` (`first`: the first for it) is fitted:
    /// not while a restored camera is kept, which lasts while A's points so far stand in (not
    /// `whole`) and for every scene of the whole A that came first (built again when the
    /// alignment comes, say), until another song is in A.
    pub(in crate::ui) fn fit_scene(&mut self, first: bool, whole: bool, song: u64) -> bool {
        if self.keep_camera {
            match self.kept_for {
                None if !whole => return false,
                None => {
                    self.kept_for = Some(song);
                    return false;
                }
                Some(kept) if kept == song => return false,
                Some(_) => {
                    self.keep_camera = false;
                    self.kept_for = None;
                }
            }
        }
        first
    }

    /// Builds the scene again on the next frame (an alignment came, a version was nudged).
    pub(in crate::ui) fn rebuild_scene(&mut self) {
        self.built_for = None;
    }

    /// The difference's CPU copy is stale (grids installed or a build started): read again.
    pub(in crate::ui) fn forget_difference(&mut self) {
        self.difference = None;
        self.difference_reading = None;
    }

    /// The GPU scene holds the grids built on a thread now: the halves draw from them, and the
    /// difference's CPU copy is read again.
    pub(in crate::ui) fn grids_installed(&mut self) {
        self.has_grids = true;
        self.forget_difference();
    }

    /// Waits for the difference's read-back on a thread that answers on `receiver`.
    pub(in crate::ui) fn reading_difference(&mut self, receiver: Receiver<Option<DifferenceCopy>>) {
        self.difference_reading = Some(receiver);
    }

    /// The read-back's answer once it came (`Some(None)`: it could not be read, or the thread
    /// ended without answering); it is kept as the read-outs' copy.
    pub(in crate::ui) fn poll_difference_read(&mut self) -> Option<&DifferenceCopy> {
        let receiver = self.difference_reading.as_ref()?;
        let copy = match receiver.try_recv() {
            Ok(copy) => copy,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => None,
        };
        self.difference_reading = None;
        self.difference = copy;
        self.difference.as_ref()
    }

    /// Whether the view asked for still waits for its grids.
    pub(in crate::ui) fn set_grids_pending(&mut self, pending: bool) {
        self.grids_pending = pending;
    }

    /// Whether the surfaces `told` (method, isovalue bits, A's and B's triangles) are new to
    /// stderr; they are kept as told.
    pub(in crate::ui) fn tell_surfaces(&mut self, told: (SurfaceMethod, u32, u32, u32)) -> bool {
        let new = self.surface_told != Some(told);
        self.surface_told = Some(told);
        new
    }

    /// `to` is heard now; side by side shows A and `to` (A and the last version heard when
    /// `to` is A).
    pub(in crate::ui) fn heard(&mut self, to: Listening) {
        self.listening = to;
        if to != Listening::A {
            self.beside = to;
        }
    }

    /// Shows `version` beside A, unless another version is heard (side by side shows A and
    /// the version heard).
    pub(in crate::ui) fn show(&mut self, version: Listening) {
        if self.listening == Listening::A && self.version(version).is_some() {
            self.beside = version;
        }
    }

    /// The version `version` (1 is B; None for A or one not there).
    pub(in crate::ui) fn version(&self, version: Listening) -> Option<&Version> {
        version.0.checked_sub(1).and_then(|i| self.versions.get(i))
    }

    /// The versions, A included.
    pub(in crate::ui) fn count(&self) -> usize {
        self.versions.len() + 1
    }

    /// The version drawn beside A, when it has loaded.
    pub(in crate::ui) fn beside_loaded(&self) -> Option<Arc<PointCloud>> {
        self.version(self.beside)?.loaded.clone()
    }

    /// Whether any version still loads.
    pub(in crate::ui) fn loading(&self) -> bool {
        self.versions.iter().any(|v| v.receiver.is_some())
    }

    /// Takes each version's cloud (or why it failed) once its load has finished: a version
    /// that failed is told as the compare's error and leaves the list (as does one whose load
    /// was cancelled, without an error). Returns whether any still loads and the versions
    /// that loaded now.
    pub(in crate::ui) fn poll_load(&mut self) -> (bool, Vec<Listening>) {
        let mut loaded_now = Vec::new();
        let mut failed = Vec::new();
        for (i, version) in self.versions.iter_mut().enumerate() {
            let Some(receiver) = &version.receiver else {
                continue;
            };
            match receiver.try_recv() {
                Ok(Ok(cloud)) => {
                    version.loaded = Some(Arc::new(cloud));
                    loaded_now.push(Listening(i + 1));
                }
                Ok(Err(message)) => {
                    failed.push(i);
                    if !cancelled(&version.shared) {
                        self.error = Some(message);
                    }
                }
                Err(TryRecvError::Empty) => continue,
                Err(TryRecvError::Disconnected) => {
                    failed.push(i);
                    self.error = Some(format!("{}: the loader stopped", version.path.display()));
                }
            }
            version.receiver = None;
        }
        if loaded_now.contains(&self.beside) {
            // The version beside A has come: the scene is built again.
            self.built_for = None;
        }
        for &i in failed.iter().rev() {
            self.remove(Listening(i + 1));
            for v in &mut loaded_now {
                if v.0 > i + 1 {
                    v.0 -= 1;
                }
            }
        }
        (self.loading(), loaded_now)
    }

    /// Drops `version` (one that did not load; never the one heard): the later versions move
    /// up a letter, and the one beside A stays the same file where it can.
    fn remove(&mut self, version: Listening) {
        let Some(i) = version.0.checked_sub(1) else {
            return;
        };
        if i >= self.versions.len() || self.listening == version {
            return;
        }
        self.versions.remove(i);
        if self.listening.0 > version.0 {
            self.listening.0 -= 1;
        }
        if self.beside.0 > version.0 {
            self.beside.0 -= 1;
        } else if self.beside == version {
            self.beside = Listening::B;
            self.built_for = None;
        }
        // The nudges were of another list (the comparison is asked again, compare_align.rs).
        self.alignment.nudges_s.clear();
    }

    /// Whether nothing is left to compare (every version failed or was cancelled).
    pub(in crate::ui) fn is_empty(&self) -> bool {
        self.versions.is_empty()
    }

    /// Takes each version's decoded audio (or why it failed) once decoded; true while any
    /// decodes.
    pub(in crate::ui) fn poll_decoding(&mut self) -> bool {
        let mut any = false;
        for (i, version) in self.versions.iter_mut().enumerate() {
            let Some(receiver) = &version.decoding else {
                continue;
            };
            match receiver.try_recv() {
                Ok(Ok(track)) => version.track = Some(track),
                Ok(Err(e)) => {
                    self.error = Some(format!("{}'s audio: {e}", Listening(i + 1).letter()));
                }
                Err(TryRecvError::Empty) => {
                    any = true;
                    continue;
                }
                Err(TryRecvError::Disconnected) => {}
            }
            version.decoding = None;
        }
        any
    }

    /// What `version`'s cloud says about its input, as the window tells it: `B NAME: MESSAGE`
    /// (NAME the file asked for, as the status overlay names A's; a timeline's song where one
    /// is named).
    pub(in crate::ui) fn warning_lines(&self, version: Listening) -> Vec<String> {
        let Some(v) = self.version(version) else {
            return Vec::new();
        };
        let Some(cloud) = &v.loaded else {
            return Vec::new();
        };
        let name = v.name();
        cloud
            .warnings()
            .iter()
            .map(|w| {
                format!(
                    "{} {}: {}",
                    version.letter(),
                    w.path.as_deref().unwrap_or(&name),
                    w.message
                )
            })
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

    /// Whether the GPU scene must be built for the Song slot's cloud `song_id` (A, or the
    /// version beside it, changed since it was built); then it counts as built for them and
    /// the old difference is dropped.
    pub(in crate::ui) fn rebuild_for(&mut self, song_id: u64) -> bool {
        let key = (song_id, self.beside, self.matched_shown());
        if self.built_for == Some(key) {
            return false;
        }
        self.built_for = Some(key);
        self.forget_difference();
        // A build for the old scene has nothing to give the new one, and the new scene has no
        // grids yet.
        self.grid_build = None;
        self.has_grids = false;
        self.grids_failed = None;
        true
    }

    /// Whether what the compare shows is still on its way: a version loading, the alignment
    /// (which moves the version beside A when it comes) or the grids the view asks for.
    pub(in crate::ui) fn settling(&self) -> bool {
        self.loading() || self.alignment.aligning() || self.grids_building() || self.grids_pending
    }

    /// The settings the two halves are drawn with: `settings`, but the points' own while the
    /// scene has no grids yet (in the Surface and Volume views the points stand in until the
    /// grids come, and drawn as the Points view draws them the pictures the halves hold are
    /// kept: a click on Surface does not draw every point of both versions again before the
    /// window shows it).
    pub(in crate::ui) fn halves_settings(&self, settings: &RenderSettings) -> RenderSettings {
        let mut drawn = settings.clone();
        if !self.has_grids {
            drawn.view = ViewKind::Points;
        }
        drawn
    }

    /// What the compare's view says over its halves while they wait (`surface_busy`: a
    /// surface is extracted), unless the status line (`status`) says it already: one notice in
    /// one place.
    pub(in crate::ui) fn badge(
        &self,
        surface_busy: bool,
        status: Option<&str>,
    ) -> Option<&'static str> {
        let waiting = if self.grids_building() {
            GRIDS_BUSY
        } else if self.difference_reading.is_some() && self.layout == CompareLayout::Difference {
            // The hover read-outs come with it.
            DIFFERENCE_BUSY
        } else if surface_busy {
            "extracting surface…"
        } else {
            return None;
        };
        (status != Some(waiting)).then_some(waiting)
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

    /// Whether the picture shows the version's levels matched to A's loudness: the "matched"
    /// measure of the difference, once the comparison has a gain for it.
    pub(in crate::ui) fn matched_shown(&self) -> bool {
        self.matched
            && self.layout == CompareLayout::Difference
            && self.alignment.level_match_db(self.beside).is_some()
    }

    /// Picks the difference's measure: `Some(measure)`, or None for "matched" (level-weighted
    /// with the version's levels matched to A's loudness).
    pub(in crate::ui) fn pick_measure(&mut self, measure: Option<DifferenceMeasure>) {
        self.matched = measure.is_none();
        self.measure = measure.unwrap_or(DifferenceMeasure::ALL[1]);
    }

    /// Whether the difference's CPU copy is missing or was read for another measure, and no
    /// read-back runs (one for another measure is read again once it came).
    pub(in crate::ui) fn difference_stale(&self) -> bool {
        self.difference_reading.is_none()
            && self
                .difference
                .as_ref()
                .is_none_or(|d| d.measure != self.measure)
    }

    /// Whether the panel's `side` button can be pressed: the version heard, or another once
    /// its audio is decoded.
    pub(in crate::ui) fn can_listen(&self, side: Listening) -> bool {
        self.listening == side
            || if side == Listening::A {
                self.a_track.is_some()
            } else {
                self.version(side).is_some_and(|v| v.track.is_some())
            }
    }

    /// The version key B switches to: the next one (A after the last) whose audio is
    /// decoded; None while none is.
    pub(in crate::ui) fn next_heard(&self) -> Option<Listening> {
        let count = self.count();
        let mut next = self.listening;
        for _ in 1..count {
            next = next.next(count);
            if self.can_listen(next) {
                return Some(next);
            }
        }
        None
    }

    /// Where the decoded track of `version` waits while another plays.
    pub(in crate::ui) fn track_slot(&mut self, version: Listening) -> Option<&mut Option<Track>> {
        match version.0.checked_sub(1) {
            None => Some(&mut self.a_track),
            Some(i) => self.versions.get_mut(i).map(|v| &mut v.track),
        }
    }

    /// Takes `version`'s decoded song for the player (None when it has none yet).
    pub(in crate::ui) fn take_track(&mut self, version: Listening) -> Option<Track> {
        self.track_slot(version).and_then(Option::take)
    }

    /// Keeps `track`, the song the player gave back, as `version`'s.
    pub(in crate::ui) fn put_track(&mut self, version: Listening, track: Option<Track>) {
        if let Some(slot) = self.track_slot(version) {
            *slot = track;
        }
    }

    /// The compare dialog opened: with nothing compared yet the view shows A alone until a
    /// version is picked.
    pub(in crate::ui) fn await_dialog(&mut self, receiver: Receiver<Option<Vec<PathBuf>>>) {
        if self.clouds.is_none() {
            self.layout = CompareLayout::Off;
        }
        self.dialog = Some(receiver);
    }

    /// The files picked in the compare dialog once it closed (none: nothing picked, or no
    /// dialog), each a version to add; pending while it is open.
    pub(in crate::ui) fn poll_dialog(&mut self) -> Poll<Vec<PathBuf>> {
        let Some(receiver) = &self.dialog else {
            return Poll::Ready(Vec::new());
        };
        let picked = match receiver.try_recv() {
            Ok(picked) => picked.unwrap_or_default(),
            Err(TryRecvError::Disconnected) => Vec::new(),
            Err(TryRecvError::Empty) => return Poll::Pending,
        };
        self.dialog = None;
        Poll::Ready(picked)
    }
}

/// Whether a load was cancelled (its row's Cancel).
fn cancelled(shared: &Shared) -> bool {
    shared.cancel.load(std::sync::atomic::Ordering::Relaxed)
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
#[path = "compare_window_tests.rs"]
mod tests;
