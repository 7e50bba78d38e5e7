//! What the app tells the user is in sight: the status area under the 3D view shows a warning
//! (no file dialog can open here) at once, wherever the side panel is scrolled; and closing the
//! window from outside (the window manager's close, as `xdotool windowclose` sends) exits
//! cleanly, as the close button does. Needs a display (`make test` runs them under xvfb-run) and
//! xdotool.

use crate::common::{self, assert_display, repo, wait_for_window};

use std::path::Path;
use std::process::{Command, Stdio};

/// Runs the window on the demo song until its screenshot is saved, pressing `press`.
fn screenshot(shot: &Path, press: &[&str]) -> (image::RgbaImage, String) {
    screenshot_of(&repo().join("data/demo_song.ply"), shot, press)
}

/// Runs the window on `cloud` until its screenshot is saved, pressing `press`.
fn screenshot_of(cloud: &Path, shot: &Path, press: &[&str]) -> (image::RgbaImage, String) {
    let _ = std::fs::remove_file(shot);
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::no_dialog(&mut command)
        .arg(cloud)
        .arg("--screenshot")
        .arg(shot);
    for key in press {
        command.arg("--press").arg(key);
    }
    let output = command.output().expect("start loudscape");
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "loudscape failed: {err}");
    let image = image::open(shot)
        .unwrap_or_else(|e| panic!("no screenshot at {}: {e}", shot.display()))
        .to_rgba8();
    (image, err)
}

/// Pixels in the warning colour right of the side panel, in the window's lower half (under the
/// 3D view, where the status area is).
fn warning_pixels(image: &image::RgbaImage) -> usize {
    let (w, h) = image.dimensions();
    let [r, g, b, _] = loudscape_warning();
    (h / 2..h)
        .flat_map(|y| (300.min(w)..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = image.get_pixel(x, y);
            p[0].abs_diff(r) < 14 && p[1].abs_diff(g) < 14 && p[2].abs_diff(b) < 14
        })
        .count()
}

/// The warning colour of the status area (ui/messages.rs `WARNING`).
fn loudscape_warning() -> [u8; 4] {
    [230, 190, 110, 255]
}

#[test]
fn the_no_dialog_warning_shows_under_the_view_at_once() {
    let _screen = common::screen();
    assert_display();
    let dir = common::output_dir();
    let (quiet, _) = screenshot(&dir.join("window_messages_none.png"), &[]);
    let (told, err) = screenshot(&dir.join("window_messages_no_dialog.png"), &["Ctrl+O"]);
    assert!(
        err.contains("loudscape: warning: no file dialog can open here"),
        "{err}"
    );
    let (before, after) = (warning_pixels(&quiet), warning_pixels(&told));
    assert!(
        after > before + 40,
        "no warning text under the view: {before} warning-coloured pixels without it, {after} with"
    );
}

#[test]
fn closing_the_window_from_outside_exits_cleanly() {
    let _screen = common::screen();
    assert_display();
    let home = common::output_dir().join("window_close_home");
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let mut child = common::home_in(&mut Command::new(env!("CARGO_BIN_EXE_loudscape")), &home)
        .arg(repo().join("data/demo_song.ply"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    let window = wait_for_window(&mut child);
    // Closed once it has drawn the song.
    if window.is_some() {
        common::song_drawn(&home.join("drawn.png"));
    }
    if let Some(id) = &window {
        let _ = Command::new("xdotool")
            .args(["windowclose", id])
            .status()
            .expect("xdotool");
    }
    let output = common::exit_within_30_s(child);
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(window.is_some(), "the window did not appear: {err}");
    assert_eq!(
        output.status.code(),
        Some(0),
        "closing from outside must exit 0: {}\n{err}",
        output.status
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// At an isovalue above every voxel the view itself says there is no surface (the notice under
/// the slider hid under the slider's tooltip).
#[test]
fn no_surface_is_said_in_the_view() {
    let _screen = common::screen();
    assert_display();
    let shot = common::output_dir().join("window_no_surface.png");
    let run = |iso: &str| {
        let _ = std::fs::remove_file(&shot);
        let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .arg(repo().join("data/demo_song.ply"))
            .args(["--view", "surface", "--screenshot"])
            .arg(&shot)
            .env("LOUDSCAPE_ISO_SWEEP", iso)
            .output()
            .expect("start loudscape");
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let image = image::open(&shot).unwrap().to_rgba8();
        // Warning-coloured text in the middle band of the view (right of the side panel).
        let (w, h) = image.dimensions();
        let [r, g, b, _] = loudscape_warning();
        (h / 4..h * 3 / 5)
            .flat_map(|y| (300.min(w)..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let p = image.get_pixel(x, y);
                p[0].abs_diff(r) < 14 && p[1].abs_diff(g) < 14 && p[2].abs_diff(b) < 14
            })
            .count()
    };
    let (surface, none) = (run("0.5"), run("1.0"));
    assert!(
        none > surface + 100,
        "no notice in the view at isovalue 1.0: {none} warning pixels (0.5: {surface})"
    );
}

/// The warnings a cloud carries (docs/FORMAT.md, "warnings": here a truncated file and a DC
/// offset) are in the status area over the view as soon as the cloud is shown, and each is
/// written to stderr once.
#[test]
fn a_clouds_warnings_show_under_the_view() {
    let _screen = common::screen();
    assert_display();
    let dir = common::output_dir();
    let (quiet, _) = screenshot(&dir.join("window_messages_clean_cloud.png"), &[]);
    let (told, err) = screenshot_of(
        &repo().join("tests/fixtures/format/song_v2_warnings.ply"),
        &dir.join("window_messages_cloud_warnings.png"),
        &[],
    );
    // Each said once on stderr (the loader's line; the window echoed it a second time).
    for warning in [
        "song_v2_warnings.ply: truncated or corrupt audio",
        "song_v2_warnings.ply: DC offset 0.300",
    ] {
        assert_eq!(err.matches(warning).count(), 1, "{warning}: {err}");
    }
    let (before, after) = (warning_pixels(&quiet), warning_pixels(&told));
    assert!(
        after > before + 200,
        "no warning under the view: {before} warning-coloured pixels before, {after} after"
    );
}
