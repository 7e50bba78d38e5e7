//! The window's ways in and out, through the same code the keys and dialogs use: `?` shows the
//! shortcuts overlay (a scripted key press, as a real one), Ctrl+S where no file dialog can open
//! saves in the current folder and says why, and the recent-files list survives a restart with a
//! deleted file shown as missing. Needs a display (`make test` runs under xvfb-run).

use crate::common::{self, fresh_dir, repo};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the window on `files` until its screenshot is saved, with no file dialog possible
/// (no D-Bus session bus, no zenity on PATH), the state folder `state`, in the folder `cwd`.
fn window(files: &[&Path], shot: &Path, press: &[&str], state: &Path, cwd: &Path) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .args(files)
        .arg("--screenshot")
        .arg(shot)
        .env("LOUDSCAPE_STATE_DIR", state)
        .env_remove("DBUS_SESSION_BUS_ADDRESS")
        .env("PATH", "/usr/bin:/bin")
        .current_dir(cwd);
    for key in press {
        command.arg("--press").arg(key);
    }
    let output = command.output().expect("start loudscape");
    assert!(
        output.status.success(),
        "loudscape failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// Share of pixels in the middle third of the window that differ between two screenshots.
fn middle_difference(a: &Path, b: &Path) -> f64 {
    let a = image::open(a).unwrap().to_rgba8();
    let b = image::open(b).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), b.dimensions());
    let (w, h) = a.dimensions();
    let mut differ = 0usize;
    let mut total = 0usize;
    for y in h / 3..2 * h / 3 {
        for x in w / 3..2 * w / 3 {
            let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
            if (0..3).any(|c| p[c].abs_diff(q[c]) > 40) {
                differ += 1;
            }
            total += 1;
        }
    }
    differ as f64 / total as f64
}

#[test]
fn question_mark_shows_the_shortcuts_overlay() {
    let _screen = common::screen();
    common::assert_display();
    let dir = fresh_dir("window_shortcuts");
    let song = repo().join("data/demo_song.ply");
    let (plain, overlay) = (dir.join("plain.png"), dir.join("overlay.png"));
    window(&[&song], &plain, &[], &dir.join("state"), &dir);
    window(&[&song], &overlay, &["?"], &dir.join("state"), &dir);
    let share = middle_difference(&plain, &overlay);
    assert!(
        share > 0.2,
        "no overlay in the middle of the window: {:.1}% of it changed",
        share * 100.0
    );
}

#[test]
fn ctrl_s_without_a_dialog_saves_in_the_current_folder() {
    let _screen = common::screen();
    common::assert_display();
    let dir = fresh_dir("window_save_fallback");
    let song = repo().join("data/demo_song.ply");
    window(
        &[&song],
        &dir.join("window.png"),
        &["Ctrl+S"],
        &dir.join("state"),
        &dir,
    );
    let saved: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("loudscape-") && n.ends_with(".png"))
        .collect();
    assert_eq!(saved.len(), 1, "{saved:?}");
    let image = image::open(dir.join(&saved[0])).unwrap();
    assert!(image.width() > 100 && image.height() > 100);
}

#[test]
fn the_recent_list_survives_a_restart_and_shows_missing_files() {
    let _screen = common::screen();
    common::assert_display();
    let dir = fresh_dir("window_recent");
    let state = dir.join("state");
    let (a, b) = (dir.join("a.ply"), dir.join("b.ply"));
    std::fs::copy(repo().join("data/demo_song.ply"), &a).unwrap();
    std::fs::copy(repo().join("data/demo_timeline.ply"), &b).unwrap();
    window(&[&a], &dir.join("first.png"), &[], &state, &dir);
    window(&[&b], &dir.join("second.png"), &[], &state, &dir);
    std::fs::remove_file(&a).unwrap();
    let third = dir.join("third.png");
    window(&[], &third, &[], &state, &dir);
    let kept: Vec<PathBuf> =
        serde_json::from_slice(&std::fs::read(state.join("recent.json")).unwrap()).unwrap();
    assert_eq!(kept, vec![b.clone(), a.clone()], "newest first, both kept");
    assert!(image::open(&third).is_ok());
}
