//! Several songs opened together become a timeline in the window, through `start_opening`, the
//! same path the Open dialog's answer, a drop and the command line take: the tags are read, a
//! song without a year is asked for in a dialog (a year typed there is remembered), a remembered
//! year is used without asking, each song's progress is reported as it finishes, and the
//! timeline is shown; opening the same songs again comes from the cache. Needs a display and
//! the extractor (`make venv`).

use crate::common::{self, repo};

use std::path::{Path, PathBuf};
use std::process::Command;

/// `seconds` of a chord at `root` Hz with a click every half second, 22,050 Hz mono WAV (no
/// tags: no year).
fn write_song(path: &Path, seconds: f32, root: f32) {
    let rate = 22_050u32;
    let n = (seconds * rate as f32) as usize;
    let mut data = Vec::with_capacity(n * 2);
    for i in 0..n {
        let t = i as f32 / rate as f32;
        let chord: f32 = [1.0f32, 1.26, 1.5, 4.0]
            .iter()
            .map(|m| (std::f32::consts::TAU * root * m * t).sin())
            .sum::<f32>()
            * 0.15
            * (0.6 + 0.4 * (t * 0.7).sin());
        let click = if i % (rate as usize / 2) < 40 {
            0.6
        } else {
            0.0
        };
        let sample = ((chord + click).clamp(-1.0, 1.0) * 32_000.0) as i16;
        data.extend_from_slice(&sample.to_le_bytes());
    }
    let mut bytes = Vec::with_capacity(44 + data.len());
    bytes.extend_from_slice(b"RIFF");
    bytes.extend_from_slice(&(36 + data.len() as u32).to_le_bytes());
    bytes.extend_from_slice(b"WAVEfmt ");
    bytes.extend_from_slice(&16u32.to_le_bytes());
    bytes.extend_from_slice(&1u16.to_le_bytes());
    bytes.extend_from_slice(&1u16.to_le_bytes());
    bytes.extend_from_slice(&rate.to_le_bytes());
    bytes.extend_from_slice(&(rate * 2).to_le_bytes());
    bytes.extend_from_slice(&2u16.to_le_bytes());
    bytes.extend_from_slice(&16u16.to_le_bytes());
    bytes.extend_from_slice(b"data");
    bytes.extend_from_slice(&(data.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&data);
    std::fs::write(path, bytes).unwrap();
}

/// Runs the window on `songs` until its screenshot is saved; returns stderr.
fn window(dir: &Path, songs: &[&Path], shot: &Path, press: &[&str]) -> String {
    let extractor = repo().join(".venv/bin/loudscape-extract");
    assert!(
        extractor.is_file(),
        "install the extractor with `make venv`"
    );
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .args(songs)
        .arg("--screenshot")
        .arg(shot)
        .env("LOUDSCAPE_STATE_DIR", dir.join("state"))
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env("XDG_CACHE_HOME", dir.join("xdg-cache"))
        .env("LOUDSCAPE_EXTRACT", &extractor);
    for key in press {
        command.arg("--press").arg(key);
    }
    let output = command.output().expect("start loudscape");
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "loudscape failed: {err}");
    assert!(image::open(shot).is_ok(), "no screenshot: {err}");
    err
}

#[test]
fn several_songs_become_a_timeline_asking_for_the_years_their_tags_lack() {
    let _screen = common::screen();
    common::assert_display();
    let dir = common::output_dir().join("window_timeline_build");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("state")).unwrap();
    let (a, b) = (dir.join("a.wav"), dir.join("b.wav"));
    write_song(&a, 4.0, 220.0);
    write_song(&b, 4.0, 330.0);

    // Neither has a year: the dialog lists both, nothing is built.
    let err = window(&dir, &[&a, &b], &dir.join("ask.png"), &[]);
    assert!(
        err.contains("2 song(s) without a year: a.wav, b.wav"),
        "{err}"
    );
    assert!(!err.contains("timeline built"), "{err}");

    // b's year is remembered from an earlier answer; a's is typed in the dialog (Enter builds).
    std::fs::write(
        dir.join("state/years.json"),
        serde_json::to_vec(&serde_json::json!({ b.to_string_lossy(): 2005 })).unwrap(),
    )
    .unwrap();
    let err = window(
        &dir,
        &[&a, &b],
        &dir.join("built.png"),
        &["text:1999", "Enter"],
    );
    assert!(err.contains("1 song(s) without a year: a.wav"), "{err}");
    assert!(
        err.contains("song 1 of 2") && err.contains("song 2 of 2"),
        "{err}"
    );
    assert!(err.contains("timeline built"), "{err}");
    let years: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("state/years.json")).unwrap()).unwrap();
    assert_eq!(years[a.to_string_lossy().as_ref()], 1999, "{years}");
    let built: Vec<PathBuf> = std::fs::read_dir(dir.join("cache"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    assert_eq!(built.len(), 1, "one timeline and nothing else: {built:?}");
    let timeline = loudscape::data::cloud::load(&built[0]).unwrap();
    let years: Vec<_> = timeline.meta.songs.iter().map(|s| s.year).collect();
    assert_eq!(years, [Some(1999), Some(2005)], "placed by the years given");
    let recent: Vec<PathBuf> =
        serde_json::from_slice(&std::fs::read(dir.join("state/recent.json")).unwrap()).unwrap();
    assert_eq!(
        recent,
        [built[0].clone()],
        "the timeline's cloud is the recent file"
    );

    // Both years remembered now: no dialog, and the timeline comes from the cache.
    let err = window(&dir, &[&a, &b], &dir.join("again.png"), &[]);
    assert!(!err.contains("without a year"), "{err}");
    assert!(err.contains("timeline from the cache"), "{err}");
}

/// Typing fast in the years dialog: a year, Tab, the next year and Enter arrive in one frame
/// (the scripted presses all do), and each year lands in its own field; Enter with a song still
/// without a year builds nothing (leaving songs out is a button's choice, never Enter's).
#[test]
fn the_years_dialog_keeps_fast_typing_in_its_fields_and_enter_leaves_no_song_out() {
    let _screen = common::screen();
    common::assert_display();
    let dir = common::output_dir().join("window_years_typing");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("state")).unwrap();
    let (a, b) = (dir.join("a.wav"), dir.join("b.wav"));
    write_song(&a, 3.0, 220.0);
    write_song(&b, 3.0, 330.0);

    // One year typed of two, then Enter: nothing is built, and the window says why.
    let err = window(
        &dir,
        &[&a, &b],
        &dir.join("half.png"),
        &["text:1996", "Enter"],
    );
    assert!(err.contains("2 song(s) without a year"), "{err}");
    assert!(err.contains("Enter: songs still without a year"), "{err}");
    assert!(!err.contains("timeline built"), "{err}");

    // Both typed with a Tab between, in one frame: each year in its own field.
    let err = window(
        &dir,
        &[&a, &b],
        &dir.join("both.png"),
        &["text:1996", "Tab", "text:2001", "Enter"],
    );
    assert!(err.contains("timeline built"), "{err}");
    let years: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("state/years.json")).unwrap()).unwrap();
    assert_eq!(years[a.to_string_lossy().as_ref()], 1996, "{years}");
    assert_eq!(years[b.to_string_lossy().as_ref()], 2001, "{years}");
}
