//! The body file read as it grows: whole rows only, a row cut in two read when its end comes,
//! a removed file, bad values; and the preview's clouds (axes, throttling, giving up).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::*;
use crate::data::cloud::DataMode;

/// A fresh folder under the system's temporary folder for test `name`.
fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loudscape-preview-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn point(i: usize) -> Point {
    let t = (i % 1000) as f32 / 1000.0;
    Point {
        position: [t * 2.0 - 1.0, -t, 0.5 - t * 0.5],
        scalar: t,
        hp: 1.0 - t,
    }
}

/// The rows of points `from..to` as the extractor writes them (float32 little-endian).
fn rows(from: usize, to: usize) -> Vec<u8> {
    (from..to)
        .flat_map(|i| {
            let p = point(i);
            [p.position[0], p.position[1], p.position[2], p.scalar, p.hp]
        })
        .flat_map(f32::to_le_bytes)
        .collect()
}

fn append(path: &Path, bytes: &[u8]) {
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .unwrap();
    file.write_all(bytes).unwrap();
    file.flush().unwrap();
}

fn expected(from: usize, to: usize) -> Vec<Point> {
    (from..to).map(point).collect()
}

#[test]
fn a_growing_file_is_read_a_piece_at_a_time() {
    let dir = dir("growing");
    let body = dir.join(".cloud.ply.points-1");
    let mut reader = BodyReader::new(&body);
    let mut points = Vec::new();
    append(&body, &rows(0, 100));
    assert_eq!(reader.read_up_to(100, &mut points).unwrap(), 100);
    // The same count again reads nothing; a smaller one too.
    assert_eq!(reader.read_up_to(100, &mut points).unwrap(), 0);
    assert_eq!(reader.read_up_to(50, &mut points).unwrap(), 0);
    append(&body, &rows(100, 250));
    assert_eq!(reader.read_up_to(250, &mut points).unwrap(), 150);
    assert_eq!(points, expected(0, 250));
    assert_eq!(reader.rows(), 250);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn rows_beyond_the_count_wait_for_their_line() {
    let dir = dir("beyond");
    let body = dir.join(".cloud.ply.points-2");
    // The next block is being written while the line for the first one is read.
    append(&body, &rows(0, 30));
    let mut reader = BodyReader::new(&body);
    let mut points = Vec::new();
    assert_eq!(reader.read_up_to(10, &mut points).unwrap(), 10);
    assert_eq!(points, expected(0, 10));
    assert_eq!(reader.read_up_to(30, &mut points).unwrap(), 20);
    assert_eq!(points, expected(0, 30));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_row_cut_in_two_is_read_when_its_end_comes() {
    let dir = dir("cut");
    let body = dir.join(".cloud.ply.points-3");
    let all = rows(0, 10);
    // The line says 10 rows but the file holds 7 and a half (a reader faster than the disk).
    append(&body, &all[..7 * POINT_BYTES + 9]);
    let mut reader = BodyReader::new(&body);
    let mut points = Vec::new();
    assert_eq!(reader.read_up_to(10, &mut points).unwrap(), 7);
    assert_eq!(points, expected(0, 7));
    append(&body, &all[7 * POINT_BYTES + 9..]);
    assert_eq!(reader.read_up_to(10, &mut points).unwrap(), 3);
    assert_eq!(points, expected(0, 10));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_removed_file_gives_no_rows_and_no_error() {
    let dir = dir("removed");
    let body = dir.join(".cloud.ply.points-4");
    let mut points = Vec::new();
    // Never there (or removed before the first read): the line is ignored.
    let mut reader = BodyReader::new(&body);
    assert_eq!(reader.read_up_to(5, &mut points).unwrap(), 0);
    // Removed once open: what was written is still read (Unix keeps the open file).
    append(&body, &rows(0, 5));
    assert_eq!(reader.read_up_to(2, &mut points).unwrap(), 2);
    std::fs::remove_file(&body).unwrap();
    let more = reader.read_up_to(5, &mut points).unwrap();
    assert!(more == 3 || cfg!(windows), "{more}");
    assert_eq!(reader.read_up_to(9, &mut points).unwrap(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_value_out_of_range_is_an_error_naming_the_row() {
    let dir = dir("bad");
    let body = dir.join(".cloud.ply.points-5");
    let mut bytes = rows(0, 4);
    bytes[3 * POINT_BYTES..3 * POINT_BYTES + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    append(&body, &bytes);
    let mut reader = BodyReader::new(&body);
    let mut points = Vec::new();
    let err = reader.read_up_to(4, &mut points).unwrap_err();
    assert!(err.to_string().contains("row 3"), "{err}");
    assert!(points.is_empty(), "no row of a bad read is kept");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn axes() -> serde_json::Value {
    serde_json::json!({
        "x": {"label": "time", "unit": "s", "min": 0.0, "max": 180.0, "scale": "linear"},
        "y": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0, "scale": "linear"},
        "z": {"label": "frequency", "unit": "Hz", "min": 0.0, "max": 22050.0, "scale": "linear"},
        "scalar": {"label": "A-weighted level", "unit": "dB", "min": -90.0, "max": 0.0},
        "hp": {"label": "harmonic-percussive ratio", "unit": "", "min": 0.0, "max": 1.0}
    })
}

fn line(path: &Path, rows: u64) -> PointsSoFar {
    PointsSoFar {
        path: path.to_owned(),
        rows,
        axes: axes(),
        freq_scale: "linear".into(),
    }
}

#[test]
fn the_preview_is_a_song_cloud_with_the_final_axes_handed_on_throttled() {
    let dir = dir("clouds");
    let body = dir.join(".cloud.ply.points-6");
    let audio = Path::new("/music/song.flac");
    let mut preview = Preview::new(audio, &Settings::default());
    let start = Instant::now();
    append(&body, &rows(0, 1000));
    let first = preview
        .hear(&line(&body, 1000), start)
        .unwrap()
        .expect("the first rows are shown at once");
    assert_eq!(first.path, audio);
    assert_eq!(first.points, expected(0, 1000));
    assert_eq!(first.meta.mode, DataMode::Song);
    assert_eq!(first.meta.axes.x.max, 180.0);
    assert_eq!(first.meta.axes.z.max, 22050.0);
    // What the frequency axis needs: the sample rate (from Nyquist) and the FFT size.
    let source = first.meta.source.as_ref().unwrap();
    assert_eq!(source.sample_rate, Some(44100));
    assert_eq!(source.path.as_deref(), Some("/music/song.flac"));
    assert_eq!(first.meta.stft.as_ref().unwrap().n_fft, Some(2048));
    assert!(crate::data::freq_axis::unsupported(&first.meta).is_none());
    // A line soon after: read, not handed on yet.
    append(&body, &rows(1000, 3000));
    let soon = start + Duration::from_millis(100);
    assert!(preview.hear(&line(&body, 3000), soon).unwrap().is_none());
    assert_eq!(preview.rows(), 3000);
    // Once the interval passed, all the rows read so far.
    let later = start + Preview::interval(1000);
    let second = preview.hear(&line(&body, 3000), later).unwrap().unwrap();
    assert_eq!(second.points, expected(0, 3000));
    // Nothing new: nothing handed on, however long after.
    let much_later = later + Duration::from_secs(5);
    assert!(
        preview
            .hear(&line(&body, 3000), much_later)
            .unwrap()
            .is_none()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn large_clouds_are_handed_on_less_often() {
    assert_eq!(Preview::interval(1000), Duration::from_millis(250));
    assert!(Preview::interval(5_000_000) > Duration::from_secs(1));
    assert!(Preview::interval(5_000_000) < Duration::from_secs(2));
}

#[test]
fn a_failed_read_gives_up_the_preview_once() {
    let dir = dir("gives-up");
    let body = dir.join(".cloud.ply.points-7");
    let mut bytes = rows(0, 10);
    bytes[0..4].copy_from_slice(&7.0f32.to_le_bytes());
    append(&body, &bytes);
    let mut preview = Preview::new(Path::new("/music/song.flac"), &Settings::default());
    let now = Instant::now();
    let err = preview.hear(&line(&body, 10), now).unwrap_err();
    assert!(
        err.contains(".cloud.ply.points-7") && err.contains("row 0"),
        "{err}"
    );
    assert_eq!(preview.failed(), Some(err.as_str()));
    // Later lines are ignored, without another error.
    assert!(preview.hear(&line(&body, 10), now).unwrap().is_none());
    // Axes a cloud cannot have give it up too.
    let mut bad = line(&body, 10);
    bad.axes = serde_json::json!({"x": {}});
    let mut preview = Preview::new(Path::new("/music/song.flac"), &Settings::default());
    let err = preview.hear(&bad, now).unwrap_err();
    assert!(err.contains("axes"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
