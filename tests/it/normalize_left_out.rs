//! `--normalize` never leaves a song out without a word: a song of the timeline without an
//! integrated loudness (a -75 dB sine gives none: BS.1770's gate keeps nothing) stays where it
//! is, and `render` says so on stderr, one line naming the song and the reason, and in the
//! picture's legend.

use crate::common::{self, fresh_dir};

use loudscape::annotate::legend::picture_legend;
use loudscape::data::cloud::{self as cloud_file, write};
use loudscape::render::scene::RenderSettings;

/// The demo timeline with the metrics of its second song taken away (as the extractor writes
/// them for a song too quiet to measure: null).
fn timeline_with_an_unmeasured_song(path: &std::path::Path) -> String {
    let demo = cloud_file::load(&common::repo().join("data/demo_timeline.ply")).unwrap();
    let mut meta = demo.meta.raw.clone();
    let song = &mut meta["songs"][1];
    song["metrics"] = serde_json::Value::Null;
    let title = song["title"].as_str().unwrap().to_string();
    let mut bytes = Vec::new();
    write(&mut bytes, &demo.points, Some(&meta)).unwrap();
    std::fs::write(path, bytes).unwrap();
    title
}

#[test]
fn a_song_left_unnormalized_is_named_on_stderr_and_in_the_legend() {
    let dir = fresh_dir("normalize_left_out");
    let timeline = dir.join("quiet_one.ply");
    let title = timeline_with_an_unmeasured_song(&timeline);
    let png = dir.join("heard.png");
    let output = common::loudscape(&[
        "render".as_ref(),
        timeline.as_os_str(),
        "--size".as_ref(),
        "320x200".as_ref(),
        "--normalize".as_ref(),
        "spotify".as_ref(),
        "-o".as_ref(),
        png.as_os_str(),
    ]);
    common::assert_success(&output);
    let err = String::from_utf8_lossy(&output.stderr);
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("not normalized"))
        .collect();
    assert_eq!(said.len(), 1, "one line for the one song: {err}");
    assert!(
        said[0].contains(&title)
            && said[0].contains("no integrated loudness")
            && said[0].contains("quiet_one.ply"),
        "{}",
        said[0]
    );
    assert!(png.is_file());

    // The legend the picture is drawn with says it too; without --normalize nothing is said.
    let loaded = cloud_file::load(&timeline).unwrap();
    let preset = loudscape::data::normalize::Normalization::parse("spotify")
        .and_then(|n| n.preset())
        .unwrap();
    let heard = loudscape::data::normalize::normalized(&loaded, &preset).unwrap();
    let legend = picture_legend(&heard, &RenderSettings::default());
    assert!(
        legend.detail.contains(&format!(
            "1 song not normalized (no integrated loudness): {title}"
        )),
        "{}",
        legend.detail
    );
    assert!(
        !picture_legend(&loaded, &RenderSettings::default())
            .detail
            .contains("normalized")
    );
    let plain = common::loudscape(&[
        "render".as_ref(),
        timeline.as_os_str(),
        "--size".as_ref(),
        "320x200".as_ref(),
        "-o".as_ref(),
        dir.join("plain.png").as_os_str(),
    ]);
    common::assert_success(&plain);
    assert!(!String::from_utf8_lossy(&plain.stderr).contains("normalized"));
}

/// An audio file is a song, and `--normalize` applies to a timeline: `render` and `video`
/// refuse it at once, in one line, before the song is extracted (a 20-minute song took 50 s of
/// extraction before the refusal). The extractor named here does not exist: any work would fail
/// otherwise.
#[test]
fn normalizing_an_audio_file_is_refused_before_it_is_extracted() {
    let dir = fresh_dir("normalize_audio_refused");
    let song = common::repo().join("data/demo_song.flac");
    for (command, out) in [("render", "song.png"), ("video", "song.mp4")] {
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .arg(command)
            .arg(&song)
            .args(["--normalize", "spotify", "-o"])
            .arg(dir.join(out))
            .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
            .env("LOUDSCAPE_EXTRACT", dir.join("no-extractor"))
            .output()
            .expect("start loudscape");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{command}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{command}: {stderr}");
        assert!(
            stderr.contains("demo_song.flac: normalization applies to a timeline, not a song"),
            "{command}: {stderr}"
        );
        assert!(!dir.join(out).exists(), "{command}");
    }
}
