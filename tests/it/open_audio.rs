//! Audio in: every command that takes a cloud takes a song too. The extractor runs as a child
//! process (the project's .venv: `make venv`), its cloud lands in the cache, and the second open
//! of the same song reads the cache without running Python. Cancelling kills the extractor and
//! leaves nothing behind.

use crate::common::{self, chord_with_clicks, extractor, fresh_dir, names_in, write_wav};

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use loudscape::extract::{self, ExtractError, Extractor, Progress, Settings};

/// The project's extractor with its installed version.
fn found() -> Extractor {
    let path = extractor();
    let version = extract::version::of(&path).expect("the extractor's version");
    Extractor { path, version }
}

/// stderr holds exactly one line, the "wrote PNG (...)" summary: no progress, no noise.
fn assert_only_the_summary(err: &str, png: &Path) {
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].starts_with(&format!("wrote {}", png.display())),
        "{err}"
    );
}

#[test]
fn render_takes_a_song_and_the_second_run_reads_the_cache() {
    let dir = fresh_dir("open_audio_render");
    let (song, cache) = (dir.join("song.wav"), dir.join("cache"));
    write_wav(&song, 3.0, 22_050, chord_with_clicks);
    let png = dir.join("v.png");
    let args = [
        "render".as_ref(),
        song.as_os_str(),
        "--view".as_ref(),
        "volume".as_ref(),
        "--size".as_ref(),
        "320x240".as_ref(),
        "-o".as_ref(),
        png.as_os_str(),
    ];
    let first = common::loudscape_extracting(&args, &cache, &extractor());
    let err = String::from_utf8_lossy(&first.stderr);
    assert!(first.status.success(), "render of a song failed: {err}");
    // stderr is not a terminal: no progress lines, as the extractor does (the window tells);
    // only the one "wrote" summary every command prints.
    assert_only_the_summary(&err, &png);
    let cached = names_in(&cache);
    assert_eq!(
        cached.len(),
        2,
        "one cloud and its checksum file in the cache, nothing partial: {cached:?}"
    );
    assert!(
        cached[0].ends_with(".ply") && cached[0].len() == 64 + 1 + 16 + 4,
        "{cached:?}"
    );
    assert_eq!(cached[1], format!("{}.sum", cached[0]));
    let cloud_file = cache.join(&cached[0]);
    let written = std::fs::metadata(&cloud_file).unwrap().modified().unwrap();
    let image = image::open(&png).unwrap().to_rgba8();
    assert_eq!(image.dimensions(), (320, 240));
    let background = *image.get_pixel(0, 0);
    let differing = image.pixels().filter(|p| **p != background).count();
    assert!(
        differing > 320 * 240 / 50,
        "the volume looks blank: {differing} pixels"
    );

    // Again, with an extractor that cannot run: the cache answers, the file is not rewritten.
    let start = Instant::now();
    let second =
        common::loudscape_extracting(&args, &cache, Path::new("/nonexistent/loudscape-extract"));
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success(), "cached render failed: {err}");
    assert_only_the_summary(&err, &png);
    assert_eq!(
        std::fs::metadata(&cloud_file).unwrap().modified().unwrap(),
        written
    );
    eprintln!("cached render: {:.2} s", start.elapsed().as_secs_f32());
}

#[test]
fn a_missing_extractor_names_the_file_and_the_install_command() {
    let dir = fresh_dir("open_audio_missing");
    let song = dir.join("song.wav");
    write_wav(&song, 0.5, 22_050, chord_with_clicks);
    let out = dir.join("grid.npy");
    let output = common::loudscape_extracting(
        &[
            "voxelize".as_ref(),
            song.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        &dir.join("cache"),
        Path::new("/nonexistent/loudscape-extract"),
    );
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(
        err.contains("song.wav") && err.contains("make venv"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn bad_audio_is_one_line_naming_the_file_and_leaves_no_partial_cloud() {
    let dir = fresh_dir("open_audio_bad");
    let song = dir.join("noise.ogg");
    std::fs::write(&song, b"OggS but not really an ogg file at all").unwrap();
    let cache = dir.join("cache");
    let out = dir.join("mesh.obj");
    let output = common::loudscape_extracting(
        &[
            "mesh".as_ref(),
            song.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        &cache,
        &extractor(),
    );
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    let last = err.trim();
    assert!(last.starts_with("loudscape: error: "), "{err}");
    assert!(
        last.contains("noise.ogg") && last.contains("extractor failed"),
        "{err}"
    );
    assert!(!err.contains("Traceback"), "{err}");
    assert!(names_in(&cache).is_empty(), "{:?}", names_in(&cache));
}

#[test]
fn cancel_kills_the_extractor_then_a_full_run_fills_the_cache() {
    let dir = fresh_dir("open_audio_cancel");
    let song = dir.join("song.wav");
    write_wav(&song, 20.0, 22_050, chord_with_clicks);
    let cache = dir.join("cache");
    let settings = Settings::default();
    let cancel = AtomicBool::new(false);
    let mut stages = Vec::new();
    let result = extract::cloud_for_audio_with(
        &song,
        &settings,
        &cache,
        || Ok(found()),
        &cancel,
        &mut |p: &Progress| {
            stages.push(p.stage.clone());
            if p.stage == "spectrogram" {
                cancel.store(true, Ordering::Relaxed);
            }
        },
    );
    assert!(
        matches!(result, Err(ExtractError::Cancelled { .. })),
        "not cancelled: {:?}",
        result.map(|r| r.ply)
    );
    assert!(!stages.contains(&"write".to_string()), "{stages:?}");
    assert!(names_in(&cache).is_empty(), "{:?}", names_in(&cache));

    cancel.store(false, Ordering::Relaxed);
    let mut fractions = Vec::new();
    let fresh = extract::cloud_for_audio_with(
        &song,
        &settings,
        &cache,
        || Ok(found()),
        &cancel,
        &mut |p: &Progress| fractions.push(p.fraction),
    )
    .expect("extract");
    let ply = fresh.ply.expect("kept in the cache");
    assert!(!fresh.hit && ply.is_file());
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]), "{fractions:?}");
    let cloud = loudscape::data::cloud::load(&ply).unwrap();
    assert!(cloud.points.len() > 1000);
    assert_eq!(fresh.cloud.points, cloud.points);

    let start = Instant::now();
    let again = extract::cloud_for_audio_with(
        &song,
        &settings,
        &cache,
        // The same version at a path that runs nothing: the cache answers without running it.
        || {
            Ok(Extractor {
                path: dir.join("no-extractor-here"),
                version: found().version,
            })
        },
        &cancel,
        &mut |_| {},
    )
    .expect("cached");
    assert!(again.hit && again.ply.as_ref() == Some(&ply));
    assert!(start.elapsed().as_secs_f32() < 1.0, "{:?}", start.elapsed());

    // A new extractor does not reuse the old one's cloud: it misses (and, not being there,
    // fails to run), leaving the old cloud alone.
    let newer = extract::cloud_for_audio_with(
        &song,
        &settings,
        &cache,
        || {
            Ok(Extractor {
                path: dir.join("no-extractor-here"),
                version: format!("{}-newer", found().version),
            })
        },
        &cancel,
        &mut |_| {},
    );
    assert!(
        matches!(newer, Err(ExtractError::Failed { .. })),
        "a new extractor's version hit the old cloud: {:?}",
        newer.map(|r| r.ply)
    );
    assert!(ply.is_file());
}

/// A song cut at half its length: the real extractor warns, and `render` says so, on the first
/// run and from the cache (before, it printed only `wrote x.png`).
#[test]
fn render_of_a_truncated_song_says_so_fresh_and_cached() {
    let dir = fresh_dir("open_audio_truncated");
    let (whole, song, cache) = (
        dir.join("whole.wav"),
        dir.join("cut.wav"),
        dir.join("cache"),
    );
    write_wav(&whole, 4.0, 22_050, chord_with_clicks);
    let bytes = std::fs::read(&whole).unwrap();
    std::fs::write(&song, &bytes[..bytes.len() / 2]).unwrap();
    let png = dir.join("cut.png");
    let args = [
        "render".as_ref(),
        song.as_os_str(),
        "--size".as_ref(),
        "160x120".as_ref(),
        "-o".as_ref(),
        png.as_os_str(),
    ];
    for run in ["fresh", "cached"] {
        let output = common::loudscape_extracting(&args, &cache, &extractor());
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{run}: {err}");
        let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning: ")).collect();
        assert_eq!(warnings.len(), 1, "{run}: {err}");
        assert!(
            warnings[0].starts_with(&format!("warning: {}: ", song.display()))
                && warnings[0].contains("of the 4.00 s"),
            "{run}: {err}"
        );
    }
}
