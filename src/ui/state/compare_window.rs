//! The window's A/B compare as it is kept between frames (the `compare` field of
//! `LoudscapeApp`): B's path, its loading thread and loaded cloud, A and B moved onto the union
//! axes, the layout (A only, side by side, difference), the difference measure, which song is
//! heard and the other decoded track, the difference grid's CPU copy for read-outs, the axis
//! labels, the hover read-outs and the compare dialog; and the two questions the state answers
//! by itself (`shown`, `side_by_side`). What the compare does (loading B, the GPU scene, the
//! panel, the two viewports, key B) is `ui/compare_window.rs`, which reads and writes these
//! fields.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::Receiver;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::playback::{PlaybackError, Track};
use crate::render::grid::difference::DifferenceMeasure;
use crate::ui::labels::AxisLabels;
use crate::view::pick::Reading;

/// How the compare is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum CompareLayout {
    /// The normal view of A alone.
    Off,
    SideBySide,
    Difference,
}

/// Which song is heard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum Listening {
    A,
    B,
}

/// The window's compare state (one field of `LoudscapeApp`).
pub(in crate::ui) struct CompareState {
    pub(in crate::ui) path: PathBuf,
    pub(in crate::ui) receiver: Option<Receiver<Result<PointCloud, String>>>,
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
    /// The "building the compare grids" notice has been on screen for a frame: build now.
    pub(in crate::ui) grids_announced: bool,
    /// The error last told in the window's messages (each new one is told once).
    pub(in crate::ui) error_told: Option<String>,
    pub(in crate::ui) labels: Option<AxisLabels>,
    pub(in crate::ui) hover: Option<(glam::Vec2, Vec<Reading>)>,
    /// The compare dialog's answer.
    pub(in crate::ui) dialog: Option<Receiver<Option<Vec<PathBuf>>>>,
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
            grids_announced: false,
            labels: None,
            hover: None,
            dialog: None,
        }
    }

    /// Whether the view shows the compare now.
    pub(in crate::ui) fn shown(&self) -> bool {
        self.layout != CompareLayout::Off && self.clouds.is_some()
    }

    pub(in crate::ui) fn side_by_side(&self) -> bool {
        self.layout == CompareLayout::SideBySide && self.clouds.is_some()
    }
}
