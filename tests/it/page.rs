//! `loudscape page`: the page holds the viewer and the cloud, packed as the page's script
//! unpacks them (gzip in base64); a missing viewer and a wrong output type are one line each.
//! A stand-in viewer (`$LOUDSCAPE_WEB_DIR`) keeps these tests free of the wasm build; the page in
//! a browser is tests/web/test_page.py.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common;

fn song() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply")
}

fn page(web_dir: &Path, args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg("page")
        .args(args)
        .env("LOUDSCAPE_WEB_DIR", web_dir)
        .output()
        .expect("start loudscape")
}

/// The text of the `<script>` element with `id`.
fn script<'a>(html: &'a str, id: &str) -> &'a str {
    let open = format!("id=\"{id}\">");
    let start = html.find(&open).expect(id) + open.len();
    let end = start + html[start..].find("</script>").expect("script end");
    &html[start..end]
}

fn unbase64(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let digits: Vec<u8> = text
        .trim()
        .bytes()
        .filter(|&c| c != b'=')
        .map(value)
        .collect();
    let mut out = Vec::new();
    for group in digits.chunks(4) {
        let n = group
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &d)| n | (u32::from(d) << (18 - 6 * i)));
        for i in 0..group.len() - 1 {
            out.push((n >> (16 - 8 * i)) as u8);
        }
    }
    out
}

fn gunzip(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .read_to_end(&mut out)
        .expect("gzip");
    out
}

#[test]
fn the_page_carries_the_viewer_and_every_point_of_the_demo() {
    let dir = common::fresh_dir("page_carries");
    let web = dir.join("web");
    std::fs::create_dir_all(&web).unwrap();
    let wasm: Vec<u8> = (0..5000u32).map(|i| (i * 7 % 251) as u8).collect();
    std::fs::write(web.join("loudscape_bg.wasm"), &wasm).unwrap();
    std::fs::write(web.join("loudscape.js"), "let wasm_bindgen = 'glue';").unwrap();
    let out = dir.join("demo.html");
    let output = page(&web, &[&song(), Path::new("-o"), &out]);
    common::assert_success(&output);
    let html = std::fs::read_to_string(&out).unwrap();
    assert!(html.contains("let wasm_bindgen = 'glue';"));
    assert_eq!(gunzip(&unbase64(script(&html, "loudscape-wasm"))), wasm);
    let data = gunzip(&unbase64(script(&html, "loudscape-cloud")));
    let cloud = loudscape::data::page_cloud::decode(&data, "demo").expect("page data");
    let original = loudscape::data::cloud::load(&song()).unwrap();
    assert_eq!(cloud.len(), original.len(), "the demo fits whole");
    assert_eq!(cloud.meta.axes, original.meta.axes);
    assert!(html.contains("Every point of the song"));
    // Nothing left beside the page.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");

    // --max-points thins, and the page says so.
    let thin = dir.join("thin.html");
    let output = page(
        &web,
        &[
            &song(),
            Path::new("-o"),
            &thin,
            Path::new("--max-points"),
            Path::new("1000"),
        ],
    );
    common::assert_success(&output);
    let html = std::fs::read_to_string(&thin).unwrap();
    let data = gunzip(&unbase64(script(&html, "loudscape-cloud")));
    let cloud = loudscape::data::page_cloud::decode(&data, "demo").expect("page data");
    assert!(cloud.len() <= 1000 && cloud.len() > 900, "{}", cloud.len());
    assert!(html.contains(&format!("of the song's {} points", original.len())));
}

#[test]
fn without_the_viewer_or_with_a_wrong_name_the_page_is_one_line() {
    let dir = common::fresh_dir("page_refused");
    let out = dir.join("song.html");
    let output = page(&dir, &[&song(), Path::new("-o"), &out]);
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(text.contains("make web"), "{text}");
    assert!(!out.exists());

    let output = page(&dir, &[&song(), Path::new("-o"), &dir.join("song.png")]);
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(text.contains("supported: .html, .htm"), "{text}");
}

/// A stand-in viewer in `dir`/web.
fn stand_in_viewer(dir: &Path) -> PathBuf {
    let web = dir.join("web");
    std::fs::create_dir_all(&web).unwrap();
    std::fs::write(web.join("loudscape_bg.wasm"), b"\0asm stand-in").unwrap();
    std::fs::write(web.join("loudscape.js"), "let wasm_bindgen = 'glue';").unwrap();
    web
}

#[test]
fn with_audio_the_page_carries_the_songs_sound_as_opus() {
    let dir = common::fresh_dir("page_audio");
    let web = stand_in_viewer(&dir);
    let scratch = dir.join("tmp");
    std::fs::create_dir_all(&scratch).unwrap();
    let out = dir.join("demo.html");
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg("page")
        .arg(song())
        .arg("-o")
        .arg(&out)
        .arg("--audio")
        .env("LOUDSCAPE_WEB_DIR", &web)
        .env("TMPDIR", &scratch)
        .output()
        .expect("start loudscape");
    common::assert_success(&output);
    let html = std::fs::read_to_string(&out).unwrap();
    let sound = dir.join("sound.webm");
    std::fs::write(&sound, unbase64(script(&html, "loudscape-audio"))).unwrap();
    let probe = common::ffprobe(&sound);
    assert_eq!(probe["streams"][0]["codec_name"], "opus", "{probe}");
    assert!(
        probe["format"]["format_name"]
            .as_str()
            .is_some_and(|f| f.contains("webm")),
        "{probe}"
    );
    let source = common::repo().join("data/demo_song.flac");
    let seconds = |p: &serde_json::Value| {
        p["format"]["duration"]
            .as_str()
            .and_then(|d| d.parse::<f64>().ok())
            .expect("duration")
    };
    let length = seconds(&common::ffprobe(&source));
    assert!((seconds(&probe) - length).abs() < 0.05, "{probe}");
    // The song's own sound: the decoded Opus follows the source sample by sample.
    let heard = common::decode_audio(&sound, 8000);
    let said = common::decode_audio(&source, 8000);
    let n = heard.len().min(said.len());
    let dot: f64 = (0..n)
        .map(|i| f64::from(heard[i]) * f64::from(said[i]))
        .sum();
    let energy = |x: &[f32]| x[..n].iter().map(|&v| f64::from(v).powi(2)).sum::<f64>();
    let correlation = dot / (energy(&heard) * energy(&said)).sqrt();
    assert!(correlation > 0.95, "correlation {correlation:.3}");
    // (The runtime folder every command makes there is not the page's.)
    let left = common::names_in(&scratch);
    assert!(
        !left.iter().any(|n| n.starts_with("loudscape-page")),
        "left behind: {left:?}"
    );
    assert!(String::from_utf8_lossy(&output.stderr).contains("kbit/s"));

    // Without --audio (the default) the page holds no sound.
    let silent = dir.join("silent.html");
    common::assert_success(&page(&web, &[&song(), Path::new("-o"), &silent]));
    let html = std::fs::read_to_string(&silent).unwrap();
    assert_eq!(script(&html, "loudscape-audio").trim(), "");
}

#[test]
fn audio_without_a_sound_to_carry_is_one_line() {
    let dir = common::fresh_dir("page_audio_refused");
    let web = stand_in_viewer(&dir);
    // A song cloud that records no source audio.
    let lonely = dir.join("lonely.ply");
    common::write_song_cloud(&lonely, 2000, 1.0, serde_json::json!({}));
    let timeline = common::repo().join("data/demo_timeline.ply");
    for (input, says) in [
        (lonely.as_path(), "leave out --audio"),
        (timeline.as_path(), "--audio is for a song"),
    ] {
        let out = dir.join("page.html");
        let output = page(&web, &[input, Path::new("-o"), &out, Path::new("--audio")]);
        let text = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{text}");
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(text.contains(says), "{text}");
        assert!(!out.exists());
    }
}

/// The demo with its time 0.5 s later and its levels 6 dB louder (its axes' ends moved, the
/// points as they are), written to `path`: another version of it, as a file.
fn later_and_louder_demo(path: &Path) {
    let demo = loudscape::data::cloud::load(&song()).unwrap();
    let mut meta = demo.meta.raw.clone();
    for (axis, by) in [("x", 0.5), ("y", 6.0), ("scalar", 6.0)] {
        let axis = &mut meta["axes"][axis];
        for end in ["min", "max"] {
            axis[end] = serde_json::json!(axis[end].as_f64().unwrap() + by);
        }
        axis.as_object_mut().unwrap().remove("ticks");
    }
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    loudscape::data::cloud::write(&mut file, &demo.points, Some(&meta)).unwrap();
}

/// `page A --compare B --offset 0.5`: both clouds in the page on the union of their axes (B
/// moved back onto A's time, 6 dB above it), each half's label with B's offset, the title and
/// the note saying it is a compare and what it carries of each.
#[test]
fn a_compare_page_carries_both_clouds_on_their_union_axes() {
    let dir = common::fresh_dir("page_compare");
    let web = stand_in_viewer(&dir);
    let b = dir.join("later.ply");
    later_and_louder_demo(&b);
    let out = dir.join("ab.html");
    let output = page(
        &web,
        &[
            &song(),
            Path::new("--compare"),
            &b,
            Path::new("--offset"),
            Path::new("0.5"),
            Path::new("-o"),
            &out,
        ],
    );
    common::assert_success(&output);
    let said = String::from_utf8_lossy(&output.stderr);
    assert!(
        said.contains("compare: A 147750 of 147750 points"),
        "{said}"
    );
    let html = std::fs::read_to_string(&out).unwrap();
    let decode = |id: &str| {
        let data = gunzip(&unbase64(script(&html, id)));
        loudscape::data::page_cloud::decode(&data, id).expect("page data")
    };
    let (a, b) = (decode("loudscape-cloud"), decode("loudscape-compare"));
    let demo = loudscape::data::cloud::load(&song()).unwrap();
    assert_eq!((a.len(), b.len()), (demo.len(), demo.len()));
    assert_eq!(a.meta.axes, b.meta.axes, "one set of axes");
    let (axes, own) = (&a.meta.axes, &demo.meta.axes);
    assert!((axes.x.min - own.x.min).abs() < 1e-6 && (axes.x.max - own.x.max).abs() < 1e-6);
    assert!((axes.y.max - own.y.max - 6.0).abs() < 1e-6);
    assert!((axes.y.min - own.y.min).abs() < 1e-6);
    // The same points, B's 6 dB up the union's level axis: a tenth of its 66 dB.
    let rise = b.points[1000].position[1] - a.points[1000].position[1];
    assert!((rise - 2.0 * 6.0 / 66.0).abs() < 1e-3, "{rise}");
    assert!(
        html.contains("<title>Compare demo_song.ply with later.ply"),
        "the title"
    );
    assert!(html.contains(r#"["A: demo_song.ply","B: later.ply, +0.50 s"]"#));
    assert!(html.contains("This page carries A: every point; B: every point;"));
}

/// What a compare page cannot be is one line and no page: a timeline on either side, --audio,
/// --offset without --compare.
#[test]
fn a_compare_page_refuses_a_timeline_and_audio_in_one_line() {
    let dir = common::fresh_dir("page_compare_refused");
    let web = stand_in_viewer(&dir);
    let timeline = common::repo().join("data/demo_timeline.ply");
    let out = dir.join("ab.html");
    let (song, o, c) = (song(), Path::new("-o"), Path::new("--compare"));
    let cases: [(Vec<&Path>, &str); 4] = [
        (
            vec![&song, c, &timeline, o, &out],
            "demo_timeline.ply: --compare is for two songs, and this is a timeline",
        ),
        (
            vec![&timeline, c, &song, o, &out],
            "demo_timeline.ply: --compare is for two songs, and this is a timeline",
        ),
        (
            vec![&song, c, &song, o, &out, Path::new("--audio")],
            "--audio is for one song's page",
        ),
        (
            vec![&song, o, &out, Path::new("--offset"), Path::new("1")],
            "need a second cloud: --compare B",
        ),
    ];
    for (args, says) in cases {
        let output = page(&web, &args);
        let text = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{text}");
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(text.contains(says), "{text}");
        assert!(!out.exists());
    }
}

/// A cloud's warnings are said once each, as loading says them ("warning: FILE: MESSAGE"),
/// for a page and a compare page alike: the page said them a second time, as
/// "warning: warning: FILE: MESSAGE".
#[test]
fn a_pages_warnings_are_said_once() {
    let dir = common::fresh_dir("page_warnings_once");
    let web = stand_in_viewer(&dir);
    let message = "decoded 1.49 s of the 4.00 s the file promises";
    let warned = dir.join("warned.ply");
    common::write_song_cloud(
        &warned,
        2000,
        37.0,
        serde_json::json!({ "warnings": [{"kind": "truncated", "message": message}] }),
    );
    let other = dir.join("other.ply");
    common::write_song_cloud(&other, 2000, 11.0, serde_json::json!({}));
    for (args, name) in [
        (vec![warned.as_path()], "one.html"),
        (
            vec![warned.as_path(), Path::new("--compare"), other.as_path()],
            "two.html",
        ),
    ] {
        let out = dir.join(name);
        let mut args = args;
        args.extend([Path::new("-o"), out.as_path()]);
        let output = page(&web, &args);
        let text = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{name}: {text}");
        let said: Vec<&str> = text.lines().filter(|l| l.contains(message)).collect();
        assert_eq!(said.len(), 1, "{name}: said {} times:\n{text}", said.len());
        assert!(said[0].starts_with("warning: "), "{name}: {text}");
        assert!(!text.contains("warning: warning"), "{name}: {text}");
    }
}
