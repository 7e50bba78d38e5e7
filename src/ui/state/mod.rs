//! What the window keeps between frames: [`LoudscapeApp`] and the types of its fields. This
//! folder is the floor under the window's behaviour, which lives in `ui/`, one file a concern,
//! each adding its methods to `LoudscapeApp`: `app.rs` (opening the window, one frame),
//! `view_3d.rs` (the 3D view's steps), `slots.rs` (loading and installing clouds), `panels.rs`
//! (the side panel), `hover.rs` (picking and markers), `persistence.rs` (what is remembered
//! between runs), `window_screenshot.rs` (the two screenshot paths) and more. A concern with
//! state of its own keeps it here under the same name: `open.rs` (the Open row,
//! [`open::OpenPanel`]), `extract_settings.rs` (the extraction settings it holds) and
//! `iso_sweep.rs` (the scripted isovalue sweep); `loading.rs` is a load on its way and what its
//! thread shares. State that owns its updates (the behaviour files change it through its
//! methods, and read its fields) has a file of its own: `view_motion.rs` (the camera, its fit
//! and motion), `surface_status.rs` (the surface's status and level of detail),
//! `frame_clock.rs` (frame number, pace, renders), `messages.rs` (what the window tells the
//! user), `timeline_build.rs` (a timeline on its way, the years typed: `TimelineBuilder`),
//! `compare_window.rs` (the A/B compare, `CompareState`, with `alignment.rs` and
//! `compare_grids.rs`) and `slot.rs`
//! (which data slot); the playback's owner is `ui/audio.rs`'s `AudioPanel`.
//! This file holds `LoudscapeApp` and the small types of its other fields (a loaded cloud, the
//! hover, the screenshot, the "Save PNG" panel).
//!
//! Nothing here imports a behaviour file: only the floors below (`audio.rs`, `labels.rs`,
//! `recent.rs`, `strip.rs`, and the crate's data, view and render types), and within the
//! folder only downward (this file imports its children; `open.rs` imports
//! `extract_settings.rs`; `timeline_build.rs` imports `loading.rs`; `view_motion.rs` imports
//! `slot.rs`; none imports this file). So each behaviour file sees the whole state without
//! importing another for a type, and no import runs back up. A type's own plain methods (those
//! that need no `LoudscapeApp`) and their tests sit with it here; its fields are open to `ui/`
//! (`pub(in crate::ui)`) for the behaviour files to read, and to write where no owner type
//! holds them yet (`python3 scripts/app_state_writes.py` lists those writes).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::Receiver;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::render::scene::{RenderSettings, ViewKind};
use crate::ui::audio::AudioPanel;
use crate::ui::labels;
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;
use crate::view::pick::Reading;

pub(super) mod alignment;
pub(super) mod compare_grids;
pub(super) mod compare_scene;
pub(super) mod compare_window;
pub(super) mod extract_settings;
pub(super) mod first_shown;
pub(super) mod frame_clock;
pub(super) mod heard;
pub(super) mod iso_sweep;
pub(super) mod loading;
pub(super) mod messages;
pub(super) mod open;
pub(super) mod picture_save;
pub(super) mod remembered;
pub(super) mod save_wait;
mod slot;
pub(super) mod surface_status;
pub(super) mod timeline_build;
pub(super) mod video_export;
pub(super) mod view_motion;
pub(super) mod volume_hold;
pub(super) mod written;

use compare_window::CompareState;
use iso_sweep::IsoSweep;
use loading::Loading;
use open::OpenPanel;
pub(super) use slot::Slot;

/// The window's state: the two data slots, the render settings, the camera and what each
/// panel keeps between frames.
pub(super) struct LoudscapeApp {
    pub(super) song: Option<Loaded>,
    pub(super) timeline: Option<Loaded>,
    pub(super) active: Slot,
    /// Of files opened together, which is shown first (`first_shown.rs`).
    pub(super) first_shown: first_shown::FirstShown,
    pub(super) settings: RenderSettings,
    /// The camera, its fit and its motion (`view_motion.rs`).
    pub(super) motion: view_motion::ViewMotion,
    pub(super) loading: Vec<Loading>,
    /// What the app is telling the user, shown under the 3D view (`messages.rs`).
    pub(super) messages: messages::Messages,
    pub(super) next_id: u64,
    /// The frame number, the frames' pace and the scene renders (`frame_clock.rs`).
    pub(super) clock: frame_clock::FrameClock,
    pub(super) screenshot: Option<ScreenshotState>,
    /// The playback: the song in the player, a seek waiting for it (`--seek`) and the audio
    /// picked by hand for each cloud (`audio.rs`).
    pub(super) audio: AudioPanel,
    pub(super) hover: Option<(HoverKey, Hover)>,
    /// The compare's side-by-side read-outs, worked out once a cursor spot and camera.
    pub(super) compare_hover: crate::ui::compare_readouts::CompareHover,
    pub(super) hovered_song: Option<usize>,
    pub(super) selected_song: Option<usize>,
    /// The "Save PNG" panel.
    pub(super) save_shot: SaveShot,
    pub(super) last_view: Option<FrameView>,
    /// The whole 3D view's size in pixels (both halves of a side-by-side compare).
    pub(super) view_px: (u32, u32),
    /// Whether to remember state (off for scripted screenshot runs).
    pub(super) persist: bool,
    /// What was last handed to eframe's storage (`persistence.rs` asks for a frame to save a
    /// change).
    pub(super) saved: Option<remembered::Remembered>,
    /// The active cloud's surface: its status and level of detail (`surface_status.rs`).
    pub(super) surface: surface_status::SurfaceStatus,
    /// Work that blocks the window, announced a frame before it runs (shown with a spinner).
    pub(super) busy: Option<String>,
    /// The busy notice has been on screen for a frame: the work may start.
    pub(super) busy_shown: bool,
    /// The first Volume frame after another view, announced a frame before it is drawn.
    pub(super) volume_hold: volume_hold::VolumeHold,
    /// Progressive points: the fraction drawn while the view fills in (`ui/progressive.rs`).
    pub(super) refining: Option<f32>,
    /// The scripted isovalue sweep of a test run (`iso_sweep.rs`).
    pub(super) iso_sweep: Option<IsoSweep>,
    /// Draw again next frame (what it shows is under way: a grid build, a surface on the worker).
    pub(super) needs_repaint: bool,
    /// The Open row (`open.rs`).
    pub(super) open: OpenPanel,
    /// A timeline built from songs: the tags, the years dialog, the rows
    /// (`timeline_build.rs`).
    pub(super) timeline_build: timeline_build::TimelineBuilder,
    /// The frequency axis chosen for songs (`freq_axis.rs`).
    pub(super) freq_axis: crate::data::freq_axis::FreqAxis,
    /// The A/B compare with a second song (`compare_window.rs`).
    pub(super) compare: Option<CompareState>,
    /// The loudness strip under the Song view (`strip.rs`).
    pub(super) strip: crate::ui::strip::LoudnessStrip,
    /// Key presses a scripted run (`--press`, tests) still has to make (`shortcuts.rs`).
    pub(super) scripted_presses: Vec<String>,
    /// Timeline mode's "level as heard" choice (`normalize.rs`).
    pub(super) heard: heard::Heard,
    /// Input events held back for the next frame: those after a Tab, typed before the focus
    /// moved (`shortcuts::split_after_focus_move`).
    pub(super) deferred_events: Vec<eframe::egui::Event>,
    /// "Export video…" and the export under way (`video_export.rs`).
    pub(super) video_export: video_export::VideoExport,
}

pub(super) struct Loaded {
    pub(super) id: u64,
    /// Point size for this cloud (sparse timelines want larger discs than dense songs).
    pub(super) point_size: f32,
    pub(super) cloud: Arc<PointCloud>,
    pub(super) labels: labels::AxisLabels,
    pub(super) world_from_data: glam::Mat4,
    pub(super) world_box: (glam::Vec3, glam::Vec3),
    /// The voxel grid read back once for hover picking in the Surface and Volume views.
    pub(super) cpu_grid: Option<Field>,
    /// The frequency axis the scene shows, and its mapping (`None`: z as stored).
    pub(super) freq_axis: crate::data::freq_axis::FreqAxis,
    pub(super) freq: Option<crate::data::freq_axis::FreqMapping>,
    /// The points as that axis shows them, for hover picking (`None`: as stored), and the
    /// thread making them.
    pub(super) view_points: Option<Arc<Vec<crate::data::cloud::Point>>>,
    pub(super) view_points_pending: Option<Receiver<Vec<crate::data::cloud::Point>>>,
}

/// What is under the cursor, recomputed only when the cursor or the view changed.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct HoverKey {
    pub(super) px: glam::Vec2,
    pub(super) camera: Camera,
    pub(super) size: (u32, u32),
    pub(super) view: ViewKind,
    pub(super) cloud_id: u64,
    pub(super) min_scalar: f32,
    pub(super) freq_axis: crate::data::freq_axis::FreqAxis,
}

#[derive(Clone, Debug, Default)]
pub(super) struct Hover {
    pub(super) readings: Vec<Reading>,
    /// Normalized x under the cursor (on the data, or where the ray enters the box).
    pub(super) x: Option<f32>,
}

pub(super) struct ScreenshotState {
    pub(super) path: PathBuf,
    pub(super) frames_shown: u32,
    pub(super) requested: bool,
    pub(super) done: Arc<AtomicBool>,
}

/// The "Save PNG" panel's choices (where it may write: `written.rs`).
pub(super) struct SaveShot {
    /// Where to save; empty saves `loudscape-<time>.png` in the current directory.
    pub(super) path: String,
    /// Whether to render at `size` instead of the window's size.
    pub(super) custom_size: bool,
    pub(super) size: [u32; 2],
    /// Save on this frame (the button or Ctrl+S).
    pub(super) requested: bool,
    /// The PNGs saved in this run: only these are written again under their own name.
    pub(super) made: written::MadeHere,
    /// The PNG being read back and written on a thread.
    pub(super) saving: Option<picture_save::PictureSave>,
    /// The save waiting for the view to fill in, before its picture is copied
    /// (`save_wait.rs`).
    pub(super) waiting: Option<save_wait::SaveWait>,
    /// The view held its scene complete last frame (every point drawn): the scripted
    /// `--press when-drawn` of tests holds the presses after it until then.
    pub(super) view_drawn: bool,
    /// The window was asked to close while a save was under way: it closes once the PNG is
    /// written (`window_screenshot.rs`, `close_after_save`).
    pub(super) closing: bool,
}

impl Default for SaveShot {
    fn default() -> Self {
        Self {
            path: String::new(),
            custom_size: false,
            size: [1920, 1080],
            requested: false,
            made: written::MadeHere::default(),
            saving: None,
            waiting: None,
            view_drawn: false,
            closing: false,
        }
    }
}
