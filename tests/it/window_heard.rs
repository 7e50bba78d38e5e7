//! The window's "level as heard" (Timeline mode): `--normalize` (the side panel's choice at
//! start) shows the demo timeline as Spotify plays it, and the picture changes.

use crate::common;

use std::path::PathBuf;
use std::process::Command;

fn shot(preset: &str) -> (image::RgbaImage, String) {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shot = common::output_dir().join(format!("window_heard_{preset}.png"));
    let _ = std::fs::remove_file(&shot);
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(repo.join("data/demo_timeline.ply"))
        .args(["--normalize", preset, "--screenshot"])
        .arg(&shot)
        .output()
        .expect("start loudscape");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{preset}: {stderr}");
    let image = image::open(&shot)
        .unwrap_or_else(|e| panic!("no screenshot at {}: {e}", shot.display()))
        .to_rgba8();
    (image, stderr)
}

#[test]
fn the_timeline_as_heard_moves_the_songs() {
    let _screen = common::screen();
    common::assert_display();
    let (plain, _) = shot("none");
    let (heard, stderr) = shot("spotify");
    assert!(
        !stderr.contains("replaces"),
        "not a re-extraction: {stderr}"
    );
    assert_eq!(plain.dimensions(), heard.dimensions());
    // The 3D view (right of the side panel) differs: the loud songs came down to -14 LUFS.
    let (w, h) = plain.dimensions();
    let changed = (0..h)
        .flat_map(|y| (w / 4..w).map(move |x| (x, y)))
        .filter(|&(x, y)| plain.get_pixel(x, y) != heard.get_pixel(x, y))
        .count();
    assert!(changed > 500, "only {changed} pixels changed");
}

#[test]
fn an_unknown_preset_is_one_clear_line() {
    let _screen = common::screen();
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(["--normalize", "tidal", "data/demo_timeline.ply"])
        .output()
        .expect("start loudscape");
    // A usage error, as clap exits on every other one.
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("loudscape"))
        .collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains("tidal") && lines[0].contains("spotify"),
        "{stderr}"
    );
}
