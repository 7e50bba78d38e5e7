//! The window opens a song (the command-line argument goes through the same `start_loading` the
//! drop and the Open row use): the extractor's stages appear on stderr while the side panel shows
//! them, the cloud is drawn, and a second open of the song comes from the cache. Needs a display
//! (`make test` runs under xvfb-run) and the extractor (`make venv`).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The share of the 3D view (right of the side panel, above the transport bar) that is not
/// background. The song's points are coloured by hp, or white while the app reads format
/// version 2 files as generic clouds; either way they cover much of the view.
fn drawn_share(shot: &Path) -> f64 {
    let image = image::open(shot)
        .unwrap_or_else(|e| panic!("no screenshot at {}: {e}", shot.display()))
        .to_rgba8();
    let (w, h) = image.dimensions();
    let background = *image.get_pixel(w - 3, 3);
    let (x0, y1) = (w / 4, h * 3 / 4);
    let mut drawn = 0usize;
    for y in 0..y1 {
        for x in x0..w {
            let p = image.get_pixel(x, y);
            if (0..3).any(|c| p[c].abs_diff(background[c]) > 40) {
                drawn += 1;
            }
        }
    }
    drawn as f64 / f64::from((w - x0) * y1)
}

#[test]
fn window_opens_a_song_and_reopens_it_from_the_cache() {
    let _screen = common::screen();
    common::assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let extractor = repo.join(".venv/bin/loudscape-extract");
    assert!(
        extractor.is_file(),
        "install the extractor with `make venv`"
    );
    let dir = common::output_dir().join("window_open_audio");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The demo song's audio, copied so that its name is new to the cache.
    let song = dir.join("demo.flac");
    std::fs::copy(repo.join("data/demo_song.flac"), &song).unwrap();
    let cache = dir.join("cache");
    let open = |shot: &Path| {
        let start = Instant::now();
        let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .arg(&song)
            .arg("--screenshot")
            .arg(shot)
            .env("LOUDSCAPE_CACHE_DIR", &cache)
            .env("LOUDSCAPE_EXTRACT", &extractor)
            .output()
            .expect("start loudscape");
        let err = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "loudscape failed: {err}");
        (err, start.elapsed().as_secs_f32())
    };
    let first_shot = dir.join("first.png");
    let (err, first_s) = open(&first_shot);
    for stage in ["decode", "spectrogram", "hpss", "points"] {
        assert!(
            err.contains(&format!("demo.flac: {stage} (")),
            "no {stage}: {err}"
        );
    }
    assert!(err.contains("cloud extracted"), "{err}");
    let share = drawn_share(&first_shot);
    assert!(
        share > 0.05,
        "the song is not drawn: {:.2}% drawn",
        share * 100.0
    );

    let second_shot = dir.join("second.png");
    let (err, second_s) = open(&second_shot);
    assert!(err.contains("cloud from the cache"), "{err}");
    assert!(!err.contains("hpss"), "extracted again: {err}");
    assert!(drawn_share(&second_shot) > 0.05);
    eprintln!("window with extraction {first_s:.1} s, from the cache {second_s:.1} s");
}

#[test]
fn a_new_floor_re_extracts_keeping_the_old_cloud_until_the_new_one_is_ready() {
    let _screen = common::screen();
    common::assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let extractor = repo.join(".venv/bin/loudscape-extract");
    assert!(
        extractor.is_file(),
        "install the extractor with `make venv`"
    );
    let dir = common::output_dir().join("window_reextract");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let song = dir.join("demo.flac");
    std::fs::copy(repo.join("data/demo_song.flac"), &song).unwrap();
    let shot = dir.join("reextracted.png");
    // The Extraction panel's floor set to 30 dB (as its slider would), then Ctrl+E.
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(&song)
        .arg("--screenshot")
        .arg(&shot)
        .args(["--press", "floor=30", "--press", "Ctrl+E"])
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env("LOUDSCAPE_EXTRACT", &extractor)
        .output()
        .expect("start loudscape");
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "loudscape failed: {err}");
    assert!(
        err.contains("extracting again (") && err.contains("--floor-db 30"),
        "{err}"
    );
    let replaced = err
        .lines()
        .find(|l| l.contains("replaces the one shown"))
        .unwrap_or_else(|| panic!("the old cloud was not on screen when the new came: {err}"));
    let counts: Vec<usize> = replaced
        .split(['(', ' '])
        .filter_map(|w| w.parse().ok())
        .collect();
    assert_eq!(counts.len(), 2, "{replaced}");
    assert!(
        counts[0] < counts[1],
        "a 30 dB floor keeps fewer points than the default 80: {replaced}"
    );
    let clouds = std::fs::read_dir(dir.join("cache"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".ply"))
        .count();
    assert_eq!(clouds, 2, "one cloud per floor in the cache");
    assert!(drawn_share(&shot) > 0.02, "the new cloud is not drawn");
}
