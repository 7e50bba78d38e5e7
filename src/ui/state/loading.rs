//! A load on its way, as the window keeps it (the `loading` field of `LoudscapeApp`): the path
//! being opened, the receiver its thread answers on, and [`Shared`], what that thread shares
//! with the window (the extractor's latest stage for the progress bar, and the Cancel flag).
//! Loads are started by `ui/slots.rs` (a song or a cloud) and `ui/timeline_build.rs` (a
//! timeline; its tag reading, and B of the A/B compare, use a `Shared` alone); their progress
//! rows are drawn by `ui/open.rs`.

use std::path::PathBuf;
use std::sync::mpsc::Receiver;

use crate::data::cloud::PointCloud;

/// A cloud being opened on a thread.
pub(in crate::ui) struct Loading {
    pub(in crate::ui) path: PathBuf,
    pub(in crate::ui) receiver: Receiver<Result<PointCloud, String>>,
    /// Progress and cancel of an extraction (`open.rs`).
    pub(in crate::ui) shared: Shared,
}

/// What a loading thread shares with the window.
#[derive(Clone, Default)]
pub(in crate::ui) struct Shared {
    /// The extractor's latest stage (audio only).
    pub(in crate::ui) progress: std::sync::Arc<std::sync::Mutex<Option<crate::extract::Progress>>>,
    /// Set by the Cancel button: the extractor is killed and its partial output removed.
    pub(in crate::ui) cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
}
