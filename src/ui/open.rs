//! Opening songs and clouds from the window: the thread that opens a path (a PLY is read, audio
//! goes through the extractor and the cloud cache in `crate::extract`), its progress bar with the
//! stage and a Cancel button, and the "Open" row of the side panel (a path field, and a native
//! file dialog through `rfd`). The command-line argument, a dropped file, the path field and the
//! dialog all end in `start_opening` (`timeline_build.rs`: a folder or several songs are a
//! timeline), and a song or a cloud in [`LoudscapeApp::start_loading`], which calls
//! [`open_path`] on a thread; the old view stays until the new cloud is installed. Below the
//! row: the recent files (`recent.rs`). The row's state (`OpenPanel`) is `state/open.rs`. The
//! save dialog for screenshots ([`LoudscapeApp::ask_where_to_save`]) lives here too. Where no
//! dialog can open (Linux without a desktop portal or zenity, as under Xvfb) the window says so
//! and goes on as it did without dialogs (the path field; screenshots in the current folder).

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

use eframe::egui::{self, RichText};

use crate::data::cloud::PointCloud;
use crate::extract::preview::Preview;
use crate::extract::{self, PointsSoFar, Progress, Settings};
use crate::ui::state::LoudscapeApp;
use crate::ui::state::loading::Shared;

/// Whether a native file dialog can open here. On Linux rfd asks the desktop portal over
/// D-Bus, then zenity; with neither (a bare X server such as Xvfb) it would return at once as if
/// the user had cancelled, so the window does not offer it.
pub(super) fn dialogs_available() -> bool {
    if !cfg!(target_os = "linux") {
        return true;
    }
    let bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|v| !v.is_empty());
    let zenity = std::env::var_os("PATH")
        .is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join("zenity").is_file()));
    bus || zenity
}

/// Why there is no dialog, for the window's messages.
pub(super) const NO_DIALOG: &str =
    "no file dialog can open here (no desktop portal on D-Bus and no zenity)";

/// Audio the dialog offers (the extractor reads these); clouds are `.ply`.
pub(super) const AUDIO_EXTENSIONS: [&str; 9] = [
    "wav", "flac", "ogg", "oga", "opus", "mp3", "aiff", "aif", "aifc",
];

/// Opens `path` as the window does: a cloud file, or audio extracted (or found in the cache).
/// Progress goes to `shared` and, one line a stage, to stderr; errors name the file. While a
/// song is extracted its points so far go to `shared` too (`extract::preview`: read here, off
/// the window's thread, handed on a few times a second); a failure to read them loses only
/// them, said in one line.
pub fn open_path(path: &Path, settings: &Settings, shared: &Shared) -> Result<PointCloud, String> {
    let mut report = |progress: &Progress| {
        if let Ok(mut slot) = shared.progress.lock() {
            *slot = Some(progress.clone());
        }
    };
    // The path the extractor records, which the growing cloud names as its source too.
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let mut preview = Preview::new(&absolute, settings);
    let mut on_points = |points: &PointsSoFar| {
        if !shared.preview {
            return;
        }
        match preview.hear(points, Instant::now()) {
            Ok(Some(cloud)) => {
                if let Ok(mut slot) = shared.partial.lock() {
                    *slot = Some(cloud);
                }
            }
            Ok(None) => {}
            Err(reason) => eprintln!(
                "loudscape: {}: the points cannot be shown while extracting ({}); the cloud \
                 shows when the extraction ends",
                path.display(),
                crate::data::cloud::one_line(&reason)
            ),
        }
    };
    // The window always tells stderr: there it is a log, not a script's input.
    extract::open_reporting_watching(
        path,
        settings,
        &shared.cancel,
        true,
        &mut report,
        &mut on_points,
    )
    .map_err(|e| e.to_string())
}

/// The native Open dialog, built here (macOS wants dialogs made on the main thread) and awaited
/// on a thread so the window keeps drawing; the answer comes through the receiver.
/// Several songs chosen become a timeline; `folder` asks for a folder (a timeline of the songs
/// in it).
pub(super) fn open_dialog(folder: bool) -> Receiver<Option<Vec<PathBuf>>> {
    let (sender, receiver) = channel();
    if folder {
        let dialog = rfd::AsyncFileDialog::new()
            .set_title("Open a folder of songs as a timeline")
            .pick_folder();
        std::thread::spawn(move || {
            let picked = pollster::block_on(dialog).map(|f| vec![f.path().to_path_buf()]);
            let _ = sender.send(picked);
        });
        return receiver;
    }
    let dialog = rfd::AsyncFileDialog::new()
        .set_title("Open a song, several songs (a timeline) or a loudscape cloud")
        .add_filter(
            "Songs and clouds",
            &[&AUDIO_EXTENSIONS[..], &["ply"]].concat(),
        )
        .add_filter("Songs", &AUDIO_EXTENSIONS)
        .add_filter("Clouds (.ply)", &["ply"])
        .pick_files();
    std::thread::spawn(move || {
        let picked = pollster::block_on(dialog)
            .map(|files| files.iter().map(|f| f.path().to_path_buf()).collect());
        let _ = sender.send(picked);
    });
    receiver
}

/// The native Save dialog for a PNG, suggesting `default_name` in the current folder.
fn save_dialog(default_name: &str) -> Receiver<Option<PathBuf>> {
    save_dialog_as("Save the view as PNG", ("PNG image", "png"), default_name)
}

/// The native Save dialog titled `title` for files of `filter` (name, extension), opening in
/// the current folder with `default_name`; awaited on a thread as [`open_dialog`] is.
pub(super) fn save_dialog_as(
    title: &str,
    filter: (&str, &str),
    default_name: &str,
) -> Receiver<Option<PathBuf>> {
    let (sender, receiver) = channel();
    let mut dialog = rfd::AsyncFileDialog::new()
        .set_title(title)
        .add_filter(filter.0, &[filter.1])
        .set_file_name(default_name);
    if let Ok(dir) = std::env::current_dir() {
        dialog = dialog.set_directory(dir);
    }
    let dialog = dialog.save_file();
    std::thread::spawn(move || {
        let picked = pollster::block_on(dialog).map(|file| file.path().to_path_buf());
        let _ = sender.send(picked);
    });
    receiver
}

/// The Open row's path field: narrow, beside Open… and Folder…, with a hint that fits it whole.
pub(super) fn open_field(path: &mut String) -> egui::TextEdit<'_> {
    egui::TextEdit::singleline(path)
        .hint_text(OPEN_HINT)
        .desired_width(95.0)
}

/// The Open field's hint.
const OPEN_HINT: &str = "song or .ply";

pub(super) fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

impl LoudscapeApp {
    /// The Open row: a path (audio or .ply) and a button; the same path as a drop.
    pub(super) fn open_controls(&mut self, ui: &mut egui::Ui) {
        // Wrapped: in a narrow side panel Folder… goes under the field rather than past the edge.
        ui.horizontal_wrapped(|ui| {
            let field = ui
                .add(open_field(&mut self.open.path))
                .on_hover_text("a song or a .ply cloud: type its path and press Enter");
            let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if enter && !self.open.path.trim().is_empty() {
                let path = PathBuf::from(self.open.path.trim());
                self.start_opening(vec![path]);
            }
            let button = ui
                .add_enabled(self.open.dialog.is_none(), egui::Button::new("Open…"))
                .on_hover_text("a song (wav, flac, ogg, opus, mp3, aiff) or a .ply cloud (Ctrl+O)");
            if button.clicked() {
                self.open_dialog_or_say_why(false);
            }
            if ui
                .add_enabled(self.open.dialog.is_none(), egui::Button::new("Folder…"))
                .on_hover_text("a folder of songs: one timeline, songs placed by year")
                .clicked()
            {
                self.open_dialog_or_say_why(true);
            }
        });
        self.poll_save_dialog(ui.ctx());
        self.timeline_build_panel(ui);
        self.recent_files(ui);
        self.extraction_controls(ui);
        let answer = self.open.dialog.as_ref().map(|r| r.try_recv());
        match answer {
            Some(Ok(picked)) => {
                self.open.dialog = None;
                if let Some(paths) = picked.filter(|p| !p.is_empty()) {
                    if let [path] = &paths[..] {
                        self.open.path = path.display().to_string();
                    }
                    self.start_opening(paths);
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

    /// Opens the Open dialog, or says why it cannot (Ctrl+O and the Open… button).
    pub(super) fn open_dialog_or_say_why(&mut self, folder: bool) {
        if self.open.dialog.is_some() {
            return;
        }
        if dialogs_available() {
            self.open.dialog = Some(open_dialog(folder));
        } else {
            self.messages
                .warn(format!("{NO_DIALOG}: type a path in the Open field"));
        }
    }

    /// Asks where to save a screenshot with the native dialog; true when it opened (its answer
    /// saves later, through `open.save_to`). False where none can open: the caller saves as it
    /// did before, and the saved message says why there was no dialog.
    pub(super) fn ask_where_to_save(&mut self, default_name: &Path) -> bool {
        if self.open.save_dialog.is_some() {
            return true;
        }
        if !dialogs_available() {
            self.open.save_to = None;
            return false;
        }
        self.open.save_dialog = Some(save_dialog(&default_name.display().to_string()));
        true
    }

    /// The save dialog's answer: a path saves the screenshot there on this frame.
    pub(super) fn poll_save_dialog(&mut self, ctx: &egui::Context) {
        let answer = self.open.save_dialog.as_ref().map(|r| r.try_recv());
        match answer {
            Some(Ok(picked)) => {
                self.open.save_dialog = None;
                if let Some(path) = picked {
                    self.open.save_to = Some(path);
                    self.save_shot.requested = true;
                }
            }
            Some(Err(std::sync::mpsc::TryRecvError::Disconnected)) => {
                self.open.save_dialog = None;
            }
            Some(Err(std::sync::mpsc::TryRecvError::Empty)) => {
                ctx.request_repaint_after(std::time::Duration::from_millis(100));
            }
            None => {}
        }
    }

    /// The recent files, newest first: a click opens one; a missing one is shown as such.
    fn recent_files(&mut self, ui: &mut egui::Ui) {
        let entries = self.open.recent.entries();
        if entries.is_empty() {
            return;
        }
        let mut open = None;
        egui::CollapsingHeader::new("Recent")
            .default_open(true)
            .show(ui, |ui| {
                for (path, present) in entries {
                    let name = self.recent_name(&path);
                    if present {
                        let link = ui
                            .add(egui::Button::new(RichText::new(&name).small()).frame(false))
                            .on_hover_text(path.display().to_string());
                        if link.clicked() {
                            open = Some(path);
                        }
                    } else {
                        ui.label(
                            RichText::new(format!("{name} (missing)"))
                                .small()
                                .weak()
                                .strikethrough(),
                        )
                        .on_hover_text(format!("not found: {}", path.display()));
                    }
                }
            });
        if let Some(path) = open {
            self.open.path = path.display().to_string();
            self.start_opening(vec![path]);
        }
    }

    /// How the recent list names `path`: its file name; a folder (opened, it is a timeline)
    /// `name/ (timeline)`, as the timeline it made is named when it is loaded from the cloud
    /// cache, or was named when it was open; another timeline built in the window, never
    /// named, "timeline built here".
    fn recent_name(&self, path: &Path) -> String {
        let name = file_name(path);
        if path.is_dir() {
            return format!("{name}/ (timeline)");
        }
        if !built_timeline(path) {
            return name;
        }
        match &self.timeline {
            Some(loaded) if std::path::absolute(&loaded.cloud.path).is_ok_and(|p| p == path) => {
                timeline_entry_name(&loaded.cloud)
            }
            _ => self
                .open
                .recent
                .name(path)
                .map_or_else(|| "timeline built here".to_string(), str::to_string),
        }
    }

    /// A file (song, cloud) or folder opened as `path` into `cloud`: first in the recent list.
    /// A timeline of several songs is named by no one path: its cloud (in the cache) is kept,
    /// with its name. A timeline built from a folder is listed once, by the folder
    /// (`recent.rs`).
    pub(super) fn opened(&mut self, path: &Path, cloud: &PointCloud) {
        let kept = if path.exists() { path } else { &cloud.path };
        let timeline = built_timeline(&cloud.path).then(|| {
            let folder = crate::ui::recent::common_folder(
                cloud.meta.songs.iter().filter_map(|s| s.open_path()),
            )
            .filter(|f| f.is_dir());
            (folder, timeline_entry_name(cloud))
        });
        let timeline = timeline
            .as_ref()
            .map(|(folder, name)| (folder.as_deref(), name.as_str()));
        if let Err(message) = self.open.recent.add_opened(kept, &cloud.path, timeline) {
            log::warn!("{message}");
        }
    }
}

/// How Recent names a timeline built in the window: `folder/ (timeline)`.
fn timeline_entry_name(cloud: &PointCloud) -> String {
    format!("{} (timeline)", crate::ui::legends::timeline_name(cloud))
}

/// Whether `path` is a timeline built in the window: `timeline-<key>.ply` in the cloud cache.
fn built_timeline(path: &Path) -> bool {
    let cache = crate::extract::cache::dir();
    let cache = std::path::absolute(&cache).unwrap_or(cache);
    let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    file_name(&path).starts_with("timeline-") && path.parent() == Some(cache.as_path())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_open_field_shows_its_whole_hint() {
        let ctx = egui::Context::default();
        let mut path = String::new();
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| {
            ui.add(open_field(&mut path));
        });
        output.textures_delta.clear();
        /// Each text drawn, and whether it was cut short ("song.ogg o…").
        fn texts(shape: &egui::Shape, into: &mut Vec<(String, bool)>) {
            match shape {
                egui::Shape::Text(text) => {
                    into.push((text.galley.text().to_string(), text.galley.elided));
                }
                egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| texts(s, into)),
                _ => {}
            }
        }
        let mut drawn = Vec::new();
        for clipped in &output.shapes {
            texts(&clipped.shape, &mut drawn);
        }
        assert!(
            drawn.iter().any(|(t, _)| t == OPEN_HINT),
            "no hint drawn: {drawn:?}"
        );
        assert!(
            drawn.iter().all(|(_, elided)| !elided),
            "the hint is cut: {drawn:?}"
        );
    }
}
