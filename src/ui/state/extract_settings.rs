//! The extraction settings kept between frames (the `extract` field of `OpenPanel`): those
//! chosen for the next song opened from audio, and those the song on screen was extracted with.
//! The panel that changes them and "Re-extract" are `ui/extract_settings.rs`.

use std::path::PathBuf;

use crate::extract::Settings;

/// The settings being chosen, and those the song on screen was asked for.
#[derive(Clone, Debug, Default)]
pub(in crate::ui) struct ExtractChoices {
    /// Used for the next song opened from audio.
    pub(in crate::ui) next: Settings,
    /// The song on screen (audio) and the settings its extraction was started with.
    pub(in crate::ui) shown: Option<(PathBuf, Settings)>,
}
