//! The side panel's Video row: "Export video…", the passage (start and end: the loop range
//! when one is set, else the whole song) and the file's name. The shown cloud becomes an MP4
//! through the app's own `loudscape video`, started as a child process with the window's view,
//! camera, size and settings, so the window never blocks. A video goes only to an `.mp4` name,
//! and never over a file this window did not write (`state/written.rs`: `name-2.mp4` instead,
//! said in the status line); the native save dialog, where one can open, asks itself. A thread reads the child's `--progress json`
//! lines; the status area under the view shows the frames done, fps and ETA with a progress
//! bar and Cancel (SIGTERM: the command stops at once and leaves no partial file). Closing the
//! window stops an export still running (`state/video_export.rs`).

use std::ffi::OsString;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::mpsc::{TryRecvError, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use eframe::egui::{self, RichText};

use crate::data::cloud::DataMode;
use crate::data::freq_axis::FreqAxis;
use crate::data::normalize::Normalization;
use crate::render::scene::RenderSettings;
use crate::render::volume::VolumeSettings;
use crate::ui::open::file_name;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::messages::{Kind, VIDEO_EXPORT};
use crate::ui::state::video_export::{RunningExport, VideoProgress};
use crate::ui::state::written;
use crate::value_name;
use crate::view::camera::Camera;

/// The frame size when the view's own cannot be a video's (odd, tiny or over 3840x2160).
const FALLBACK_SIZE: (u32, u32) = (1280, 720);

/// What `loudscape video` writes (its `-o` takes only this).
pub(super) const VIDEO_EXTENSION: &str = "mp4";

/// What an export takes from the window.
#[derive(Clone, Debug)]
pub(super) struct ExportChoice {
    /// The shown cloud's file.
    pub(super) input: PathBuf,
    pub(super) output: PathBuf,
    /// A timeline (no frequency axis, no passage; a normalization preset applies).
    pub(super) timeline: bool,
    pub(super) settings: RenderSettings,
    /// The window's camera; `None` while it waits for its first fit (the command fits).
    pub(super) camera: Option<Camera>,
    /// The 3D view's size in pixels.
    pub(super) view_px: (u32, u32),
    pub(super) freq_axis: FreqAxis,
    /// Timeline mode's "level as heard" choice.
    pub(super) normalize: Normalization,
    /// A song's passage, seconds (start, end); `None`: the whole song.
    pub(super) passage: Option<(f64, f64)>,
}

/// The passage a song's export covers: the start and end fields once edited, else the loop
/// range when one is set, else the whole song (`None`).
pub(super) fn export_passage(
    edited: Option<(f64, f64)>,
    looped: Option<(f64, f64)>,
) -> Option<(f64, f64)> {
    edited.or(looped.filter(|(start, end)| end > start))
}

/// The frame size a view of `px` exports at: its size rounded down to even sides, or
/// [`FALLBACK_SIZE`] where that is too small or larger than `video` takes.
pub(super) fn video_size(px: (u32, u32)) -> (u32, u32) {
    let (w, h) = (px.0 & !1, px.1 & !1);
    if w < 64 || h < 64 || w > 3840 || u64::from(w) * u64::from(h) > 3840 * 2160 {
        FALLBACK_SIZE
    } else {
        (w, h)
    }
}

/// The arguments of `loudscape video` (after the program) for `choice`: only options `video`
/// takes, with values inside its ranges. The song and the output go as absolute paths, byte for
/// byte: a name that is not UTF-8 is not mangled, and none starts with `-` (an option).
pub(super) fn video_args(choice: &ExportChoice) -> Vec<OsString> {
    let absolute = |p: &std::path::Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut args: Vec<OsString> = vec![
        "video".into(),
        absolute(&choice.input).into_os_string(),
        "-o".into(),
        absolute(&choice.output).into_os_string(),
    ];
    args.extend(option_args(choice).into_iter().map(OsString::from));
    args
}

/// The options of [`video_args`] after the paths.
fn option_args(choice: &ExportChoice) -> Vec<String> {
    let s = &choice.settings;
    let (w, h) = video_size(choice.view_px);
    let mut args: Vec<String> = vec!["--view".into(), value_name(&s.view)];
    if let Some(camera) = choice.camera {
        args.push(format!(
            "--camera-at={:.3},{:.3},{:.4}",
            camera.azimuth.to_degrees(),
            camera.elevation.to_degrees(),
            camera.distance.max(1e-3)
        ));
    }
    let clamp =
        |v: f32, range: std::ops::RangeInclusive<f32>| v.clamp(*range.start(), *range.end());
    args.extend([
        "--size".into(),
        format!("{w}x{h}"),
        "--progress".into(),
        "json".into(),
        "--colormap".into(),
        value_name(&s.colours.hp),
        "--tf-colormap".into(),
        value_name(&s.colours.density),
        "--background".into(),
        value_name(&s.colours.background),
        "--method".into(),
        value_name(&s.surface.method),
        "--iso".into(),
        format!("{}", s.surface.iso_value.clamp(0.0, 1.0)),
        "--tf".into(),
        value_name(&s.volume.preset),
        "--density".into(),
        format!(
            "{}",
            clamp(s.volume.density_scale, VolumeSettings::DENSITY_RANGE)
        ),
        "--opacity".into(),
        format!(
            "{}",
            clamp(s.volume.opacity_scale, VolumeSettings::OPACITY_RANGE)
        ),
        "--point-size".into(),
        format!("{}", s.points.size_px.clamp(0.5, 64.0)),
    ]);
    if s.volume.hp_tint {
        args.push("--hp-tint".into());
    }
    if !s.volume.shading {
        args.push("--no-shading".into());
    }
    if !s.show_box {
        // The window draws the axis labels with the box.
        args.push("--no-labels".into());
    }
    if choice.timeline {
        if choice.normalize != Normalization::AsMastered {
            args.extend(["--normalize".into(), value_name(&choice.normalize)]);
        }
    } else {
        if choice.freq_axis != FreqAxis::Linear {
            args.extend(["--freq-axis".into(), value_name(&choice.freq_axis)]);
        }
        if let Some((start, end)) = choice.passage {
            args.extend([
                "--start".into(),
                format!("{start}"),
                "--end".into(),
                format!("{end}"),
            ]);
        }
    }
    args
}

impl LoudscapeApp {
    /// The Video row: Export video…, the passage's start and end (a song's), and the name.
    pub(super) fn video_controls(&mut self, ui: &mut egui::Ui) {
        let exportable = self
            .active()
            .is_some_and(|l| l.cloud.meta.mode != DataMode::Generic);
        let idle = self.video_export.running.is_none() && self.video_export.save_dialog.is_none();
        let passage = self.passage_row();
        let ordered = passage.is_none_or(|p| p.start < p.end);
        ui.horizontal_wrapped(|ui| {
            let button = ui
                .add_enabled(
                    exportable && idle && ordered,
                    egui::Button::new("Export video…"),
                )
                .on_hover_text(
                    "An MP4 (H.264 + AAC) of this view, camera and settings with the playhead \
                     moving through the passage and its sound (a timeline sweeps across its \
                     years): loudscape video",
                )
                .on_disabled_hover_text(if !exportable {
                    "open a song or a timeline: a cloud without a time axis has no video"
                } else if !idle {
                    "an export is under way (its Cancel is under the view)"
                } else {
                    "the start must come before the end"
                });
            if button.clicked() {
                self.ask_where_to_export(crate::ui::open::dialogs_available());
            }
            if let Some(mut p) = passage {
                let start = ui
                    .add(
                        egui::DragValue::new(&mut p.start)
                            .range(0.0..=p.duration)
                            .speed(0.1)
                            .fixed_decimals(1)
                            .suffix(" s"),
                    )
                    .on_hover_text("the video's start, seconds into the song");
                ui.label("to");
                let end = ui
                    .add(
                        egui::DragValue::new(&mut p.end)
                            .range(0.0..=p.duration)
                            .speed(0.1)
                            .fixed_decimals(1)
                            .suffix(" s"),
                    )
                    .on_hover_text("the video's end, seconds into the song");
                if start.changed() || end.changed() {
                    self.video_export.passage = Some((p.start, p.end));
                }
                if p.looped {
                    ui.label(RichText::new("the loop").small().weak())
                        .on_hover_text("the loop range under the view; edit to choose another");
                }
            }
        });
        let hint = format!("{}.{VIDEO_EXTENSION}", self.export_stem());
        ui.add(
            egui::TextEdit::singleline(&mut self.video_export.path)
                .hint_text(hint)
                .desired_width(ui.available_width().min(230.0)),
        )
        .on_hover_text(
            "where Export video… writes: an .mp4 name (the save dialog starts from it where one \
             can open); a file this window did not write is kept, and the video goes to \
             name-2.mp4 beside it",
        );
    }

    /// The start and end fields of the shown song (Song mode; a timeline sweeps its years):
    /// the edited passage, else the loop range, else the whole song. Edits made for another
    /// song are forgotten.
    fn passage_row(&mut self) -> Option<PassageRow> {
        let loaded = self.active()?;
        if loaded.cloud.meta.mode != DataMode::Song {
            return None;
        }
        let (id, duration) = (loaded.id, crate::playback::song_duration_s(&loaded.cloud));
        if self.video_export.passage_for != Some(id) {
            self.video_export.passage = None;
            self.video_export.passage_for = Some(id);
        }
        let chosen = export_passage(self.video_export.passage, self.audio.loop_shown());
        let (start, end) = chosen.unwrap_or((0.0, duration));
        Some(PassageRow {
            start,
            end,
            duration,
            looped: self.video_export.passage.is_none() && chosen.is_some(),
        })
    }

    /// Asks where to write the video: the native dialog, starting from the Video field's name
    /// (else `<song>.mp4`), where one can open (it asks before replacing a file); else that
    /// name itself, or `name-2.mp4` beside it when a file this window did not write has it.
    fn ask_where_to_export(&mut self, dialog: bool) {
        let typed = self.video_export.path.trim().to_string();
        let name = if typed.is_empty() {
            PathBuf::from(format!("{}.{VIDEO_EXTENSION}", self.export_stem()))
        } else {
            PathBuf::from(&typed)
        };
        let Ok(name) = written::of_kind(&name, VIDEO_EXTENSION) else {
            self.messages.error(format!(
                "Export video: {} is not an .{VIDEO_EXTENSION} name: nothing exported (the \
                 video is H.264 + AAC in MP4)",
                name.display()
            ));
            return;
        };
        if dialog {
            self.video_export.save_dialog = Some(crate::ui::open::save_dialog_as(
                "Export the view as a video",
                ("MP4 video", VIDEO_EXTENSION),
                &name.display().to_string(),
            ));
            return;
        }
        let (path, renamed) = written::target(&name, &self.video_export.made);
        if renamed {
            self.messages.say(
                VIDEO_EXPORT,
                Kind::Warning,
                format!(
                    "{} exists and this window did not write it: exporting to {} instead",
                    name.display(),
                    path.display()
                ),
            );
        } else if typed.is_empty() {
            self.messages.say(
                VIDEO_EXPORT,
                Kind::Info,
                format!(
                    "{}: exporting to {} (type a name in the Video field to choose)",
                    crate::ui::open::NO_DIALOG,
                    path.display()
                ),
            );
        }
        self.start_video_export(path);
    }

    /// The shown song's name (its audio file's stem), the timeline's as its legend names it,
    /// or the cloud's.
    fn export_stem(&self) -> String {
        let Some(loaded) = self.active() else {
            return "loudscape".into();
        };
        let from = match loaded.cloud.meta.mode {
            DataMode::Song => {
                crate::playback::resolve_source(&loaded.cloud).unwrap_or(loaded.cloud.path.clone())
            }
            DataMode::Timeline => {
                return crate::ui::state::video_export::timeline_video_stem(&loaded.cloud);
            }
            _ => loaded.cloud.path.clone(),
        };
        from.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "loudscape".into())
    }

    /// What the window shows, for an export to `output`.
    fn export_choice(&mut self, output: PathBuf) -> Option<ExportChoice> {
        let loaded = self.active()?;
        let input = std::path::absolute(&loaded.cloud.path).unwrap_or(loaded.cloud.path.clone());
        Some(ExportChoice {
            input,
            output,
            timeline: loaded.cloud.meta.mode == DataMode::Timeline,
            settings: self.settings.clone(),
            camera: self.motion.settled_camera(),
            view_px: self.view_px,
            freq_axis: self.freq_axis,
            normalize: self.heard.preset,
            passage: self.passage_row().and_then(|p| {
                // The whole song is no passage (the command's default, to the sample).
                (p.start > 0.0 || p.end < p.duration).then_some((p.start, p.end))
            }),
        })
    }

    /// Starts `loudscape video` writing `output` (an `.mp4` name: the dialog's answer, or
    /// [`Self::ask_where_to_export`]'s), its progress read on threads.
    pub(super) fn start_video_export(&mut self, output: PathBuf) {
        if self.video_export.running.is_some() {
            return;
        }
        let output = std::path::absolute(&output).unwrap_or(output);
        let Some(choice) = self.export_choice(output.clone()) else {
            self.messages.error("export video: no song is shown");
            return;
        };
        if choice.camera.is_some_and(|c| c.target.length() > 1e-3) {
            // `video --camera-at` orbits the data's centre: a pan is not carried over.
            self.messages
                .warn("export video: the video is centred on the data (the pan is not kept)");
        }
        let program = match std::env::current_exe() {
            Ok(program) => program,
            Err(e) => {
                self.messages.error(format!(
                    "export video: cannot find the loudscape program: {e}"
                ));
                return;
            }
        };
        let mut command = Command::new(program);
        command
            .args(video_args(&choice))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        crate::files::stop_with_parent(&mut command);
        let mut child = match command.spawn() {
            Ok(child) => child,
            Err(e) => {
                self.messages.error(format!("export video: {e}"));
                return;
            }
        };
        let (sender, progress) = channel();
        let last_error = Arc::new(Mutex::new(String::new()));
        if let Some(stdout) = child.stdout.take() {
            std::thread::spawn(move || {
                for line in BufReader::new(stdout).lines() {
                    let Ok(line) = line else { break };
                    if let Some(p) = VideoProgress::parse(&line)
                        && sender.send(p).is_err()
                    {
                        break;
                    }
                }
            });
        }
        let stderr_reader = child.stderr.take().map(|stderr| {
            let last = last_error.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines() {
                    let Ok(line) = line else { break };
                    // A log for scripts and tests, as the window's own messages are.
                    eprintln!("{line}");
                    if !line.trim().is_empty()
                        && let Ok(mut kept) = last.lock()
                    {
                        *kept = line.trim().to_string();
                    }
                }
            })
        });
        self.video_export.running = Some(RunningExport {
            child,
            output,
            progress,
            latest: None,
            last_error,
            stderr_reader,
            cancelled: false,
        });
    }

    /// Follows the save dialog and the export under way; says how it ended.
    pub(super) fn poll_video_export(&mut self, ctx: &egui::Context) {
        let answer = self.video_export.save_dialog.as_ref().map(|r| r.try_recv());
        match answer {
            Some(Ok(picked)) => {
                self.video_export.save_dialog = None;
                // The dialog asked before replacing a file; the name must still be a video's.
                match picked.map(|path| {
                    written::of_kind(&path, VIDEO_EXTENSION)
                        .map(|named| (named != path, named))
                        .map_err(|_| path)
                }) {
                    Some(Ok((false, path))) => self.start_video_export(path),
                    // A name the dialog did not give (".mp4" added) was not asked about.
                    Some(Ok((true, path))) => {
                        let (path, _) = written::target(&path, &self.video_export.made);
                        self.start_video_export(path);
                    }
                    Some(Err(path)) => self.messages.error(format!(
                        "Export video: {} is not an .{VIDEO_EXTENSION} name: nothing exported",
                        path.display()
                    )),
                    None => {}
                }
            }
            Some(Err(TryRecvError::Disconnected)) => self.video_export.save_dialog = None,
            Some(Err(TryRecvError::Empty)) => ctx.request_repaint_after(Duration::from_millis(100)),
            None => {}
        }
        let cancel_at_start = self.video_export.cancel_at_start;
        let Some(running) = self.video_export.running.as_mut() else {
            return;
        };
        while let Ok(p) = running.progress.try_recv() {
            running.latest = Some(p);
        }
        if cancel_at_start && running.latest.is_some() && !running.cancelled {
            running.cancelled = true;
            running.stop();
        }
        let ended = match running.child.try_wait() {
            Ok(Some(status)) => Some(Ok(status)),
            Ok(None) => None,
            Err(e) => Some(Err(e)),
        };
        let reader_done = running
            .stderr_reader
            .as_ref()
            .is_none_or(|r| r.is_finished());
        let Some(ended) = ended.filter(|_| reader_done) else {
            ctx.request_repaint_after(Duration::from_millis(100));
            return;
        };
        let Some(running) = self.video_export.running.take() else {
            return;
        };
        self.video_export.cancel_at_start = false;
        let last_error = running
            .last_error
            .lock()
            .map(|l| l.clone())
            .unwrap_or_default();
        match ended {
            _ if running.cancelled => {
                self.messages
                    .say(VIDEO_EXPORT, Kind::Info, "video export cancelled")
            }
            Ok(status) if status.success() && running.output.is_file() => {
                let frames = running
                    .latest
                    .map_or(String::new(), |p| format!(" ({} frames)", p.frames));
                self.video_export.made.record(&running.output);
                self.messages.say(
                    VIDEO_EXPORT,
                    Kind::Info,
                    format!("saved video {}{frames}", running.output.display()),
                );
            }
            Ok(_) => self.messages.say(
                VIDEO_EXPORT,
                Kind::Error,
                format!(
                    "video export to {} failed: {}",
                    file_name(&running.output),
                    if last_error.is_empty() {
                        "the video command stopped without saying why".to_string()
                    } else {
                        last_error.trim_start_matches("error: ").to_string()
                    }
                ),
            ),
            Err(e) => self
                .messages
                .say(VIDEO_EXPORT, Kind::Error, format!("video export: {e}")),
        }
        ctx.request_repaint();
    }

    /// The export's row in the status area: the frames done, fps, ETA, a bar and Cancel.
    pub(super) fn video_export_progress(&mut self, ui: &mut egui::Ui) {
        let Some(running) = self.video_export.running.as_mut() else {
            return;
        };
        let mut cancel = false;
        ui.horizontal_wrapped(|ui| {
            ui.spinner();
            ui.label(RichText::new(file_name(&running.output)).strong());
            if running.cancelled {
                ui.label("cancelling…");
                return;
            }
            let (fraction, text) = match running.latest {
                Some(p) => (
                    p.fraction(),
                    format!(
                        "Exporting video: frame {} of {}, {:.1} fps, ETA {}",
                        p.frame,
                        p.frames,
                        p.fps,
                        crate::playback::format_clock(p.eta_s)
                    ),
                ),
                None => (0.0, "Exporting video: starting…".to_string()),
            };
            ui.add(
                egui::ProgressBar::new(fraction)
                    .text(text)
                    .desired_width(420.0),
            );
            cancel = ui
                .small_button("Cancel")
                .on_hover_text("stop the export; no file is left")
                .clicked();
        });
        if cancel {
            running.cancelled = true;
            running.stop();
        }
    }

    /// The scripted presses of tests: `export-video=PATH` types PATH in the Video field and
    /// presses Export video… where no dialog opens, `export-video-cancel=PATH` does so and
    /// cancels the export once it has begun, `export-video-end=SECONDS` sets the end field
    /// (a short video).
    pub(super) fn scripted_video_export(&mut self, name: &str) -> bool {
        if let Some(end) = name.strip_prefix("export-video-end=") {
            match (end.parse::<f64>(), self.passage_row()) {
                (Ok(end), Some(row)) if end > row.start && end <= row.duration => {
                    self.video_export.passage = Some((row.start, end));
                }
                _ => self
                    .messages
                    .error(format!("--press {name}: not a time in the song")),
            }
        } else if let Some(path) = name.strip_prefix("export-video-cancel=") {
            self.video_export.cancel_at_start = true;
            self.video_export.path = path.to_string();
            self.ask_where_to_export(false);
        } else if let Some(path) = name.strip_prefix("export-video=") {
            self.video_export.path = path.to_string();
            self.ask_where_to_export(false);
        } else {
            return false;
        }
        true
    }

    /// Whether an export (or its save dialog) is under way: a scripted screenshot waits.
    pub(super) fn video_exporting(&self) -> bool {
        self.video_export.running.is_some() || self.video_export.save_dialog.is_some()
    }
}

/// The start and end fields as the Video row shows them, seconds.
#[derive(Clone, Copy, Debug)]
struct PassageRow {
    start: f64,
    end: f64,
    duration: f64,
    /// Taken from the loop range (not edited).
    looped: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::colormap::{Background, HpColourMap};
    use crate::render::scene::ViewKind;
    use crate::render::surface::SurfaceMethod;
    use crate::render::volume::TransferPreset;

    fn choice() -> ExportChoice {
        let mut settings = RenderSettings {
            view: ViewKind::Surface,
            ..Default::default()
        };
        settings.colours.hp = HpColourMap::Cividis;
        settings.colours.background = Background::Light;
        settings.surface.method = SurfaceMethod::DualContouring;
        settings.surface.iso_value = 0.35;
        settings.volume.preset = TransferPreset::Ember;
        settings.volume.density_scale = 2.0;
        settings.volume.opacity_scale = 0.5;
        settings.volume.hp_tint = true;
        settings.points.size_px = 3.0;
        ExportChoice {
            input: PathBuf::from("/music/song.ply"),
            output: PathBuf::from("/out/song.mp4"),
            timeline: false,
            settings,
            camera: Some(Camera::from_angles(-35.0, 25.0, 4.0)),
            view_px: (1101, 641),
            freq_axis: FreqAxis::Mel,
            normalize: Normalization::Preset(crate::data::normalize::PRESETS[0]),
            passage: None,
        }
    }

    #[test]
    fn the_window_s_view_camera_and_settings_become_video_s_arguments() {
        let args = video_args(&choice());
        let expected = [
            "video",
            "/music/song.ply",
            "-o",
            "/out/song.mp4",
            "--view",
            "surface",
            "--camera-at=325.000,25.000,4.0000",
            "--size",
            "1100x640",
            "--progress",
            "json",
            "--colormap",
            "cividis",
            "--tf-colormap",
            "preset",
            "--background",
            "light",
            "--method",
            "dc",
            "--iso",
            "0.35",
            "--tf",
            "ember",
            "--density",
            "2",
            "--opacity",
            "0.5",
            "--point-size",
            "3",
            "--hp-tint",
            // A song: its frequency axis; the normalization preset is Timeline mode's only.
            "--freq-axis",
            "mel",
        ];
        assert_eq!(args, expected);
    }

    #[test]
    fn a_timeline_takes_its_preset_and_no_frequency_axis_or_passage() {
        let mut c = choice();
        c.timeline = true;
        c.passage = Some((1.0, 2.0));
        c.camera = None;
        c.settings.show_box = false;
        c.settings.volume.shading = false;
        let args = video_args(&c);
        assert!(
            !args
                .iter()
                .any(|a| a.to_string_lossy().starts_with("--camera-at"))
        );
        assert!(
            !args
                .iter()
                .any(|a| a == "--freq-axis" || a == "--end" || a == "--start")
        );
        let tail = &args[args.len() - 4..];
        assert_eq!(
            tail,
            ["--no-shading", "--no-labels", "--normalize", "spotify"]
        );
        // A song's passage.
        let mut song = choice();
        song.passage = Some((12.25, 31.5));
        let args = video_args(&song);
        assert_eq!(
            &args[args.len() - 4..],
            ["--start", "12.25", "--end", "31.5"]
        );
    }

    #[test]
    fn the_passage_is_the_edited_one_else_the_loop_else_the_whole_song() {
        assert_eq!(export_passage(None, None), None, "the whole song");
        assert_eq!(export_passage(None, Some((10.0, 20.0))), Some((10.0, 20.0)));
        // A loop range not yet set (0 to 0) is no passage.
        assert_eq!(export_passage(None, Some((0.0, 0.0))), None);
        assert_eq!(
            export_passage(Some((3.0, 4.5)), Some((10.0, 20.0))),
            Some((3.0, 4.5)),
            "the fields, once edited, win over the loop"
        );
    }

    #[test]
    fn the_size_is_even_and_within_what_video_takes() {
        assert_eq!(video_size((1281, 721)), (1280, 720));
        assert_eq!(video_size((3840, 2160)), (3840, 2160));
        assert_eq!(video_size((5000, 2000)), FALLBACK_SIZE);
        assert_eq!(video_size((40, 30)), FALLBACK_SIZE);
    }

    #[test]
    fn every_built_argument_list_is_accepted_by_video_s_parser() {
        // The arguments parse as the values `video` checks them (ranges, names).
        let mut c = choice();
        c.settings.surface.iso_value = 7.0;
        c.settings.volume.density_scale = 100.0;
        c.settings.points.size_px = 0.0;
        let args = video_args(&c);
        let value = |flag: &str| {
            let i = args.iter().position(|a| a == flag).expect(flag);
            args[i + 1].clone()
        };
        assert_eq!(value("--iso"), "1");
        assert_eq!(value("--density"), "8");
        assert_eq!(value("--point-size"), "0.5");
        let text = |flag: &str| {
            value(flag)
                .into_string()
                .expect("an option's value is text")
        };
        assert!(HpColourMap::parse(&text("--colormap")).is_some());
        assert!(TransferPreset::parse(&text("--tf")).is_some());
        assert!(SurfaceMethod::parse(&text("--method")).is_some());
    }

    /// Any name a file system allows reaches `video` as that file: a song whose name is not
    /// UTF-8 (it was passed as its lossy display, a name that does not exist), and relative names
    /// starting with `-`, which `video` would have read as options.
    #[cfg(unix)]
    #[test]
    fn odd_names_reach_video_as_the_files_they_are() {
        use std::os::unix::ffi::OsStrExt;
        let mut c = choice();
        c.input = PathBuf::from(std::ffi::OsStr::from_bytes(b"/music/caf\xe9.ply"));
        c.output = PathBuf::from("-x.mp4");
        let args = video_args(&c);
        assert_eq!(args[1].as_bytes(), b"/music/caf\xe9.ply");
        assert_eq!(args[2], "-o");
        let output = std::path::Path::new(&args[3]);
        assert!(output.is_absolute(), "{output:?}");
        assert!(output.ends_with("-x.mp4"), "{output:?}");
    }
}
