//! `render A --compare B` with `--align`, `--offset` and `--match-loudness` (issue 34): B moved
//! onto A's time and loudness before the union axes. A song against itself differs by zero
//! until it is offset; a real song against its copy delayed by 0.731 s and 4 dB louder is found
//! at that offset and gain (the extractor's comparison), and its difference then shrinks to the
//! STFT's frame-phase residue. Needs the project's extractor (.venv, `make venv`) and ffmpeg.

use crate::common::{self, assert_success, compare_render, compare_video, extractor, half, repo};

use std::ffi::OsStr;
use std::path::Path;

/// Renders `a --compare b --view difference --measure level` with `extra`, the song cache in
/// `dir/cache`; returns stderr, asserting success.
fn difference(dir: &Path, a: &Path, b: &Path, name: &str, extra: &[&str]) -> String {
    let out = dir.join(format!("{name}.png"));
    let mut args: Vec<&OsStr> = vec![
        "render".as_ref(),
        a.as_os_str(),
        "--compare".as_ref(),
        b.as_os_str(),
        "--view".as_ref(),
        "difference".as_ref(),
        "--measure".as_ref(),
        "level".as_ref(),
        "--size".as_ref(),
        "480x300".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    let output = common::loudscape_extracting(&args, &dir.join("cache"), &extractor());
    assert_success(&output);
    assert!(image::open(&out).is_ok(), "{} is a picture", out.display());
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The number after `word` in `text` ("range ±0.123" -> 0.123 for "range ±").
fn number_after(text: &str, word: &str) -> f64 {
    let at = text
        .find(word)
        .unwrap_or_else(|| panic!("no '{word}' in {text}"));
    let rest = &text[at + word.len()..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("no number after '{word}' in {text}"))
}

#[test]
fn an_offset_moves_b_in_time_and_the_legend_says_so() {
    let dir = common::fresh_dir("compare_offset");
    let song = repo().join("data/demo_song.ply");
    let same = difference(&dir, &song, &song, "same", &[]);
    assert_eq!(number_after(&same, "range ±"), 0.0, "{same}");
    let moved = difference(&dir, &song, &song, "moved", &["--offset", "0.5"]);
    assert!(number_after(&moved, "range ±") > 0.01, "{moved}");
    assert!(moved.contains("B aligned +0.500 s"), "{moved}");
}

#[test]
fn the_flags_are_checked_before_any_work() {
    let dir = common::fresh_dir("compare_align_flags");
    let song = repo().join("data/demo_song.ply");
    let out = dir.join("no.png");
    for (extra, expected) in [
        (&["--compare", "x", "--match-loudness"][..], "needs --align"),
        (&["--offset", "0.5"][..], "need a second cloud"),
        (&["--compare", "x", "--offset", "inf"][..], "--offset inf"),
    ] {
        let mut args: Vec<&OsStr> = vec![
            "render".as_ref(),
            song.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ];
        args.extend(extra.iter().map(OsStr::new));
        let output = common::loudscape(&args);
        assert!(!output.status.success(), "{extra:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
        assert!(!out.exists());
    }
}

#[test]
fn a_delayed_louder_copy_is_aligned_and_matched_before_the_difference() {
    let dir = common::fresh_dir("compare_align_real");
    let a = repo().join("data/demo_song.flac");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let plain = difference(&dir, &a, &b, "plain", &[]);
    let aligned = difference(&dir, &a, &b, "aligned", &["--align", "--match-loudness"]);
    let offset = number_after(&aligned, "B aligned ");
    assert!((offset - 0.731).abs() < 0.001, "{aligned}");
    let said = &aligned[aligned.find("B aligned").unwrap_or(0)..];
    let gain = number_after(said, "s, ");
    assert!((gain + 4.0).abs() < 0.2, "{aligned}");
    assert!(aligned.contains("dB to match A"), "{aligned}");
    let (before, after) = (
        number_after(&plain, "range ±"),
        number_after(&aligned, "range ±"),
    );
    println!(
        "level difference range: {before:.4} as the files are, {after:.4} aligned and matched"
    );
    assert!(after < before * 0.5, "{before} -> {after}");
}

/// `video A --compare B --offset` draws B on A's time as `render --compare --offset
/// --playhead` does, and says the alignment.
#[test]
fn a_compare_video_follows_the_aligned_time() {
    let dir = common::fresh_dir("compare_align_video");
    let song = repo().join("data/demo_song.ply");
    let offset = ["--offset", "0.5"];
    let (frames, stderr) = compare_video(&song, &song, &offset, &dir.join("aligned.mp4"));
    assert!(stderr.contains("compare: B aligned +0.500 s"), "{stderr}");
    let render = compare_render(&song, &song, &offset, &dir.join("aligned.png"));
    let frame = frames.last().expect("a frame");
    let (share, mean) = common::difference(&half(frame), &half(&render), 32);
    println!("video frame against render --offset: {share} of pixels differ (mean {mean})");
    assert!(share < 0.002, "{share} of pixels differ (mean {mean})");
    // Not aligned, B's half is another picture.
    let plain = compare_render(&song, &song, &[], &dir.join("plain.png"));
    let (share_plain, _) = common::difference(&half(frame), &half(&plain), 32);
    println!("video frame against render without the offset: {share_plain} of pixels differ");
    assert!(
        share_plain > 10.0 * share.max(0.0005),
        "{share_plain} against {share}"
    );
}

/// Coloured (not grey) pixels of `image` in the columns `x0..x1` and rows from `y0` down.
fn coloured(image: &image::RgbaImage, x0: u32, x1: u32, y0: u32) -> usize {
    let mut count = 0;
    for y in y0..image.height() {
        for x in x0..x1.min(image.width()) {
            let p = image.get_pixel(x, y);
            let (max, min) = (p[0].max(p[1]).max(p[2]), p[0].min(p[1]).min(p[2]));
            count += usize::from(max - min > 60);
        }
    }
    count
}

/// `loudscape compare A B C -o sheet.png`: the extractor's sheet with a row of small multiples
/// under it, one tile a version (three quarters as high as it is wide, the sheet's width
/// shared), each drawn with data; the rest of the sheet is the extractor's, pixel for pixel.
#[test]
fn the_sheet_gains_a_row_of_small_multiples() {
    let dir = common::fresh_dir("compare_sheet_multiples");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let c = dir.join("earlier_louder.wav");
    common::demo_through(&c, "atrim=start=0.4,asetpts=PTS-STARTPTS,volume=2dB");
    let a = repo().join("data/demo_song.flac");
    let sheet = dir.join("sheet.png");
    let args: Vec<&OsStr> = vec![
        "compare".as_ref(),
        a.as_os_str(),
        b.as_os_str(),
        c.as_os_str(),
        "-o".as_ref(),
        sheet.as_os_str(),
    ];
    let output = common::loudscape_extracting(&args, &dir.join("cache"), &extractor());
    assert_success(&output);
    // The extractor's own sheet of the same versions.
    let alone = dir.join("alone.png");
    let made = std::process::Command::new(extractor())
        .args(["compare", "-q", "-o"])
        .arg(&alone)
        .arg("--")
        .args([&a, &b, &c])
        .output()
        .expect("run the extractor");
    assert_success(&made);
    let sheet = image::open(&sheet).unwrap().to_rgba8();
    let alone = image::open(&alone).unwrap().to_rgba8();
    let tile_width = alone.width() / 3;
    assert_eq!(sheet.width(), alone.width());
    assert_eq!(sheet.height(), alone.height() + tile_width * 3 / 4);
    for y in (0..alone.height()).step_by(7) {
        for x in (0..alone.width()).step_by(7) {
            assert_eq!(sheet.get_pixel(x, y), alone.get_pixel(x, y), "({x}, {y})");
        }
    }
    for tile in 0..3 {
        let drawn = coloured(
            &sheet,
            tile * tile_width,
            (tile + 1) * tile_width,
            alone.height(),
        );
        assert!(drawn > 2_000, "tile {tile} holds {drawn} coloured pixels");
    }
}

/// `--align` needs the extractor (it finds B's offset from both songs' audio); where it is
/// missing, `render`, `video` and `page` each say so in one line with how to install it, and
/// write nothing (the page said only where it had looked: "beside the loudscape binary, …").
#[test]
fn align_without_the_extractor_says_how_to_install_it() {
    let dir = common::fresh_dir("align_no_extractor");
    let song = repo().join("data/demo_song.ply");
    // A stand-in web viewer, so the page gets as far as the alignment without `make web`.
    let web = dir.join("web");
    std::fs::create_dir_all(&web).unwrap();
    std::fs::write(web.join("loudscape_bg.wasm"), b"\0asm stand-in").unwrap();
    std::fs::write(web.join("loudscape.js"), "let wasm_bindgen = 'glue';").unwrap();
    for (command, out) in [
        ("render", "ab.png"),
        ("video", "ab.mp4"),
        ("page", "ab.html"),
    ] {
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .arg(command)
            .arg(&song)
            .arg("--compare")
            .arg(&song)
            .args(if command == "page" {
                &["--align"][..]
            } else {
                &["--align", "--view", "compare"][..]
            })
            .arg("-o")
            .arg(dir.join(out))
            .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
            .env("LOUDSCAPE_EXTRACT", dir.join("no-extractor"))
            .env("LOUDSCAPE_WEB_DIR", &web)
            .output()
            .expect("start loudscape");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{command}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{command}: {stderr}");
        assert!(
            stderr.contains("the extractor loudscape-extract was not found")
                && stderr.contains("install it with `make venv`"),
            "{command}: {stderr}"
        );
        assert!(!dir.join(out).exists(), "{command}");
    }
}
