//! Opening songs and clouds from the window: the thread that opens a path (a PLY is read, audio
//! goes through the extractor and the cloud cache in `crate::extract`), its progress bar with the
//! stage and a Cancel button, and the "Open" row of the side panel (a path field, and a native
//! file dialog through `rfd`). The command-line argument, a dropped file, the path field and the
//! dialog all end in [`LoudscapeApp::start_loading`], which calls [`open_path`] on a thread; the
//! old view stays until the new cloud is installed.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, channel};

use eframe::egui::{self, RichText};

use crate::data::cloud::PointCloud;
use crate::extract::{self, Progress, Settings};
use crate::ui::state::{LoudscapeApp, Shared};

/// Audio the dialog offers (the extractor reads these); clouds are `.ply`.
const AUDIO_EXTENSIONS: [&str; 9] = [
    "wav", "flac", "ogg", "oga", "opus", "mp3", "aiff", "aif", "aifc",
];

/// Opens `path` as the window does: a cloud file, or audio extracted (or found in the cache).
/// Progress goes to `shared` and, one line a stage, to stderr; errors name the file.
pub fn open_path(path: &Path, settings: &Settings, shared: &Shared) -> Result<PointCloud, String> {
    let mut report = |progress: &Progress| {
        if let Ok(mut slot) = shared.progress.lock() {
            *slot = Some(progress.clone());
        }
    };
    // The window always tells stderr: there it is a log, not a script's input.
    extract::open_reporting(path, settings, &shared.cancel, true, &mut report)
        .map_err(|e| e.to_string())
}

/// The native Open dialog, built here (macOS wants dialogs made on the main thread) and awaited
/// on a thread so the window keeps drawing; the answer comes through the receiver.
pub(super) fn open_dialog() -> Receiver<Option<PathBuf>> {
    let (sender, receiver) = channel();
    let dialog = rfd::AsyncFileDialog::new()
        .set_title("Open a song or a loudscape cloud")
        .add_filter(
            "Songs and clouds",
            &[&AUDIO_EXTENSIONS[..], &["ply"]].concat(),
        )
        .add_filter("Songs", &AUDIO_EXTENSIONS)
        .add_filter("Clouds (.ply)", &["ply"])
        .pick_file();
    std::thread::spawn(move || {
        let picked = pollster::block_on(dialog).map(|file| file.path().to_path_buf());
        let _ = sender.send(picked);
    });
    receiver
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

impl LoudscapeApp {
    /// The Open row: a path (audio or .ply) and a button; the same path as a drop.
    pub(super) fn open_controls(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let field = ui.add(
                egui::TextEdit::singleline(&mut self.open.path)
                    .hint_text("song.ogg or cloud.ply")
                    .desired_width(170.0),
            );
            let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if enter && !self.open.path.trim().is_empty() {
                let path = PathBuf::from(self.open.path.trim());
                self.start_loading(path);
            }
            let button = ui
                .add_enabled(self.open.dialog.is_none(), egui::Button::new("Open…"))
                .on_hover_text("a song (wav, flac, ogg, opus, mp3, aiff) or a .ply cloud");
            if button.clicked() {
                self.open.dialog = Some(open_dialog());
            }
        });
        let answer = self.open.dialog.as_ref().map(|r| r.try_recv());
        match answer {
            Some(Ok(picked)) => {
                self.open.dialog = None;
                if let Some(path) = picked {
                    self.open.path = path.display().to_string();
                    self.start_loading(path);
                }
            }
            Some(Err(std::sync::mpsc::TryRecvError::Disconnected)) => self.open.dialog = None,
            Some(Err(std::sync::mpsc::TryRecvError::Empty)) => {
                ui.ctx()
                    .request_repaint_after(std::time::Duration::from_millis(100));
            }
            None => {}
        }
    }

    /// One row a load: the file, the extractor's stage and share done, and Cancel.
    pub(super) fn loading_progress(&mut self, ui: &mut egui::Ui) {
        for loading in &self.loading {
            let progress = loading.shared.progress.lock().ok().and_then(|p| p.clone());
            let cancelled = loading.shared.cancel.load(Ordering::Relaxed);
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(RichText::new(file_name(&loading.path)).strong());
                if progress.is_some()
                    && !cancelled
                    && ui
                        .small_button("Cancel")
                        .on_hover_text("stop the extractor")
                        .clicked()
                {
                    loading.shared.cancel.store(true, Ordering::Relaxed);
                }
            });
            match (&progress, cancelled) {
                (_, true) => {
                    ui.label("cancelling…");
                }
                (Some(progress), false) => {
                    ui.add(
                        egui::ProgressBar::new(progress.fraction)
                            .text(format!(
                                "{} {:.0}%",
                                progress.stage,
                                progress.fraction * 100.0
                            ))
                            .desired_width(240.0),
                    );
                }
                (None, false) => {
                    ui.label("loading");
                }
            }
        }
    }
}
