//! "Export video…" in the window: an export started as the button starts it (the scripted
//! `--press export-video=PATH`, which skips the save dialog) runs `loudscape video` off the UI
//! thread and writes an H.264 + AAC MP4 of the view's size; one cancelled once it has begun
//! (`--press export-video-cancel=PATH`, the Cancel button's path) leaves no file. The scripted
//! screenshot run waits for the export to end before it closes the window. Needs a display
//! (`make test` runs it under xvfb-run), ffmpeg and ffprobe.

use crate::common::{
    self, assert_display, ffprobe, fresh_dir, processes_naming, repo, wait_for_window,
};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs the window on the demo song, pressing `press`, until its screenshot is saved (after
/// the export ended); returns its stderr.
fn run_window(dir: &Path, press: &[String]) -> String {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .arg(repo().join("data/demo_song.ply"))
        .arg("--screenshot")
        .arg(dir.join("window.png"));
    common::run_pressing(&mut command, press)
}

#[test]
fn export_video_writes_h264_and_aac_of_the_view_s_size() {
    let _screen = common::screen();
    assert_display();
    let dir = fresh_dir("window_video_export");
    let video = dir.join("demo export.mp4");
    let err = run_window(
        &dir,
        &[
            "export-video-end=1".into(),
            format!("export-video={}", video.display()),
        ],
    );
    assert!(video.is_file(), "no video written: {err}");
    assert!(
        err.contains(&format!("saved video {}", video.display())),
        "the window did not say where the video went: {err}"
    );
    let probe = ffprobe(&video);
    let streams = probe["streams"].as_array().expect("streams");
    let codecs: Vec<&str> = streams
        .iter()
        .filter_map(|s| s["codec_name"].as_str())
        .collect();
    assert_eq!(codecs.len(), 2, "{probe}");
    assert!(
        codecs.contains(&"h264") && codecs.contains(&"aac"),
        "{codecs:?}"
    );
    let v = streams
        .iter()
        .find(|s| s["codec_type"] == "video")
        .expect("a video stream");
    let (w, h) = (v["width"].as_u64().unwrap(), v["height"].as_u64().unwrap());
    // The 3D view's size rounded down to even sides (the window is smaller than 1280x720's
    // fallback would need to be, and wider than tall).
    assert!(w % 2 == 0 && h % 2 == 0, "{w}x{h}");
    assert!(
        (64..=1600).contains(&w) && (64..=1000).contains(&h),
        "{w}x{h}"
    );
    assert_ne!((w, h), (1280, 720), "the view's size was not used");
    // One second at 30 fps, within a frame.
    let frames: u64 = v["nb_frames"].as_str().unwrap_or("0").parse().unwrap();
    assert!((29..=31).contains(&frames), "{frames} frames");
}

#[test]
fn a_cancelled_export_leaves_no_file() {
    let _screen = common::screen();
    assert_display();
    let dir = fresh_dir("window_video_cancel");
    let video = dir.join("cancelled.mp4");
    let err = run_window(&dir, &[format!("export-video-cancel={}", video.display())]);
    assert!(
        err.contains("video export cancelled"),
        "the window did not say it cancelled: {err}"
    );
    assert!(!video.exists(), "a cancelled export wrote its video");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains("cancelled"))
        .collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

#[test]
fn closing_the_window_while_exporting_stops_the_export_and_leaves_no_file() {
    let _screen = common::screen();
    assert_display();
    let dir = fresh_dir("window_video_close");
    let video = dir.join("closed.mp4");
    // The command's temporary beside the video: `closed.mp4.loudscape-PID.partial.mp4`.
    let partial_of = |dir: &std::path::Path| {
        std::fs::read_dir(dir)
            .ok()?
            .flatten()
            .map(|e| e.path())
            .find(|p| {
                let name = p.file_name().unwrap_or_default().to_string_lossy();
                name.starts_with("closed.mp4.") && name.ends_with(".partial.mp4")
            })
    };
    let mut child = common::home_in(&mut Command::new(env!("CARGO_BIN_EXE_loudscape")), &dir)
        .arg(repo().join("data/demo_song.ply"))
        .args(["--press", &format!("export-video={}", video.display())])
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    let window = wait_for_window(&mut child);
    // Wait until frames are being encoded (the command's temporary file exists).
    let start = Instant::now();
    while partial_of(&dir).is_none() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(100));
    }
    let partial = partial_of(&dir);
    let encoding = partial.is_some();
    let partial = partial.unwrap_or_else(|| dir.join("closed.mp4.partial.mp4"));
    if let Some(id) = &window {
        let _ = Command::new("xdotool").args(["windowclose", id]).status();
    }
    let output = common::exit_within_30_s(child);
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(window.is_some(), "the window did not appear: {err}");
    assert!(encoding, "the export never started: {err}");
    assert_eq!(output.status.code(), Some(0), "closing must exit 0: {err}");
    // The export is stopped with the window, and cleans up after itself at once.
    let start = Instant::now();
    while processes_naming(&partial) > 0 && start.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(processes_naming(&partial), 0, "the export still runs");
    assert!(
        !video.exists(),
        "a video was written after the window closed"
    );
    assert!(!partial.exists(), "the partial file is left");
}
