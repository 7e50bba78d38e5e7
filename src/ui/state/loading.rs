//! A load on its way, as the window keeps it (the `loading` field of `LoudscapeApp`): the path
//! being opened, the receiver its thread answers on, and [`Shared`], what that thread shares
//! with the window (the extractor's latest stage for the progress bar, the Cancel flag, and the
//! song's points so far while it is extracted). Loads are started by `ui/slots.rs` (a song or a
//! cloud) and `ui/timeline_build.rs` (a timeline; its tag reading, and B of the A/B compare,
//! use a `Shared` alone); their progress rows are drawn by `ui/messages.rs`, the points so far
//! shown by `ui/slots.rs` ([`PreviewShown`]).

use std::path::PathBuf;
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::data::cloud::PointCloud;
use crate::view::camera::Camera;

/// A cloud being opened on a thread.
pub(in crate::ui) struct Loading {
    pub(in crate::ui) path: PathBuf,
    pub(in crate::ui) receiver: Receiver<Result<PointCloud, String>>,
    /// Progress and cancel of an extraction (`messages.rs`).
    pub(in crate::ui) shared: Shared,
    /// When it started.
    pub(in crate::ui) started: Instant,
    /// The song's points so far, while they are shown (`slots.rs`).
    pub(in crate::ui) preview: Option<PreviewShown>,
}

impl Loading {
    pub(in crate::ui) fn new(
        path: PathBuf,
        receiver: Receiver<Result<PointCloud, String>>,
        shared: Shared,
    ) -> Loading {
        Loading {
            path,
            receiver,
            shared,
            started: Instant::now(),
            preview: None,
        }
    }
}

/// The growing cloud of a song being extracted, shown in its slot.
pub(in crate::ui) struct PreviewShown {
    /// Its id in the slot (a newer one replaces it as the points come).
    pub(in crate::ui) id: u64,
    /// Points shown.
    pub(in crate::ui) points: usize,
    /// The cloud the first points replaced in the slot, and the camera then: shown again if
    /// the extraction fails or is cancelled.
    pub(in crate::ui) replaced: Option<(Arc<PointCloud>, Camera)>,
}

/// What a loading thread shares with the window.
#[derive(Clone, Default)]
pub(in crate::ui) struct Shared {
    /// The extractor's latest stage (audio only).
    pub(in crate::ui) progress: Arc<Mutex<Option<crate::extract::Progress>>>,
    /// Set by the Cancel button: the extractor is killed and its partial output removed.
    pub(in crate::ui) cancel: Arc<std::sync::atomic::AtomicBool>,
    /// Whether the window shows the points of a song while it is extracted (not for B of a
    /// compare).
    pub(in crate::ui) preview: bool,
    /// The newest cloud of the points so far (audio only; `extract::preview`), taken by the
    /// window when it shows it.
    pub(in crate::ui) partial: Arc<Mutex<Option<PointCloud>>>,
}
