//! Format versions 1 and 2 (docs/FORMAT.md): every fixture in tests/fixtures/format/ (written by
//! the Python extractor's `loudscape_fixtures.formats`) against its `.expected.json`, the
//! exact bytes of non-UTF-8 paths, every version-2 error case of the spec, the Rust writer's
//! version-2 layout, and a 10,000-song timeline header (megabytes, no 64 KiB cap).

use std::path::{Path, PathBuf};

use loudscape::data::cloud::{self, CloudError, DataMode, MAX_HEADER_BYTES, Point};
use serde_json::{Value, json};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format")
}

fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loudscape-format-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

fn fixture_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(fixtures())
        .expect("tests/fixtures/format/ exists")
        .filter_map(|entry| {
            let name = entry.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".ply").map(str::to_owned)
        })
        .collect();
    names.sort();
    names
}

fn record(p: &Point) -> Vec<f32> {
    vec![p.position[0], p.position[1], p.position[2], p.scalar, p.hp]
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("an array of numbers")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

/// The expected float32 values (written by Python as the exact f64 of each float32; JSON
/// parsing may be one f64 ulp off, which rounding to f32 undoes), compared exactly.
fn float32s(v: &Value) -> Vec<f32> {
    floats(v).into_iter().map(|x| x as f32).collect()
}

#[test]
fn every_fixture_matches_its_expected_values() {
    let names = fixture_names();
    for want in [
        "song_v1",
        "song_v2",
        "song_v2_non_utf8",
        "timeline_v1",
        "timeline_v2",
        "timeline_v2_non_utf8",
    ] {
        assert!(names.iter().any(|n| n == want), "fixture {want} missing");
    }
    for name in &names {
        let ply = fixtures().join(format!("{name}.ply"));
        let text = std::fs::read_to_string(fixtures().join(format!("{name}.expected.json")))
            .unwrap_or_else(|e| panic!("{name}.expected.json: {e}"));
        let expected: Value = serde_json::from_str(&text).expect("expected JSON");
        let bytes = std::fs::read(&ply).expect("read fixture");
        let cloud = cloud::load(&ply).unwrap_or_else(|e| panic!("{e}"));

        let count = expected["point_count"].as_u64().expect("point_count") as usize;
        assert_eq!(cloud.len(), count, "{name}: point count");
        let header_bytes = expected["header_bytes"].as_u64().expect("header_bytes") as usize;
        assert_eq!(
            bytes.len(),
            header_bytes + count * cloud::POINT_BYTES,
            "{name}: header length"
        );
        let v2_lines = bytes[..header_bytes]
            .split(|&b| b == b'\n')
            .filter(|l| l.starts_with(b"comment loudscape-meta-v2 "))
            .count() as u64;
        assert_eq!(
            Some(v2_lines),
            expected["meta_v2_lines"].as_u64(),
            "{name}: version-2 parts"
        );
        // float32 values widen to f64 exactly, so the records compare exactly.
        for (i, want) in expected["first_records"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            assert_eq!(
                record(&cloud.points[i]),
                float32s(want),
                "{name}: record {i}"
            );
        }
        let last = expected["last_records"].as_array().unwrap();
        for (k, want) in last.iter().enumerate() {
            let i = count - last.len() + k;
            assert_eq!(
                record(&cloud.points[i]),
                float32s(want),
                "{name}: record {i}"
            );
        }
        let mut sums = [0f64; 5];
        for p in &cloud.points {
            for (sum, v) in sums.iter_mut().zip(record(p)) {
                *sum += f64::from(v);
            }
        }
        for (column, (got, want)) in sums
            .iter()
            .zip(floats(&expected["column_sums"]))
            .enumerate()
        {
            // numpy sums pairwise, this sums in order: they agree to rounding.
            assert!(
                (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
                "{name}: column {column} sums to {got}, expected {want}"
            );
        }
        assert_eq!(cloud.meta.raw, expected["metadata"], "{name}: metadata");
        let mode = expected["metadata"]["mode"].as_str().unwrap();
        let want_mode = if mode == "song" {
            DataMode::Song
        } else {
            DataMode::Timeline
        };
        assert_eq!(cloud.meta.mode, want_mode, "{name}: mode");
        if want_mode == DataMode::Timeline {
            let songs = expected["metadata"]["songs"].as_array().unwrap();
            assert_eq!(cloud.meta.songs.len(), songs.len(), "{name}: songs");
            for (song, want) in cloud.meta.songs.iter().zip(songs) {
                assert_eq!(song.title, want["title"].as_str().unwrap(), "{name}: title");
                assert_eq!(song.x_min, want["x_min"].as_f64(), "{name}: x_min");
            }
        }
    }
}

#[cfg(unix)]
fn os_bytes(path: &Path) -> Vec<u8> {
    use std::os::unix::ffi::OsStrExt;
    path.as_os_str().as_bytes().to_vec()
}

#[cfg(unix)]
#[test]
fn non_utf8_paths_open_by_their_exact_bytes() {
    let song = cloud::load(&fixtures().join("song_v2_non_utf8.ply")).unwrap();
    let source = song.meta.source.as_ref().expect("source");
    assert_eq!(
        source.path.as_deref(),
        Some("data/caf\u{fffd} \u{fffd}.wav")
    );
    assert_eq!(
        source.path_bytes.as_deref(),
        Some(&b"data/caf\xe9 \xff.wav"[..])
    );
    assert_eq!(
        os_bytes(&source.open_path().unwrap()),
        b"data/caf\xe9 \xff.wav"
    );

    let timeline = cloud::load(&fixtures().join("timeline_v2_non_utf8.ply")).unwrap();
    let songs = &timeline.meta.songs;
    assert_eq!(
        os_bytes(&songs[1].open_path().unwrap()),
        b"music/Bj\xf6rk/Debut/01 Human Behaviour.mp3"
    );
    assert!(songs[1].path.as_deref().unwrap().contains('\u{fffd}'));
    // UTF-8 names have no companion and open by their text.
    for i in [0, 2] {
        assert_eq!(songs[i].path_bytes, None);
        assert_eq!(
            songs[i].open_path().map(|p| os_bytes(&p)),
            songs[i].path.as_ref().map(|p| p.as_bytes().to_vec())
        );
    }
    let skipped = &timeline.meta.raw["extraction"]["skipped"][0];
    assert_eq!(
        skipped["path_bytes_b64"],
        json!("bXVzaWMv//4gYnJva2VuIG5hbWUud2F2")
    );

    // Playback looks the audio up by its bytes: put a file there and find it.
    let dir = scratch_dir().join("playback");
    std::fs::create_dir_all(dir.join("data")).unwrap();
    use std::os::unix::ffi::OsStrExt;
    let audio = dir.join(std::ffi::OsStr::from_bytes(b"data/caf\xe9 \xff.wav"));
    std::fs::write(&audio, b"RIFF").unwrap();
    let mut moved = song.clone();
    moved.path = dir.join("song.ply");
    let found = loudscape::playback::resolve_source(&moved).expect("found by its bytes");
    assert_eq!(os_bytes(&found), os_bytes(&audio));
}

/// The lines of a fixture's header and its body.
fn split_fixture(name: &str) -> (Vec<String>, Vec<u8>) {
    let bytes = std::fs::read(fixtures().join(name)).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let lines = header.lines().map(str::to_owned).collect();
    (lines, bytes[end..].to_vec())
}

fn join(lines: &[String], body: &[u8]) -> Vec<u8> {
    let mut bytes = lines.join("\n").into_bytes();
    bytes.push(b'\n');
    bytes.extend_from_slice(body);
    bytes
}

/// Writes `bytes` as `name`, loads it, and checks the one-line message: it starts with the file
/// name and holds every needle.
fn expect_error(name: &str, bytes: &[u8], needles: &[&str]) {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).unwrap();
    let err: CloudError = match cloud::load(&path) {
        Ok(c) => panic!("{name}: loaded {} points, expected an error", c.len()),
        Err(e) => e,
    };
    let message = err.to_string();
    assert!(
        message.starts_with(&format!("{}: ", path.display())) && !message.contains('\n'),
        "{name}: {message}"
    );
    for needle in needles {
        assert!(
            message.contains(needle),
            "{name}: lacks {needle:?}: {message}"
        );
    }
}

#[test]
fn version_2_error_cases_are_refused_naming_the_line() {
    // timeline_v2: parts 1/4..4/4 on lines 3..6.
    let (lines, body) = split_fixture("timeline_v2.ply");
    assert!(lines[2].starts_with("comment loudscape-meta-v2 1/4 "));
    assert!(lines[5].starts_with("comment loudscape-meta-v2 4/4 "));
    let edit = |f: &dyn Fn(&mut Vec<String>)| {
        let mut l = lines.clone();
        f(&mut l);
        join(&l, &body)
    };
    let part = |l: &[String], i: usize| l[i].splitn(4, ' ').nth(3).unwrap().to_owned();
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        (
            "swapped.ply",
            edit(&|l| l.swap(3, 4)),
            vec!["header line 4", "part 3/4 out of order (expected 2/4)"],
        ),
        (
            "first_not_1.ply",
            edit(&|l| {
                l.remove(2);
            }),
            vec!["header line 3", "part 2/4 comes first"],
        ),
        (
            "missing_last.ply",
            edit(&|l| {
                l.remove(5);
            }),
            vec!["header line 3", "has 3 of its 4 parts"],
        ),
        (
            "repeated.ply",
            edit(&|l| {
                let again = l[3].clone();
                l.insert(4, again);
            }),
            vec!["header line 5", "part 2/4 out of order (expected 3/4)"],
        ),
        (
            "extra.ply",
            edit(&|l| l.insert(6, "comment loudscape-meta-v2 5/4 x".into())),
            vec!["header line 7", "more parts than announced"],
        ),
        (
            "changing_n.ply",
            edit(&|l| l[3] = format!("comment loudscape-meta-v2 2/5 {}", part(l, 3))),
            vec!["header line 4", "the part count changed"],
        ),
        (
            "leading_zero.ply",
            edit(&|l| l[3] = format!("comment loudscape-meta-v2 02/4 {}", part(l, 3))),
            vec![
                "header line 4",
                "expected `comment loudscape-meta-v2 I/N CHUNK`",
            ],
        ),
        (
            "two_spaces.ply",
            edit(&|l| l[3] = format!("comment loudscape-meta-v2 2/4  {}", part(l, 3))),
            vec![
                "header line 4",
                "expected `comment loudscape-meta-v2 I/N CHUNK`",
            ],
        ),
        (
            "trailing_space.ply",
            edit(&|l| l[3].push(' ')),
            vec![
                "header line 4",
                "expected `comment loudscape-meta-v2 I/N CHUNK`",
            ],
        ),
        (
            "no_chunk.ply",
            edit(&|l| l[3] = "comment loudscape-meta-v2 2/4".into()),
            vec![
                "header line 4",
                "expected `comment loudscape-meta-v2 I/N CHUNK`",
            ],
        ),
        (
            "bare_keyword.ply",
            edit(&|l| l.insert(2, "comment loudscape-meta-v2".into())),
            vec![
                "header line 3",
                "expected `comment loudscape-meta-v2 I/N CHUNK`",
            ],
        ),
        (
            "both_versions.ply",
            edit(&|l| l.insert(6, "comment loudscape-meta {\"format_version\":1}".into())),
            vec![
                "header line 7",
                "both a version-1 loudscape-meta comment and version-2",
            ],
        ),
        (
            "v1_before_v2.ply",
            edit(&|l| l.insert(2, "comment loudscape-meta {\"format_version\":1}".into())),
            vec![
                "header line 4",
                "both version-2 loudscape-meta-v2 parts and a version-1",
            ],
        ),
        (
            "not_json.ply",
            edit(&|l| l[5] = "comment loudscape-meta-v2 4/4 ]]".into()),
            vec!["header line 3", "loudscape-meta: invalid JSON"],
        ),
        (
            "not_object.ply",
            edit(&|l| {
                l.drain(3..6);
                l[2] = "comment loudscape-meta-v2 1/1 [1,2]".into();
            }),
            vec!["header line 3", "expected a JSON object"],
        ),
    ];
    for (name, bytes, needles) in &cases {
        expect_error(name, bytes, needles);
    }
    // Other comments between parts are fine; the lines may end in \r\n.
    let between = edit(&|l| l.insert(4, "comment made by hand".into()));
    cloud::load_from_bytes(&between, Path::new("between.ply")).expect("comment between parts");
    let crlf: Vec<String> = lines.iter().map(|l| format!("{l}\r")).collect();
    cloud::load_from_bytes(&join(&crlf, &body), Path::new("crlf.ply")).expect("\\r\\n lines");

    // Two version-1 lines.
    let (v1, v1_body) = split_fixture("song_v1.ply");
    let mut twice = v1.clone();
    twice.insert(3, v1[2].clone());
    expect_error(
        "two_v1.ply",
        &join(&twice, &v1_body),
        &[
            "header line 4",
            "second loudscape-meta comment (the first is line 3)",
        ],
    );
}

#[test]
fn bad_base64_companion_is_refused() {
    let (lines, body) = split_fixture("song_v2_non_utf8.ply");
    let text: String = lines
        .iter()
        .filter_map(|l| l.strip_prefix("comment loudscape-meta-v2 "))
        .map(|l| l.split_once(' ').unwrap().1)
        .collect();
    for (bad, reason) in [
        ("ZGF0YS9jYWbpIP8ud2F", "not a multiple of 4"),
        ("ZGF0YS9jYWbpIP8ud2F*", "not in the base64 alphabet"),
        ("ZG=0YS9jYWbpIP8ud2F2", "misplaced `=`"),
    ] {
        let changed = text.replace("ZGF0YS9jYWbpIP8ud2F2", bad);
        let meta: Value = serde_json::from_str(&changed.replace("\\u0020", " ")).unwrap();
        let mut bytes = Vec::new();
        cloud::write_header(&mut bytes, 353, Some(&meta)).unwrap();
        bytes.extend_from_slice(&body);
        expect_error(
            "bad_b64.ply",
            &bytes,
            &[
                "header line 3",
                "`source.path_bytes_b64` is not base64",
                reason,
            ],
        );
    }
}

fn timeline_meta(songs: usize) -> Value {
    let axis = |label: &str| json!({"label": label, "unit": "", "min": 0.0, "max": 1.0, "scale": "linear"});
    let songs: Vec<Value> = (0..songs)
        .map(|i| {
            let a = 2.0 * i as f64 / songs as f64 - 1.0;
            json!({
                "path": format!("music/Artist {i}/Album/{i:05} Some Song Title.flac"),
                "year": 1970 + (i % 50),
                "title": format!("Song number {i}"),
                "artist": format!("Artist {i}"),
                "x_min": a,
                "x_max": a + 2.0 / songs as f64,
                "point_offset": i * 2,
                "point_count": 2,
                "frames_non_silent": 1000,
                "frames_total": 1000,
                "metrics": {"integrated_lufs": -14.0, "lra_lu": 6.5, "sample_peak_dbfs": -0.1,
                            "true_peak_dbtp": 0.2, "plr_db": 14.2, "crest_median_db": 12.0,
                            "crest_p95_db": 18.0, "hp_mean": 0.5}
            })
        })
        .collect();
    json!({
        "format_version": 2,
        "mode": "timeline",
        "point_count": songs.len() * 2,
        "axes": {"x": axis("year"), "y": axis("level"), "z": axis("crest factor"),
                 "scalar": axis("A-weighted level"), "hp": axis("hp")},
        "songs": songs,
        "extraction": {"x_by": "year", "skipped": []}
    })
}

#[test]
fn rust_writer_writes_version_2_that_both_readers_agree_on() {
    let meta = timeline_meta(4);
    let points = vec![
        Point {
            position: [0.0, 0.5, -0.5],
            scalar: 0.25,
            hp: 0.75,
        };
        8
    ];
    let mut bytes = Vec::new();
    cloud::write(&mut bytes, &points, Some(&meta)).unwrap();
    let header = std::str::from_utf8(&bytes[..bytes.len() - 8 * 20]).unwrap();
    let parts: Vec<&str> = header
        .lines()
        .filter(|l| l.starts_with("comment loudscape-meta"))
        .collect();
    assert!(parts.len() >= 2, "{header}");
    for (i, line) in parts.iter().enumerate() {
        assert!(line.len() < 1000, "line {i} is {} bytes", line.len());
        let prefix = format!("comment loudscape-meta-v2 {}/{} ", i + 1, parts.len());
        let chunk = line.strip_prefix(&prefix).expect("numbered part");
        assert!(chunk.bytes().all(|b| (0x21..=0x7e).contains(&b)));
        if i + 1 < parts.len() {
            assert_eq!(chunk.len(), cloud::META_CHUNK_BYTES);
        }
    }
    let cloud = cloud::load_from_bytes(&bytes, Path::new("written.ply")).unwrap();
    assert_eq!(cloud.points, points);
    assert_eq!(cloud.meta.raw, meta);
    // Version 1 on request.
    let mut v1 = Vec::new();
    cloud::write_header_version(&mut v1, 8, Some(&meta), 1).unwrap();
    let v1_text = std::str::from_utf8(&v1).unwrap();
    assert_eq!(v1_text.matches("comment loudscape-meta {").count(), 1);
    assert!(v1_text.contains("\"format_version\":1"));
}

#[test]
fn a_10000_song_timeline_header_of_megabytes_loads() {
    let meta = timeline_meta(10_000);
    let points = vec![
        Point {
            position: [0.0; 3],
            scalar: 0.5,
            hp: 0.5,
        };
        20_000
    ];
    let mut bytes = Vec::new();
    cloud::write(&mut bytes, &points, Some(&meta)).unwrap();
    let header_bytes = bytes.len() - points.len() * 20;
    assert!(
        header_bytes > 4 << 20 && (header_bytes as u64) < MAX_HEADER_BYTES,
        "{header_bytes}"
    );
    let path = scratch_dir().join("timeline_10000.ply");
    std::fs::write(&path, &bytes).unwrap();
    let started = std::time::Instant::now();
    let cloud = cloud::load(&path).unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "10,000-song timeline: {header_bytes} header bytes loaded in {:?}",
        started.elapsed()
    );
    assert_eq!(cloud.meta.songs.len(), 10_000);
    assert_eq!(cloud.meta.songs[9_999].title, "Song number 9999");
    assert_eq!(cloud.len(), 20_000);
    // The hover's song lookup (once per cursor move): finds every song, and is cheap.
    let songs = &cloud.meta.songs;
    let started = std::time::Instant::now();
    for i in (0..10_000).step_by(10) {
        let centre = (songs[i].x_min.unwrap() + songs[i].x_max.unwrap()) / 2.0;
        assert_eq!(
            loudscape::view::pick::song_at(songs, centre as f32),
            Some(i)
        );
    }
    eprintln!(
        "song_at over 10,000 songs: {:?} a lookup",
        started.elapsed() / 1000
    );
}
