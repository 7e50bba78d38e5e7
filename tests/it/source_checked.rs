//! Every command that takes a cloud's audio takes its checked source
//! (`playback::checked_source`): `compare` and `render --compare --align` refuse a cloud whose
//! recorded source was replaced by other audio, in one line naming the cloud and the source,
//! before any analysis, as `video` does. Needs ffmpeg (to make the other audio).

use crate::common::{self, repo};

use std::path::Path;
use std::process::{Command, Output};

/// Runs `loudscape args` in `dir` (where the cloud's relative source path is looked up first).
fn loudscape_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(args)
        .current_dir(dir)
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env(
            "LOUDSCAPE_EXTRACT",
            repo().join(".venv/bin/loudscape-extract"),
        )
        .output()
        .expect("start loudscape")
}

#[test]
fn a_clouds_source_replaced_by_other_audio_is_refused_by_compare_and_align() {
    let dir = common::fresh_dir("source_checked");
    // The demo cloud records `data/demo_song.flac` (30 s): in `dir`, that is 2 s of it.
    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::copy(repo().join("data/demo_song.ply"), dir.join("song.ply")).unwrap();
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(repo().join("data/demo_song.flac"))
        .args(["-t", "2"])
        .arg(dir.join("data/demo_song.flac"))
        .output()
        .expect("this test needs ffmpeg");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let expected = [
        "song.ply",
        "demo_song.flac",
        "is not the audio the cloud was made from",
        "2.000 s long, the cloud's 30.000 s",
    ];
    for (args, out) in [
        (
            &[
                "compare",
                "song.ply",
                "data/demo_song.flac",
                "-o",
                "sheet.png",
            ][..],
            "sheet.png",
        ),
        (
            &[
                "render",
                "song.ply",
                "--compare",
                "song.ply",
                "--view",
                "difference",
                "--align",
                "-o",
                "pic.png",
            ][..],
            "pic.png",
        ),
    ] {
        let output = loudscape_in(&dir, args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        for word in expected {
            assert!(stderr.contains(word), "{args:?}: no '{word}' in {stderr}");
        }
        assert!(!dir.join(out).exists(), "{args:?}");
    }
}
