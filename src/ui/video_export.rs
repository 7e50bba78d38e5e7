//! "Export video…" in the side panel's Screenshot section: the shown cloud as an MP4 through
//! the app's own `loudscape video`, started as a child process with the window's view, camera,
//! size and settings, so the window never blocks. A thread reads the child's `--progress json`
//! lines; the status area under the view shows the frames done, fps and ETA with a progress
//! bar and Cancel (SIGTERM: the command stops at once and leaves no partial file). Closing the
//! window stops an export still running (`state/video_export.rs`).

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::mpsc::{TryRecvError, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use eframe::egui::{self, RichText};

use crate::data::cloud::DataMode;
use crate::data::freq_axis::FreqAxis;
use crate::render::scene::RenderSettings;
use crate::render::volume::VolumeSettings;
use crate::ui::open::file_name;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::video_export::{RunningExport, VideoProgress};
use crate::view::camera::Camera;

/// The frame size when the view's own cannot be a video's (odd, tiny or over 3840x2160).
const FALLBACK_SIZE: (u32, u32) = (1280, 720);

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
    /// Timeline mode's "level as heard" preset key.
    pub(super) normalize: Option<&'static str>,
    /// The passage's end, seconds (scripted test runs only).
    pub(super) end: Option<f64>,
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
/// takes, with values inside its ranges.
pub(super) fn video_args(choice: &ExportChoice) -> Vec<String> {
    let s = &choice.settings;
    let (w, h) = video_size(choice.view_px);
    let lower = |name: &str| name.to_ascii_lowercase();
    let mut args: Vec<String> = vec![
        "video".into(),
        choice.input.display().to_string(),
        "-o".into(),
        choice.output.display().to_string(),
        "--view".into(),
        lower(s.view.name()),
    ];
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
        lower(s.colours.hp.name()),
        "--tf-colormap".into(),
        lower(s.colours.density.name()),
        "--background".into(),
        s.colours.background.name().into(),
        "--method".into(),
        s.surface.method.short_name().into(),
        "--iso".into(),
        format!("{}", s.surface.iso_value.clamp(0.0, 1.0)),
        "--tf".into(),
        lower(s.volume.preset.name()),
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
        if let Some(key) = choice.normalize {
            args.extend(["--normalize".into(), key.into()]);
        }
    } else {
        if choice.freq_axis != FreqAxis::Linear {
            args.extend(["--freq-axis".into(), choice.freq_axis.name().into()]);
        }
        if let Some(end) = choice.end {
            args.extend(["--end".into(), format!("{end}")]);
        }
    }
    args
}

impl LoudscapeApp {
    /// The "Export video…" button, beside Save PNG.
    pub(super) fn export_video_button(&mut self, ui: &mut egui::Ui) {
        let exportable = self
            .active()
            .is_some_and(|l| l.cloud.meta.mode != DataMode::Generic);
        let idle = self.video_export.running.is_none() && self.video_export.save_dialog.is_none();
        if ui
            .add_enabled(exportable && idle, egui::Button::new("Export video…"))
            .on_hover_text(
                "An MP4 (H.264 + AAC) of this view, camera and settings with the playhead moving \
                 through the song and its sound (a timeline sweeps across its years): \
                 loudscape video",
            )
            .clicked()
        {
            self.ask_where_to_export();
        }
    }

    /// Asks where to write the video (native dialog, `<song>.mp4` in the current folder); where
    /// no dialog can open, the Screenshot field's path if it names an .mp4, else that name.
    fn ask_where_to_export(&mut self) {
        let name = PathBuf::from(format!("{}.mp4", self.export_stem()));
        if crate::ui::open::dialogs_available() {
            self.video_export.save_dialog = Some(crate::ui::open::save_dialog_as(
                "Export the view as a video",
                ("MP4 video", "mp4"),
                &name.display().to_string(),
            ));
            return;
        }
        let typed = PathBuf::from(self.save_shot.path.trim());
        let typed_mp4 = typed
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mp4"));
        let path = if typed_mp4 { typed } else { name };
        self.messages.warn(format!(
            "{}: exporting to {} (type a .mp4 path in the Screenshot field to choose)",
            crate::ui::open::NO_DIALOG,
            path.display()
        ));
        self.start_video_export(path);
    }

    /// The shown song's name (its audio file's stem), or the cloud's.
    fn export_stem(&self) -> String {
        let Some(loaded) = self.active() else {
            return "loudscape".into();
        };
        let from = if loaded.cloud.meta.mode == DataMode::Song {
            crate::playback::resolve_source(&loaded.cloud).unwrap_or(loaded.cloud.path.clone())
        } else {
            loaded.cloud.path.clone()
        };
        from.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "loudscape".into())
    }

    /// What the window shows, for an export to `output`.
    fn export_choice(&self, output: PathBuf) -> Option<ExportChoice> {
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
            normalize: self.heard.preset_key(),
            end: self.video_export.test_end,
        })
    }

    /// Starts `loudscape video` writing `output`, its progress read on threads.
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
        stop_with_parent(&mut command);
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
                if let Some(path) = picked {
                    self.start_video_export(path);
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
            _ if running.cancelled => self.messages.info("video export cancelled"),
            Ok(status) if status.success() && running.output.is_file() => {
                let frames = running
                    .latest
                    .map_or(String::new(), |p| format!(" ({} frames)", p.frames));
                self.messages
                    .info(format!("saved video {}{frames}", running.output.display()));
            }
            Ok(_) => self.messages.error(format!(
                "video export to {} failed: {}",
                file_name(&running.output),
                if last_error.is_empty() {
                    "the video command stopped without saying why".to_string()
                } else {
                    last_error.trim_start_matches("error: ").to_string()
                }
            )),
            Err(e) => self.messages.error(format!("video export: {e}")),
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

    /// The scripted presses of tests: `export-video=PATH` exports to PATH as the button does
    /// (no dialog), `export-video-cancel=PATH` starts one and cancels it once it has begun,
    /// `export-video-end=SECONDS` makes the next one short (`--end`).
    pub(super) fn scripted_video_export(&mut self, name: &str) -> bool {
        if let Some(end) = name.strip_prefix("export-video-end=") {
            match end.parse::<f64>() {
                Ok(end) if end > 0.0 => self.video_export.test_end = Some(end),
                _ => self.messages.error(format!("--press {name}: not a time")),
            }
        } else if let Some(path) = name.strip_prefix("export-video-cancel=") {
            self.video_export.cancel_at_start = true;
            self.start_video_export(PathBuf::from(path));
        } else if let Some(path) = name.strip_prefix("export-video=") {
            self.start_video_export(PathBuf::from(path));
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

/// Linux: the child gets SIGTERM if the window's process dies without stopping it, so it still
/// removes its partial file.
fn stop_with_parent(command: &mut Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: between fork and exec the closure only calls prctl(2), which is
        // async-signal-safe and touches no memory of the parent.
        unsafe {
            command.pre_exec(|| {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = command;
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
            normalize: Some("spotify"),
            end: None,
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
        c.end = Some(2.0);
        c.camera = None;
        c.settings.show_box = false;
        c.settings.volume.shading = false;
        let args = video_args(&c);
        assert!(!args.iter().any(|a| a.starts_with("--camera-at")));
        assert!(!args.iter().any(|a| a == "--freq-axis" || a == "--end"));
        let tail = &args[args.len() - 4..];
        assert_eq!(
            tail,
            ["--no-shading", "--no-labels", "--normalize", "spotify"]
        );
        // A song's test passage.
        let mut song = choice();
        song.end = Some(1.5);
        let args = video_args(&song);
        assert_eq!(&args[args.len() - 2..], ["--end", "1.5"]);
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
        assert!(HpColourMap::parse(&value("--colormap")).is_some());
        assert!(TransferPreset::parse(&value("--tf")).is_some());
        assert!(SurfaceMethod::parse(&value("--method")).is_some());
    }
}
