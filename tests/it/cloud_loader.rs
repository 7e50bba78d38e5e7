//! The PLY loader against valid and generic files, damaged bytes, and the extractor's fixture;
//! malformed headers, one test per case, are in tests/it/cloud_loader_malformed.rs.
//! [`check_against_expected`] compares a loaded file with an expected-values JSON written by the
//! Python side (point count, first and last records, per-column sums).

use std::path::Path;

use loudscape::data::cloud::{self, DataMode};
use serde_json::{Value, json};

use crate::loader_files::*;

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
