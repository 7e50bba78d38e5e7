//! The PLY loader against valid, generic and malformed files.
//!
//! Files are written at run time into a scratch folder, so every error message can be checked
//! for the file name, the place (header line or byte offset) and the reason.
//! [`check_against_expected`] compares a loaded file with an expected-values JSON written by the
//! Python side (point count, first and last records, per-column sums).

use std::path::{Path, PathBuf};

use loudscape::data::cloud::{self, CloudError, DataMode, Point, PointCloud};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------------------------
// Helpers

fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loudscape-cloud-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

fn write_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

fn song_meta() -> Value {
    json!({
        "format_version": 1,
        "mode": "song",
        "point_count": 10,
        "axes": {
            "x": {"label": "time", "unit": "s", "min": 0.0, "max": 12.5, "scale": "linear"},
            "y": {"label": "frequency", "unit": "Hz", "min": 20.0, "max": 20000.0, "scale": "log"},
            "z": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0, "scale": "linear"},
            "scalar": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0, "scale": "linear"},
            "hp": {"label": "harmonic ratio", "unit": "", "min": 0.0, "max": 1.0, "scale": "linear"}
        },
        "source": {"path": "song.wav", "sample_rate": 48000, "channels": 2, "duration_s": 12.5},
        "stft": {"n_fft": 2048, "hop_length": 512, "window": "hann"},
        "metrics": {"integrated_lufs": -9.5, "lra_lu": 4.0, "sample_peak_dbfs": -0.1,
                    "true_peak_dbtp": 0.3, "plr_db": 9.8, "crest_median_db": 11.0,
                    "crest_p95_db": null},
        "some_future_key": {"ignored": true}
    })
}

fn sample_points(n: usize) -> Vec<Point> {
    (0..n)
        .map(|i| {
            let t = if n > 1 {
                i as f32 / (n - 1) as f32
            } else {
                0.5
            };
            Point {
                position: [t * 2.0 - 1.0, 1.0 - t * 2.0, (t - 0.5) * 0.5],
                scalar: t,
                hp: 1.0 - t,
            }
        })
        .collect()
}

fn file_bytes(points: &[Point], meta: &Value) -> Vec<u8> {
    let mut bytes = Vec::new();
    cloud::write(&mut bytes, points, Some(meta)).expect("write to memory");
    bytes
}

/// A valid 10-point song file.
fn valid_bytes() -> Vec<u8> {
    file_bytes(&sample_points(10), &song_meta())
}

/// Length of the header, `end_header\n` included.
fn header_len(bytes: &[u8]) -> usize {
    let marker = b"end_header\n";
    bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("header has end_header")
        + marker.len()
}

/// A loudscape header with the standard lines replaced: `lines` is the full header text
/// (without the final newline), `{META}` stands for the meta comment.
fn header_text(lines: &[&str]) -> String {
    let meta = format!("comment loudscape-meta {}", song_meta());
    let mut text = String::new();
    for line in lines {
        text.push_str(&line.replace("{META}", &meta));
        text.push('\n');
    }
    text
}

const STANDARD: [&str; 10] = [
    "ply",
    "format binary_little_endian 1.0",
    "{META}",
    "element vertex 10",
    "property float x",
    "property float y",
    "property float z",
    "property float scalar",
    "property float hp",
    "end_header",
];

/// The standard header with line `number` (1-based) replaced by `line`, then 10 valid points.
fn with_header_line(number: usize, line: &str) -> Vec<u8> {
    let mut lines = STANDARD.to_vec();
    lines[number - 1] = line;
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    bytes
}

/// Writes `bytes` as `name`, loads it, and checks that it fails with a one-line message that
/// names the file and contains every one of `needles`.
fn expect_error(name: &str, bytes: &[u8], needles: &[&str]) -> CloudError {
    let path = write_file(name, bytes);
    let err = match cloud::load(&path) {
        Ok(cloud) => panic!("{name}: loaded {} points, expected an error", cloud.len()),
        Err(err) => err,
    };
    let message = err.to_string();
    assert!(
        message.starts_with(&format!("{}: ", path.display())),
        "{name}: message does not start with the file name: {message}"
    );
    assert!(
        !message.contains('\n'),
        "{name}: message spans lines: {message}"
    );
    for needle in needles {
        assert!(
            message.contains(needle),
            "{name}: message lacks {needle:?}: {message}"
        );
    }
    assert_eq!(err.path(), path);
    err
}

fn set_value(bytes: &mut [u8], point: usize, field: usize, value: f32) {
    let at = header_len(bytes) + point * 20 + field * 4;
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

fn in_range(cloud: &PointCloud) -> bool {
    cloud.points.iter().all(|p| {
        p.position.iter().all(|v| (-1.0..=1.0).contains(v))
            && (0.0..=1.0).contains(&p.scalar)
            && (0.0..=1.0).contains(&p.hp)
    })
}

/// Loads `ply` and compares it with the expected values in `expected` (JSON written by the
/// extractor's tests): `point_count`, the first and last records, and per-column sums.
/// Records are `[x, y, z, scalar, hp]` arrays or objects with those keys; the key names tried
/// are listed in the code so the Python side's choice needs no change here.
pub fn check_against_expected(ply: &Path, expected: &Path) {
    let cloud = cloud::load(ply).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(expected)
        .unwrap_or_else(|e| panic!("{}: cannot read: {e}", expected.display()));
    let expected_json: Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{}: invalid JSON: {e}", expected.display()));
    let key = |names: &[&str]| -> &Value {
        names
            .iter()
            .find_map(|n| expected_json.get(*n))
            .unwrap_or_else(|| panic!("{}: none of the keys {names:?}", expected.display()))
    };
    let record = |v: &Value| -> [f64; 5] {
        let get = |i: usize, name: &str| {
            v.get(i)
                .or_else(|| v.get(name))
                .and_then(Value::as_f64)
                .unwrap_or_else(|| panic!("bad expected record {v}"))
        };
        [
            get(0, "x"),
            get(1, "y"),
            get(2, "z"),
            get(3, "scalar"),
            get(4, "hp"),
        ]
    };
    let actual = |p: &Point| -> [f64; 5] {
        [p.position[0], p.position[1], p.position[2], p.scalar, p.hp].map(f64::from)
    };
    let close = |a: f64, b: f64, tolerance: f64| (a - b).abs() <= tolerance * (1.0 + b.abs());

    let count = key(&["point_count", "count", "n_points"])
        .as_u64()
        .expect("point_count is a whole number") as usize;
    assert_eq!(cloud.len(), count, "point count");
    let first = key(&["first", "first_3", "first_records", "head"])
        .as_array()
        .expect("first records are an array");
    for (i, want) in first.iter().enumerate() {
        let (want, got) = (record(want), actual(&cloud.points[i]));
        assert!(
            want.iter().zip(got).all(|(w, g)| close(g, *w, 1e-6)),
            "record {i}: expected {want:?}, found {got:?}"
        );
    }
    let last = key(&["last", "last_3", "last_records", "tail"])
        .as_array()
        .expect("last records are an array");
    for (k, want) in last.iter().enumerate() {
        let i = count - last.len() + k;
        let (want, got) = (record(want), actual(&cloud.points[i]));
        assert!(
            want.iter().zip(got).all(|(w, g)| close(g, *w, 1e-6)),
            "record {i}: expected {want:?}, found {got:?}"
        );
    }
    let sums = record(key(&["sums", "column_sums", "sum"]));
    let mut got = [0f64; 5];
    for p in &cloud.points {
        for (sum, v) in got.iter_mut().zip(actual(p)) {
            *sum += v;
        }
    }
    for (i, (want, got)) in sums.iter().zip(got).enumerate() {
        assert!(
            close(got, *want, 1e-6),
            "sum of column {}: expected {want}, found {got}",
            ["x", "y", "z", "scalar", "hp"][i]
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Valid files

#[test]
fn round_trip_through_a_file() {
    let points = sample_points(10);
    let path = write_file("round_trip.ply", &file_bytes(&points, &song_meta()));
    let cloud = cloud::load(&path).expect("valid file loads");
    assert_eq!(cloud.path, path);
    assert_eq!(cloud.points, points);
    assert_eq!(cloud.meta.mode, DataMode::Song);
    assert_eq!(cloud.meta.point_count, Some(10));
    assert_eq!(cloud.meta.axes.x.unit, "s");
    assert_eq!(cloud.meta.axes.y.scale, cloud::AxisScale::Log);
    assert_eq!(
        cloud.meta.source.as_ref().and_then(|s| s.sample_rate),
        Some(48000)
    );
    assert_eq!(cloud.meta.stft.as_ref().and_then(|s| s.n_fft), Some(2048));
    let metrics = cloud.meta.metrics.as_ref().expect("metrics");
    assert_eq!(metrics.integrated_lufs, Some(-9.5));
    assert_eq!(metrics.crest_p95_db, None);
    assert_eq!(cloud.meta.raw["some_future_key"]["ignored"], json!(true));
    assert_eq!(cloud.bounds.min.x, -1.0);
    assert_eq!(cloud.bounds.max.x, 1.0);
    assert_eq!(cloud.as_bytes().len(), 200);
}

#[test]
fn timeline_with_songs() {
    let mut meta = song_meta();
    meta["mode"] = json!("timeline");
    meta["axes"]["x"] = json!({"label": "year", "unit": "year", "min": 1960, "max": 2024});
    meta["songs"] = json!([
        {"title": "A", "artist": "B", "year": 1984, "path": "a.flac", "x_min": -1.0, "x_max": -0.5,
         "metrics": {"integrated_lufs": -12.0}, "genre": "pop"},
        {"title": "C", "artist": "D", "year": 2001.0}
    ]);
    let path = write_file("timeline.ply", &file_bytes(&sample_points(10), &meta));
    let cloud = cloud::load(&path).expect("timeline loads");
    assert_eq!(cloud.meta.mode, DataMode::Timeline);
    assert_eq!(cloud.meta.songs.len(), 2);
    assert_eq!(cloud.meta.songs[0].year, Some(1984));
    assert_eq!(cloud.meta.songs[0].x_max, Some(-0.5));
    assert_eq!(cloud.meta.songs[0].extra["genre"], json!("pop"));
    assert_eq!(
        cloud.meta.songs[0]
            .metrics
            .as_ref()
            .and_then(|m| m.integrated_lufs),
        Some(-12.0)
    );
    assert_eq!(cloud.meta.songs[1].year, Some(2001));
    assert_eq!(cloud.meta.songs[1].path, None);
}

#[test]
fn empty_cloud_loads() {
    let mut meta = song_meta();
    meta["point_count"] = json!(0);
    let path = write_file("empty_cloud.ply", &file_bytes(&[], &meta));
    let cloud = cloud::load(&path).expect("empty cloud loads");
    assert!(cloud.is_empty());
    assert_eq!(cloud.bounds, cloud::Aabb::NORMALIZED_CUBE);
}

#[test]
fn values_within_epsilon_of_the_range_load() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 0, 0, -1.000_004);
    set_value(&mut bytes, 1, 4, 1.000_004);
    let path = write_file("epsilon.ply", &bytes);
    cloud::load(&path).expect("values within epsilon load");
}

#[test]
fn crlf_header_and_other_comments_load() {
    let text = header_text(&STANDARD).replace('\n', "\r\n").replacen(
        "ply\r\n",
        "ply\r\ncomment written on Windows\r\n",
        1,
    );
    let mut bytes = text.into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    let path = write_file("crlf.ply", &bytes);
    assert_eq!(cloud::load(&path).expect("loads").len(), 10);
}

#[test]
fn generic_ascii_xyz() {
    let text = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\n\
                property float x\nproperty float y\nproperty float z\n\
                property uchar red\nproperty uchar green\nproperty uchar blue\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                0 0 0 255 0 0\n10 0 0 0 255 0\n0 5 0 0 0 255\n\n0 0 2 1 2 3\n3 0 1 2\n";
    let path = write_file("generic.ply", text.as_bytes());
    let cloud = cloud::load(&path).expect("generic ascii loads");
    assert_eq!(cloud.meta.mode, DataMode::Generic);
    assert_eq!(cloud.len(), 4);
    assert!(in_range(&cloud));
    assert!(cloud.points.iter().all(|p| p.scalar == 1.0 && p.hp == 0.5));
    // Longest side (x, 10 units) spans [-1, 1]; the others keep the aspect.
    assert_eq!(cloud.points[0].position, [-1.0, -0.5, -0.2]);
    assert_eq!(cloud.points[1].position, [1.0, -0.5, -0.2]);
    assert_eq!(cloud.points[3].position, [-1.0, -0.5, 0.2]);
    let axes = &cloud.meta.axes;
    assert_eq!(
        (axes.x.label.as_str(), axes.x.min, axes.x.max),
        ("x", 0.0, 10.0)
    );
    assert_eq!((axes.y.min, axes.y.max), (-2.5, 7.5));
    assert_eq!((axes.z.min, axes.z.max), (-4.0, 6.0));
    // Ticks come out in the file's units.
    let labels: Vec<String> = axes.x.ticks(6).into_iter().map(|t| t.label).collect();
    assert_eq!(labels, ["0", "2", "4", "6", "8", "10"]);
}

#[test]
fn generic_binary_double_with_normals_and_faces() {
    let count = 50usize;
    let mut bytes = b"ply\nformat binary_little_endian 1.0\ncomment Open3D-like\n\
        element vertex 50\nproperty double x\nproperty double y\nproperty double z\n\
        property float nx\nproperty float ny\nproperty float nz\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for i in 0..count {
        // Survey-like coordinates: a large offset with small steps.
        for v in [
            500_000.0 + i as f64 * 0.25,
            4_000_000.0 - i as f64 * 0.1,
            12.0,
        ] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 1.0] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes.extend_from_slice(&[10, 20, 30]);
    }
    for face in [[0i32, 1, 2], [2, 3, 4]] {
        bytes.push(3);
        for v in face {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    let path = write_file("generic_double.ply", &bytes);
    let cloud = cloud::load(&path).expect("generic binary loads");
    assert_eq!(cloud.meta.mode, DataMode::Generic);
    assert_eq!(cloud.len(), count);
    assert!(in_range(&cloud));
    assert!(cloud.points.iter().all(|p| p.scalar == 1.0 && p.hp == 0.5));
    let first = cloud.points[0].position;
    let last = cloud.points[count - 1].position;
    assert!(
        (first[0] + 1.0).abs() < 1e-6 && (last[0] - 1.0).abs() < 1e-6,
        "{first:?} {last:?}"
    );
    // y spans 4.9 of x's 12.25: aspect kept.
    assert!((first[1] - last[1] - 2.0 * 4.9 / 12.25).abs() < 1e-5);
    assert!((cloud.meta.axes.x.min - 500_000.0).abs() < 1e-6);
    assert!((cloud.meta.axes.x.max - 500_012.25).abs() < 1e-6);
}

#[test]
fn generic_single_point_and_empty() {
    let one = "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n\
               property double z\nend_header\n5 5 5\n";
    let cloud = cloud::load(&write_file("one.ply", one.as_bytes())).expect("loads");
    assert_eq!(cloud.points[0].position, [0.0, 0.0, 0.0]);
    assert_eq!((cloud.meta.axes.x.min, cloud.meta.axes.x.max), (4.0, 6.0));
    let none = "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
                property float z\nend_header\n";
    let cloud = cloud::load(&write_file("none.ply", none.as_bytes())).expect("loads");
    assert!(cloud.is_empty());
}

// ---------------------------------------------------------------------------------------------
// Malformed files: one test per case

#[test]
fn truncated_body() {
    let bytes = valid_bytes();
    let end = bytes.len() - 7;
    let offset = end.to_string();
    expect_error(
        "truncated.ply",
        &bytes[..end],
        &[
            "truncated body",
            &format!("byte {offset}"),
            "header line 4",
            "10 points",
            "193 bytes",
        ],
    );
}

#[test]
fn trailing_bytes() {
    let mut bytes = valid_bytes();
    let end = bytes.len();
    bytes.extend_from_slice(b"xyz");
    expect_error(
        "trailing.ply",
        &bytes,
        &[&format!("byte {end}"), "3 trailing bytes", "10 points"],
    );
}

#[test]
fn wrong_magic() {
    let mut bytes = valid_bytes();
    bytes[2] = b'x';
    expect_error(
        "magic.ply",
        &bytes,
        &["header line 1", "not a PLY file", "`plx`"],
    );
    expect_error(
        "magic_png.ply",
        b"\x89PNG\r\n\x1a\n",
        &["header line 1", "not a PLY file"],
    );
}

#[test]
fn wrong_format_line() {
    let bytes = with_header_line(2, "format binary_big_endian 1.0");
    expect_error(
        "big_endian.ply",
        &bytes,
        &["header line 2", "binary_little_endian"],
    );
    let bytes = with_header_line(2, "format binary_little_endian 2.0");
    expect_error(
        "version.ply",
        &bytes,
        &[
            "header line 2",
            "expected `format binary_little_endian 1.0`",
        ],
    );
    let bytes = with_header_line(2, "format ascii 1.0");
    expect_error(
        "ascii_loudscape.ply",
        &bytes,
        &["header line 2", "must be `format binary_little_endian"],
    );
    let bytes = with_header_line(2, "format zip 1.0");
    expect_error("zip.ply", &bytes, &["header line 2", "unknown format"]);
}

#[test]
fn wrong_count() {
    let mut meta = song_meta();
    meta["point_count"] = json!(9);
    let mut bytes = header_text(&STANDARD)
        .replace("element vertex 10", "element vertex 9")
        .replace(&song_meta().to_string(), &meta.to_string())
        .into_bytes();
    let end = bytes.len() + 9 * 20;
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "count_low.ply",
        &bytes,
        &[&format!("byte {end}"), "20 trailing bytes", "header line 4"],
    );
    // The header and the metadata disagree.
    let bytes = with_header_line(4, "element vertex 11");
    expect_error(
        "count_meta.ply",
        &bytes,
        &[
            "header line 3",
            "point_count 10 does not match `element vertex 11`",
        ],
    );
}

#[test]
fn missing_count() {
    let bytes = with_header_line(4, "element vertex");
    expect_error("no_count.ply", &bytes, &["header line 4", "no count"]);
    let bytes = with_header_line(4, "element vertex ten");
    expect_error(
        "word_count.ply",
        &bytes,
        &["header line 4", "`ten` is not a whole number"],
    );
    let bytes = with_header_line(4, "element vertex -10");
    expect_error(
        "negative_count.ply",
        &bytes,
        &["header line 4", "not a whole number"],
    );
}

#[test]
fn wrong_property_name() {
    let bytes = with_header_line(7, "property float w");
    expect_error(
        "name.ply",
        &bytes,
        &[
            "header line 7",
            "expected `property float z`, found `property float w`",
        ],
    );
}

#[test]
fn wrong_property_type() {
    let bytes = with_header_line(8, "property double scalar");
    expect_error(
        "double.ply",
        &bytes,
        &[
            "header line 8",
            "expected `property float scalar`, found `property double scalar`",
        ],
    );
    let bytes = with_header_line(8, "property half scalar");
    expect_error(
        "half.ply",
        &bytes,
        &["header line 8", "unknown property type `half`"],
    );
}

#[test]
fn wrong_property_order() {
    let mut lines = STANDARD.to_vec();
    lines.swap(7, 8);
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "order.ply",
        &bytes,
        &[
            "header line 8",
            "expected `property float scalar`, found `property float hp`",
        ],
    );
}

#[test]
fn extra_property_in_a_loudscape_file() {
    let mut lines = STANDARD.to_vec();
    lines.insert(9, "property float extra");
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "extra.ply",
        &bytes,
        &["header line 10", "unexpected `property float extra`"],
    );
    // A missing property is as wrong as an extra one.
    let mut lines = STANDARD.to_vec();
    lines.remove(8);
    let bytes = header_text(&lines).into_bytes();
    expect_error(
        "missing_hp.ply",
        &bytes,
        &["header line 9", "missing `property float hp`"],
    );
    // So is a second element.
    let mut lines = STANDARD.to_vec();
    lines.insert(9, "element face 0");
    let bytes = header_text(&lines).into_bytes();
    expect_error(
        "face.ply",
        &bytes,
        &["header line 10", "unexpected `element face`"],
    );
}

#[test]
fn nan_value() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 3, 0, f32::NAN);
    let at = header_len(&bytes) + 60;
    expect_error(
        "nan.ply",
        &bytes,
        &[&format!("point 3 at byte {at}"), "x is NaN"],
    );
}

#[test]
fn infinite_value() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 5, 3, f32::INFINITY);
    let at = header_len(&bytes) + 5 * 20 + 12;
    expect_error(
        "inf.ply",
        &bytes,
        &[&format!("point 5 at byte {at}"), "scalar is +inf"],
    );
}

#[test]
fn out_of_range_values() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 2, 0, 1.5);
    let at = header_len(&bytes) + 40;
    expect_error(
        "x_range.ply",
        &bytes,
        &[
            &format!("point 2 at byte {at}"),
            "x = 1.5 is outside [-1, 1]",
        ],
    );
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 9, 4, -0.25);
    let at = header_len(&bytes) + 9 * 20 + 16;
    expect_error(
        "hp_range.ply",
        &bytes,
        &[
            &format!("point 9 at byte {at}"),
            "hp = -0.25 is outside [0, 1]",
        ],
    );
}

#[test]
fn huge_count_in_a_tiny_file() {
    let mut meta = song_meta();
    meta.as_object_mut().expect("object").remove("point_count");
    let text = header_text(&STANDARD).replace(&song_meta().to_string(), &meta.to_string());
    let huge = text.replace("element vertex 10", "element vertex 4000000000000");
    let started = std::time::Instant::now();
    expect_error(
        "huge.ply",
        huge.as_bytes(),
        &[
            "truncated body",
            "header line 4",
            "4000000000000 points",
            "only 0 bytes",
        ],
    );
    assert!(
        started.elapsed().as_secs_f64() < 1.0,
        "failed slowly: nothing should be allocated"
    );
    // N * 20 overflows 64 bits.
    let overflow = text.replace("element vertex 10", "element vertex 18446744073709551615");
    expect_error(
        "overflow.ply",
        overflow.as_bytes(),
        &["header line 4", "too large"],
    );
    // N does not fit in 64 bits.
    let beyond = text.replace(
        "element vertex 10",
        "element vertex 99999999999999999999999",
    );
    expect_error(
        "beyond.ply",
        beyond.as_bytes(),
        &["header line 4", "not a whole number"],
    );
    // A generic file gets the same protection.
    let generic = "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\n\
                   property float x\nproperty float y\nproperty float z\nend_header\n";
    expect_error(
        "huge_generic.ply",
        generic.as_bytes(),
        &["truncated body", "header line 3"],
    );
    let generic = generic.replace("binary_little_endian", "ascii");
    expect_error(
        "huge_ascii.ply",
        generic.as_bytes(),
        &["header line 3", "needs at least"],
    );
}

#[test]
fn header_without_end_header() {
    let text = header_text(&STANDARD[..9]);
    expect_error(
        "no_end.ply",
        text.as_bytes(),
        &["header line 10", "ends before `end_header`"],
    );
    // A 10 MB line where the header should end: the file ends first (the cap is 64 MiB).
    let mut bytes = header_text(&STANDARD[..9]).into_bytes();
    bytes.extend(std::iter::repeat_n(b'a', 10 * 1024 * 1024));
    expect_error(
        "long_line.ply",
        &bytes,
        &["header line 10", "ends before `end_header`"],
    );
    // A stream (no length known) of endless header: stops at the cap.
    let endless = std::io::Read::chain(
        std::io::Cursor::new(header_text(&STANDARD[..9]).into_bytes()),
        std::io::repeat(b'a'),
    );
    let err = cloud::load_from_reader(endless, Path::new("endless.ply"), None)
        .expect_err("an endless header fails");
    let message = err.to_string();
    assert!(
        message.starts_with("endless.ply: header line 10: ")
            && message.contains("longer than 64 MiB without `end_header`"),
        "{message}"
    );
}

/// A change to a valid meta object that makes it invalid.
type MetaChange = fn(&mut Value);

fn remove(value: &mut Value, key: &str) {
    if let Some(object) = value.as_object_mut() {
        object.remove(key);
    }
}

#[test]
fn bad_json_meta() {
    let bytes = with_header_line(
        3,
        "comment loudscape-meta {\"format_version\": 1, \"mode\": ",
    );
    expect_error(
        "json.ply",
        &bytes,
        &["header line 3", "loudscape-meta: invalid JSON"],
    );
    let cases: [(&str, MetaChange, &str); 7] = [
        (
            "no_version",
            |m| remove(m, "format_version"),
            "missing `format_version`",
        ),
        (
            "version_3",
            |m| m["format_version"] = json!(3),
            "format_version 3 is not supported",
        ),
        ("no_mode", |m| remove(m, "mode"), "missing `mode`"),
        (
            "bad_mode",
            |m| m["mode"] = json!("album"),
            "`mode` must be \"song\" or \"timeline\", found \"album\"",
        ),
        ("no_axes", |m| remove(m, "axes"), "missing `axes`"),
        (
            "no_hp_axis",
            |m| remove(&mut m["axes"], "hp"),
            "`axes` has no `hp` axis",
        ),
        (
            "log_zero",
            |m| m["axes"]["y"]["min"] = json!(0.0),
            "`axes.y`: a log axis needs positive min and max",
        ),
    ];
    for (name, change, needle) in cases {
        let mut meta = song_meta();
        change(&mut meta);
        // Written by hand: the writer owns `format_version` and would set it.
        let bytes = with_header_line(3, &format!("comment loudscape-meta {meta}"));
        expect_error(&format!("{name}.ply"), &bytes, &["header line 3", needle]);
    }
    let mut meta = song_meta();
    meta["axes"]["x"]["min"] = json!("zero");
    expect_error(
        "axis_type.ply",
        &file_bytes(&sample_points(10), &meta),
        &["header line 3", "`axes.x`"],
    );
    let mut meta = song_meta();
    meta["metrics"]["plr_db"] = json!("loud");
    expect_error(
        "metric_type.ply",
        &file_bytes(&sample_points(10), &meta),
        &["header line 3", "`metrics`"],
    );
}

#[test]
fn empty_file() {
    expect_error("empty.ply", b"", &["header line 1", "empty"]);
}

#[test]
fn non_utf8_header() {
    let bytes = with_header_line(3, "comment caf\u{e9}");
    let mut bytes = bytes;
    let at = bytes.iter().position(|&b| b == 0xc3).expect("the e acute");
    bytes[at] = 0xff;
    expect_error("utf8.ply", &bytes, &["header line 3", "not valid UTF-8"]);
}

#[test]
fn other_header_mistakes() {
    let bytes = with_header_line(5, "propertyfloat x");
    expect_error(
        "keyword.ply",
        &bytes,
        &["header line 5", "unknown header keyword"],
    );
    let mut lines = STANDARD.to_vec();
    lines.remove(1);
    expect_error(
        "no_format.ply",
        header_text(&lines).as_bytes(),
        &["header line 9", "no `format` line"],
    );
    let generic = "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\n\
                   property float y\nproperty float z\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0";
    expect_error(
        "generic_big_endian.ply",
        generic.as_bytes(),
        &["header line 2", "binary_big_endian PLY is not supported"],
    );
    let no_z = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n";
    expect_error(
        "no_z.ply",
        no_z.as_bytes(),
        &["header line 3", "no property `z`"],
    );
    let words = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n1 2 3\n1 two 3\n";
    let second_line = header_len(words.as_bytes()) + "1 2 3\n".len();
    expect_error(
        "ascii_word.ply",
        words.as_bytes(),
        &[
            &format!("byte {second_line}"),
            "line 9",
            "`two` is not a number",
        ],
    );
    let short = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n1.0 2.0 3.0\n4.0 5.0 6.0\n";
    expect_error(
        "ascii_short.ply",
        short.as_bytes(),
        &["ends after 2 of 3 vertex records"],
    );
    let nan = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
               property float z\nend_header\n1 2 3\n1 nan 3\n";
    expect_error(
        "ascii_nan.ply",
        nan.as_bytes(),
        &[
            &format!("point 1 at byte {second_line}"),
            "line 9",
            "y is NaN",
        ],
    );
    let dir = scratch_dir();
    let err = cloud::load(&dir).expect_err("a directory is not a file");
    assert!(
        err.to_string().starts_with(&dir.display().to_string()),
        "{err}"
    );
    let missing = dir.join("does_not_exist.ply");
    let err = cloud::load(&missing).expect_err("missing file");
    assert!(
        err.to_string().contains("does_not_exist.ply: cannot open"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// Robustness

/// xorshift64*: a small deterministic generator, so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn random_mutations_never_panic() {
    let valid = valid_bytes();
    let generic = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nproperty list uchar int idx\nend_header\n\
                    0 0 0 2 1 2\n1 1 1 0\n2 0 1 1 7\n"
        .to_vec();
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let interesting: [&[u8]; 8] = [
        b"\n",
        b" ",
        b"9",
        b"-",
        b"end_header\n",
        b"\xff",
        b"list ",
        b"99999999999",
    ];
    let mut loaded = 0;
    for round in 0..2000 {
        let mut bytes = if round % 4 == 3 {
            generic.clone()
        } else {
            valid.clone()
        };
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len() + 1);
            match rng.below(6) {
                0 if at < bytes.len() => bytes[at] ^= 1 << rng.below(8),
                1 if at < bytes.len() => bytes[at] = rng.next() as u8,
                2 => bytes.truncate(at),
                3 => {
                    let piece = interesting[rng.below(interesting.len())];
                    bytes.splice(at..at, piece.iter().copied());
                }
                4 if at < bytes.len() => {
                    let end = (at + 1 + rng.below(16)).min(bytes.len());
                    bytes.drain(at..end);
                }
                _ => bytes.extend((0..rng.below(8)).map(|_| rng.next() as u8)),
            }
        }
        let name = Path::new("mutated.ply");
        let result = if round % 2 == 0 {
            cloud::load_from_bytes(&bytes, name)
        } else {
            cloud::load_from_reader(bytes.as_slice(), name, None)
        };
        match result {
            Ok(cloud) => {
                loaded += 1;
                assert!(
                    in_range(&cloud),
                    "round {round}: loaded values out of range"
                );
            }
            Err(err) => {
                let message = err.to_string();
                assert!(
                    message.starts_with("mutated.ply: "),
                    "round {round}: {message}"
                );
                assert!(!message.contains('\n'), "round {round}: {message}");
            }
        }
    }
    assert!(
        loaded > 0 && loaded < 2000,
        "mutations should both break and spare files: {loaded}"
    );
}

// ---------------------------------------------------------------------------------------------
// Fixture written by the Python extractor

#[test]
fn expected_values_helper_accepts_a_matching_file() {
    let points = sample_points(10);
    let ply = write_file("expected_self.ply", &file_bytes(&points, &song_meta()));
    let record = |p: &Point| json!([p.position[0], p.position[1], p.position[2], p.scalar, p.hp]);
    let mut sums = [0f64; 5];
    for p in &points {
        for (s, v) in
            sums.iter_mut()
                .zip([p.position[0], p.position[1], p.position[2], p.scalar, p.hp])
        {
            *s += f64::from(v);
        }
    }
    let expected = json!({
        "point_count": 10,
        "first": points[..3].iter().map(record).collect::<Vec<_>>(),
        "last": points[7..].iter().map(record).collect::<Vec<_>>(),
        "sums": {"x": sums[0], "y": sums[1], "z": sums[2], "scalar": sums[3], "hp": sums[4]},
    });
    let expected_path = write_file(
        "expected_self.expected.json",
        expected.to_string().as_bytes(),
    );
    check_against_expected(&ply, &expected_path);
}

#[test]
fn fixture_song_matches_expected() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let (ply, expected) = (
        data.join("fixture_song.ply"),
        data.join("fixture_song.expected.json"),
    );
    check_against_expected(&ply, &expected);
    // The metadata the extractor wrote is the metadata the reader parsed.
    let cloud = loudscape::data::cloud::load(&ply).expect("fixture loads");
    let text = std::fs::read_to_string(&expected).expect("expected values");
    let want: Value = serde_json::from_str(&text).expect("expected JSON");
    assert_eq!(
        cloud.meta.raw, want["metadata"],
        "metadata differs from the expected values"
    );
    assert_eq!(cloud.meta.mode, loudscape::data::cloud::DataMode::Song);
    let metrics = cloud.meta.metrics.as_ref().expect("song metrics");
    assert_eq!(
        metrics.integrated_lufs,
        want["metadata"]["metrics"]["integrated_lufs"].as_f64()
    );
}
