//! "Export video…" in the window: an export started as the button starts it (the scripted
//! `--press export-video=PATH`, which skips the save dialog) runs `loudscape video` off the UI
//! thread and writes an H.264 + AAC MP4 of the view's size; one cancelled once it has begun
//! (`--press export-video-cancel=PATH`, the Cancel button's path) leaves no file. The scripted
//! screenshot run waits for the export to end before it closes the window. Needs a display
//! (`make test` runs it under xvfb-run), ffmpeg and ffprobe.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn assert_display() {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "this test needs a display: run it through `make test` (xvfb-run) or xvfb-run -a cargo test"
    );
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh folder of its own under tests/output.
fn fresh_dir(name: &str) -> PathBuf {
    let dir = repo().join("tests").join("output").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create the test folder");
    dir
}

/// Runs the window on the demo song, pressing `press`, until its screenshot is saved (after
/// the export ended); returns its stderr.
fn run_window(dir: &Path, press: &[String]) -> String {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .arg(repo().join("data/demo_song.ply"))
        .arg("--screenshot")
        .arg(dir.join("window.png"));
    for key in press {
        command.arg("--press").arg(key);
    }
    let output = command.output().expect("start loudscape");
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "loudscape failed: {err}");
    err
}

fn ffprobe(path: &Path) -> serde_json::Value {
    let output = Command::new("ffprobe")
        .args(["-v", "error", "-show_streams", "-of", "json"])
        .arg(path)
        .output()
        .expect("ffprobe (install ffmpeg)");
    assert!(
        output.status.success(),
        "ffprobe failed on {}",
        path.display()
    );
    serde_json::from_slice(&output.stdout).expect("ffprobe json")
}

#[test]
fn export_video_writes_h264_and_aac_of_the_view_s_size() {
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

/// The window's own id, once it is shown (None if the app ended first).
fn wait_for_window(child: &mut std::process::Child) -> Option<String> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(90) {
        if let Ok(Some(_)) = child.try_wait() {
            return None;
        }
        let search = Command::new("xdotool")
            .args(["search", "--all", "--pid", &child.id().to_string()])
            .args(["--name", "^loudscape$"])
            .output()
            .expect("xdotool (scripts/setup-system.sh installs it)");
        let ids = String::from_utf8_lossy(&search.stdout).into_owned();
        if let Some(id) = ids.lines().next() {
            return Some(id.trim().to_string());
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    None
}

/// Processes whose command line names `path`.
fn processes_naming(path: &Path) -> usize {
    let needle = path.to_str().unwrap().as_bytes().to_vec();
    std::fs::read_dir("/proc")
        .unwrap()
        .flatten()
        .filter_map(|e| std::fs::read(e.path().join("cmdline")).ok())
        .filter(|c| c.windows(needle.len()).any(|w| w == needle.as_slice()))
        .count()
}

#[test]
fn closing_the_window_while_exporting_stops_the_export_and_leaves_no_file() {
    assert_display();
    let dir = fresh_dir("window_video_close");
    let video = dir.join("closed.mp4");
    let partial = dir.join("closed.mp4.partial.mp4");
    let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(repo().join("data/demo_song.ply"))
        .args(["--press", &format!("export-video={}", video.display())])
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .env("HOME", &dir)
        .env("XDG_DATA_HOME", &dir)
        .env("XDG_CONFIG_HOME", &dir)
        .env("XDG_STATE_HOME", &dir)
        .env("XDG_CACHE_HOME", &dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    let window = wait_for_window(&mut child);
    // Wait until frames are being encoded (the command's temporary file exists).
    let start = Instant::now();
    while !partial.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(100));
    }
    let encoding = partial.exists();
    if let Some(id) = &window {
        let _ = Command::new("xdotool").args(["windowclose", id]).status();
    }
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(30) && child.try_wait().ok().flatten().is_none() {
        std::thread::sleep(Duration::from_millis(100));
    }
    if child.try_wait().ok().flatten().is_none() {
        let _ = child.kill();
    }
    let output = child.wait_with_output().expect("wait for loudscape");
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
