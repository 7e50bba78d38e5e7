//! Save PNG and Export video… never write over a file the window did not make: a PNG goes only
//! to a `.png` name (Ctrl+S with a video's name in the Screenshot field writes nothing and says
//! why), a video only to an `.mp4` name, and a name already taken by someone else's file is
//! written as `name-2.png` / `name-2.mp4` beside it, said in the status line. Needs a display
//! (`make test` runs it under xvfb-run), ffmpeg for the export.

use crate::common::{self, assert_display, fresh_dir, repo};

use std::path::Path;
use std::process::Command;

/// Runs the window on the demo song with `press`, until its scripted screenshot (taken once an
/// export has ended) is saved into `dir`; returns its stderr.
fn run_window(dir: &Path, press: &[String]) -> String {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::home_in(&mut command, dir)
        .current_dir(dir)
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .arg(repo().join("data/demo_song.ply"))
        .arg("--screenshot")
        .arg(dir.join("window.png"));
    common::run_pressing(&mut command, press)
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_finished_video_survives_ctrl_s_and_a_second_export() {
    let _screen = common::screen();
    assert_display();
    let dir = fresh_dir("window_save_safety_video");
    let video = dir.join("song1.mp4");
    // A finished one-second video, exported from the window.
    let err = run_window(
        &dir,
        &[
            "export-video-end=1".into(),
            format!("export-video={}", video.display()),
        ],
    );
    assert!(video.is_file(), "no video written: {err}");
    let before = std::fs::read(&video).unwrap();
    // The next run: the video's name typed in the Screenshot field, Ctrl+S, and another export
    // asked to go to the same name.
    let err = run_window(
        &dir,
        &[
            format!("shot-path={}", video.display()),
            "Ctrl+S".into(),
            "export-video-end=1".into(),
            format!("export-video={}", video.display()),
        ],
    );
    assert_eq!(
        std::fs::read(&video).unwrap(),
        before,
        "the finished video was written over: {err}"
    );
    assert!(
        err.contains("song1.mp4") && err.contains("not a .png name"),
        "Ctrl+S did not say why it saved nothing: {err}"
    );
    let second = dir.join("song1-2.mp4");
    assert!(second.is_file(), "the second export went nowhere: {err}");
    assert!(
        err.contains(&format!("saved video {}", second.display())) && err.contains("exists"),
        "the window did not say where the second video went and why: {err}"
    );
    let probe = common::ffprobe(&second);
    assert!(
        probe["streams"].as_array().is_some_and(|s| !s.is_empty()),
        "{probe}"
    );
    // Nothing else: no PNG beside the videos but the scripted screenshot of the window.
    assert_eq!(
        files_in(&dir),
        ["song1-2.mp4", "song1.mp4", "window.png"],
        "{err}"
    );
}

#[test]
fn ctrl_s_writes_a_png_the_window_did_not_make_under_a_fresh_name() {
    let _screen = common::screen();
    assert_display();
    let dir = fresh_dir("window_save_safety_png");
    let shot = dir.join("shot.png");
    std::fs::write(&shot, b"someone else's picture").unwrap();
    let err = run_window(
        &dir,
        &[format!("shot-path={}", shot.display()), "Ctrl+S".into()],
    );
    assert_eq!(
        std::fs::read(&shot).unwrap(),
        b"someone else's picture",
        "Ctrl+S wrote over a file it did not make: {err}"
    );
    let fresh = dir.join("shot-2.png");
    let picture = image::open(&fresh)
        .unwrap_or_else(|e| panic!("no PNG at {}: {e}: {err}", fresh.display()))
        .to_rgba8();
    assert!(picture.width() > 64 && picture.height() > 64);
    assert!(
        err.contains(&format!("saved {}", fresh.display())) && err.contains("exists"),
        "the window did not say where the PNG went and why: {err}"
    );
}
