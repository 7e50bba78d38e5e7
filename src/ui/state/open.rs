//! The Open row's state (the `open` field of `LoudscapeApp`): the path field, the Open and Save
//! dialogs while they are open and where the save dialog said to save, the recent files, the
//! shortcuts overlay's switch and the extraction settings (`state/extract_settings.rs`). What
//! the row does is `ui/open.rs`.

use std::path::PathBuf;
use std::sync::mpsc::Receiver;

use crate::ui::recent::RecentFiles;
use crate::ui::state::extract_settings::ExtractChoices;

/// The Open row's state: its text field, the dialogs while they are open, the recent files,
/// the extraction settings and the shortcuts overlay.
#[derive(Default)]
pub(in crate::ui) struct OpenPanel {
    pub(in crate::ui) path: String,
    /// The compare's B field: typed into before any compare exists (`compare_window.rs`).
    pub(in crate::ui) compare_path: String,
    /// The dialog's answer (`None`: closed without a choice).
    pub(in crate::ui) dialog: Option<Receiver<Option<Vec<PathBuf>>>>,
    /// The save dialog's answer, while it is open.
    pub(in crate::ui) save_dialog: Option<Receiver<Option<PathBuf>>>,
    /// Where the save dialog said to save the next screenshot.
    pub(in crate::ui) save_to: Option<PathBuf>,
    pub(in crate::ui) recent: RecentFiles,
    /// The `?` overlay is shown (`shortcuts.rs`).
    pub(in crate::ui) show_shortcuts: bool,
    /// The extraction settings for the next song opened, and those of the song shown
    /// (`extract_settings.rs`).
    pub(in crate::ui) extract: ExtractChoices,
}
