//! What the window remembers between runs (eframe's storage, under its app key): the files,
//! the view, the camera, the settings, the compare's versions and the "level as heard". The app's
//! state holds the last copy handed to storage; `ui/persistence.rs` makes and applies it.

use std::path::PathBuf;

use crate::render::scene::ViewKind;
use crate::view::camera::Camera;

/// What the app remembers between runs.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Remembered {
    pub files: Vec<PathBuf>,
    pub view: Option<ViewKind>,
    pub camera: Option<Camera>,
    /// The 3D view's height and the window's (points) the camera was left at: a reopened
    /// window whose loudness strip comes after its first frames keeps the same framing.
    pub view_heights: Option<(f32, f32)>,
    pub iso_value: Option<f32>,
    pub show_box: Option<bool>,
    /// Transfer function preset name (Classic, Ember, Glacial) and the volume's hp tint.
    #[serde(default)]
    pub transfer: Option<String>,
    #[serde(default)]
    pub hp_tint: Option<bool>,
    /// Surface method short name (mt, dc).
    #[serde(default)]
    pub surface_method: Option<String>,
    /// Audio picked by hand for a cloud whose recorded source moved: cloud path -> audio path.
    pub audio_for: Vec<(PathBuf, PathBuf)>,
    /// Colour maps and background (`render::colormap::Colours`).
    #[serde(default)]
    pub colours: Option<crate::render::colormap::Colours>,
    /// The slot shown: "song" or "timeline" (the camera is its).
    #[serde(default)]
    pub active: Option<String>,
    /// B of the compare (absolute), reopened with A.
    #[serde(default)]
    pub compare: Option<PathBuf>,
    /// The compare's further versions, C, D... (absolute), reopened after B.
    #[serde(default)]
    pub compare_more: Vec<PathBuf>,
    /// The "level as heard" preset of Timeline mode (`normalize::PRESETS` key).
    #[serde(default)]
    pub heard: Option<String>,
}
