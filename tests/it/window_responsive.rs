//! The window stays responsive (Xvfb in CI: `make test` runs the tests under xvfb-run):
//! an isovalue swept one value a frame in the Surface view is extracted in the background while
//! the window keeps drawing, the requests are coalesced, and the surface left on screen is the
//! one of the last value; and opening the window prints nothing on stderr (ALSA's probe of the
//! audio device printed eight lines on every launch).

use crate::common::{self, assert_display};

use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The value of `key=value` in `line`.
fn value(line: &str, key: &str) -> f64 {
    line.split(' ')
        .find_map(|w| w.strip_prefix(&format!("{key}=")))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key}= in {line}"))
}

#[test]
fn isovalue_sweep_keeps_the_window_drawing_and_ends_on_the_last_value() {
    let _screen = common::screen();
    assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shot = common::output_dir().join("window_iso_sweep.png");
    let _ = std::fs::remove_file(&shot);
    let values: Vec<String> = (0..=20)
        .map(|i| format!("{:.2}", 0.2 + 0.02 * f64::from(i)))
        .collect();
    let last: f32 = values.last().unwrap().parse().unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(repo.join("data/demo_song.ply"))
        .args(["--view", "surface", "--screenshot"])
        .arg(&shot)
        .env("LOUDSCAPE_ISO_SWEEP", values.join(","))
        .output()
        .expect("start loudscape");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "loudscape failed: {stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("iso sweep: "))
        .unwrap_or_else(|| panic!("no sweep line: {stderr}"));
    eprintln!("{line}");
    let frames = value(line, "frames");
    let busy = value(line, "busy_frames");
    let installed = value(line, "installed");
    let shown = value(line, "shown_iso") as f32;
    assert_eq!(value(line, "values"), values.len() as f64);
    // The surface on screen is the last value's, not an earlier one that finished later.
    assert_eq!(shown, last, "{line}");
    // Never more extractions than values (requests are coalesced, never queued up; on a
    // single-queue software device each frame may wait for the extraction ahead of it on the
    // GPU queue, so fewer is not guaranteed there: the unit tests of the coalescer hold that).
    assert!(
        installed >= 1.0 && installed <= values.len() as f64,
        "{line}"
    );
    // The window drew frames while extractions ran (it did not wait for them).
    assert!(busy >= 2.0, "{line}");
    // Each request extracts the coarse surface of the level of detail first.
    assert!(value(line, "coarse_installed") >= 1.0, "{line}");
    assert!(frames > installed, "{line}");
    // The last surface is on screen.
    let image = image::open(&shot).expect("screenshot").to_rgba8();
    let (w, h) = image.dimensions();
    let background = *image.get_pixel(w - 3, 3);
    let drawn = (0..h)
        .flat_map(|y| (w / 4..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = image.get_pixel(x, y);
            (0..3).any(|c| p[c].abs_diff(background[c]) > 40)
        })
        .count();
    assert!(
        drawn as f64 / f64::from((w - w / 4) * h) > 0.02,
        "no surface in the screenshot"
    );
}

#[test]
fn opening_the_window_prints_nothing_on_stderr() {
    let _screen = common::screen();
    assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // A normal launch (not a scripted screenshot run, which opens no audio device), with its
    // remembered state kept in a folder of its own.
    let home = common::output_dir().join("window_quiet_home");
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(repo.join("data/demo_song.ply"))
        .env("HOME", &home)
        .env("XDG_DATA_HOME", &home)
        .env("XDG_CONFIG_HOME", &home)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    // Wait for the window, then for the song drawn in it (the audio device is opened before
    // the first frame, `AudioPanel::new`). Its own window: the other window tests' run in the
    // same process, on the same display.
    let found = common::wait_for_window(&mut child).is_some();
    if found {
        common::song_drawn(&home.join("drawn.png"));
    }
    // SIGTERM: the app's handler removes temporaries and exits.
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let output = child.wait_with_output().expect("wait for loudscape");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(found, "the window did not appear: {stderr}");
    assert!(stderr.trim().is_empty(), "stderr is not empty:\n{stderr}");
}
