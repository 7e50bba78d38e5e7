//! What the side panel's "level as heard" choice keeps between frames (its behaviour is
//! `ui/normalize.rs`).

use std::sync::Arc;

use crate::data::cloud::PointCloud;
use crate::data::normalize::Normalization;

/// The side panel's "level as heard" choice in Timeline mode.
#[derive(Default)]
pub(in crate::ui) struct Heard {
    /// The normalization shown (the files as mastered, or a preset).
    pub(in crate::ui) preset: Normalization,
    /// A new choice, applied where the GPU is at hand (`LoudscapeApp::apply_heard`).
    pub(in crate::ui) pending: Option<Normalization>,
    /// The timeline as loaded, the source of every shifted copy.
    pub(in crate::ui) original: Option<Arc<PointCloud>>,
    /// The id of the timeline this installed; another id means a new file was loaded.
    pub(in crate::ui) shown: u64,
}
