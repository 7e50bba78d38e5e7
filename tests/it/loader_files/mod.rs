//! Helpers of the PLY loader's tests (tests/it/cloud_loader.rs, tests/it/cloud_loader_malformed.rs):
//! files written at run time into a scratch folder, a standard header to vary line by line, the
//! one-line error check, and [`check_against_expected`] for the extractor's expected-values JSON.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use loudscape::data::cloud::{self, CloudError, Point, PointCloud};
use serde_json::{Value, json};

/// A scratch folder of the calling test's own: the test modules share one process, and two of
/// them may write files of the same name (libtest names each test's thread after the test).
pub fn scratch_dir() -> PathBuf {
    let test = std::thread::current()
        .name()
        .unwrap_or("main")
        .replace("::", "-");
    let dir = std::env::temp_dir()
        .join(format!("loudscape-cloud-tests-{}", std::process::id()))
        .join(test);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

pub fn write_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

pub fn song_meta() -> Value {
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

pub fn sample_points(n: usize) -> Vec<Point> {
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

pub fn file_bytes(points: &[Point], meta: &Value) -> Vec<u8> {
    let mut bytes = Vec::new();
    cloud::write(&mut bytes, points, Some(meta)).expect("write to memory");
    bytes
}

/// A valid 10-point song file.
pub fn valid_bytes() -> Vec<u8> {
    file_bytes(&sample_points(10), &song_meta())
}

/// Length of the header, `end_header\n` included.
pub fn header_len(bytes: &[u8]) -> usize {
    let marker = b"end_header\n";
    bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("header has end_header")
        + marker.len()
}

/// A loudscape header with the standard lines replaced: `lines` is the full header text
/// (without the final newline), `{META}` stands for the meta comment.
pub fn header_text(lines: &[&str]) -> String {
    let meta = format!("comment loudscape-meta {}", song_meta());
    let mut text = String::new();
    for line in lines {
        text.push_str(&line.replace("{META}", &meta));
        text.push('\n');
    }
    text
}

pub const STANDARD: [&str; 10] = [
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
pub fn with_header_line(number: usize, line: &str) -> Vec<u8> {
    let mut lines = STANDARD.to_vec();
    lines[number - 1] = line;
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    bytes
}

/// Writes `bytes` as `name`, loads it, and checks that it fails with a one-line message that
/// names the file and contains every one of `needles`.
pub fn expect_error(name: &str, bytes: &[u8], needles: &[&str]) -> CloudError {
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

pub fn set_value(bytes: &mut [u8], point: usize, field: usize, value: f32) {
    let at = header_len(bytes) + point * 20 + field * 4;
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

pub fn in_range(cloud: &PointCloud) -> bool {
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
