//! PLY point-cloud loading.
//!
//! Reads the loudscape point-cloud file (docs/FORMAT.md): a PLY header with the metadata JSON
//! (format version 2: split into `comment loudscape-meta-v2 I/N CHUNK` lines, joined; version 1:
//! one `comment loudscape-meta {JSON}` line) and `element vertex N` of `float x, y, z, scalar, hp`,
//! then N little-endian records of 20 bytes. The header is read line by line (at most
//! [`MAX_HEADER_BYTES`]); the body is read once, straight into a `Vec<Point>` of exactly N
//! allocated up front, and then checked in place: every value finite, positions in [-1, 1],
//! `scalar` and `hp` in [0, 1] (with [`RANGE_EPSILON`] of slack). The body length is checked
//! against the file length before anything is allocated, so a header that declares more points
//! than the file holds fails at once.
//!
//! A PLY without `loudscape-meta` (as MeshLab, Open3D or CloudCompare write: ascii or
//! binary_little_endian, any scalar property types, extra vertex properties and later elements
//! such as faces) opens as a [`DataMode::Generic`] cloud: `x`, `y`, `z` are moved and scaled with
//! one factor (aspect kept) so the bounding box is centered and its longest side spans [-1, 1];
//! `scalar` is 1 and `hp` is 0.5; the axes are labelled `x`, `y`, `z` in the file's units.
//!
//! Every failure is a [`CloudError`] whose message names the file, the place (header line or
//! byte offset, and point index) and the reason, on one line. No input makes the loader panic.
//!
//! Files: this one holds the types ([`PointCloud`], [`Point`], [`CloudMeta`], [`CloudError`]) and
//! the entry points ([`load`], [`load_from_bytes`], [`load_from_reader`]); `header.rs` parses the
//! header, `meta.rs` types the `loudscape-meta` JSON, `body.rs` is the fast path for loudscape
//! bodies (and the checks every body shares), `generic.rs` reads other PLY point clouds and
//! `write.rs` writes loudscape files. A new format version belongs in `meta.rs` (the
//! `format_version` check and any new keys) and, if its records differ, a body reader of its own
//! beside `body.rs`.

use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use serde::Deserialize;
use serde_json::Value;

pub use crate::data::axes::{Axes, Axis, AxisScale, Tick};
pub use write::{META_CHUNK_BYTES, write, write_header, write_header_version, write_points};

mod body;
mod generic;
mod header;
mod meta;
pub use meta::{LoudnessCurves, loudness_curves, one_line};
mod write;

use body::Body;
use header::parse_header;
use meta::{lenient_i32, lenient_u32, parse_meta};

/// One point, as in the file and on the GPU: shaders read the point buffer as `array<f32>` with
/// stride 5 (x, y, z, scalar, hp). Keep in sync with the shaders that read point buffers.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Point {
    /// Normalized position, each coordinate in [-1, 1].
    pub position: [f32; 3],
    /// Normalized scalar (e.g. level), in [0, 1].
    pub scalar: f32,
    /// Harmonic-percussive ratio, in [0, 1] (0 percussive, 1 harmonic).
    pub hp: f32,
}

/// Bytes per point record, in the file and on the GPU.
pub const POINT_BYTES: usize = 20;
const _: () = assert!(std::mem::size_of::<Point>() == POINT_BYTES);
const _: () = assert!(std::mem::align_of::<Point>() == 4);

/// The `format_version`s this build reads (docs/FORMAT.md): 1 (one `loudscape-meta` line) and 2
/// (`loudscape-meta-v2` parts).
pub const FORMAT_VERSIONS: [u64; 2] = [1, 2];
/// The `format_version` [`write`] writes.
pub const FORMAT_VERSION: u64 = 2;
/// The header may not be longer than this (nor, of course, than the file); a file without
/// `end_header` fails after it. The rule (docs/FORMAT.md, "Header size"): the header is held in
/// memory twice while it is parsed (the text, then the JSON values, about 5x the text), so the cap
/// bounds that to well under a GiB while leaving room for ten times the largest library we know
/// of: a 10,000-song timeline has a 5-7 MB header, 64 MiB holds about 90,000 songs. The Python
/// reader's `read_ply_metadata` stops at the same size.
pub const MAX_HEADER_BYTES: u64 = 64 << 20;
/// Slack allowed on the [-1, 1] and [0, 1] ranges, for float rounding in the writer.
pub const RANGE_EPSILON: f32 = 1e-5;
/// The vertex properties of a loudscape file, in order.
pub const PROPERTY_NAMES: [&str; 5] = ["x", "y", "z", "scalar", "hp"];
/// `scalar` of points from a generic PLY.
pub const GENERIC_SCALAR: f32 = 1.0;
/// `hp` of points from a generic PLY.
pub const GENERIC_HP: f32 = 0.5;

const META_KEYWORD: &str = "loudscape-meta";
/// The word of a version-2 metadata part: `comment loudscape-meta-v2 I/N CHUNK`.
const META_V2_KEYWORD: &str = "loudscape-meta-v2";
/// Longest line accepted in an ascii body.
const MAX_ASCII_LINE_BYTES: u64 = 1024 * 1024;
/// Records per read when the body length is unknown or the body is converted (generic files).
const CHUNK_RECORDS: usize = 1 << 16;

/// A loaded point cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCloud {
    /// The file it came from (as given to [`load`]).
    pub path: PathBuf,
    pub points: Vec<Point>,
    pub meta: CloudMeta,
    /// Bounds of the positions (normalized coordinates).
    pub bounds: Aabb,
}

impl PointCloud {
    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// What the extractor found wrong or odd in the input; empty when nothing.
    pub fn warnings(&self) -> &[CloudWarning] {
        &self.meta.warnings
    }

    /// The warnings as the user reads them: `warning: FILE: MESSAGE`, FILE being the song a
    /// timeline's warning concerns, else the cloud's path (for audio: the song's).
    pub fn warning_lines(&self) -> Vec<String> {
        self.warnings()
            .iter()
            .map(|w| {
                let file = w
                    .path
                    .clone()
                    .unwrap_or_else(|| self.path.display().to_string());
                format!("warning: {file}: {}", w.message)
            })
            .collect()
    }

    /// The points as bytes, ready for a GPU buffer (stride [`POINT_BYTES`]).
    pub fn as_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.points)
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The normalized data cube [-1, 1]^3: the bounds of an empty cloud, so a camera framing the
    /// bounds frames the space every loudscape cloud lives in.
    pub const NORMALIZED_CUBE: Aabb = Aabb {
        min: Vec3::NEG_ONE,
        max: Vec3::ONE,
    };

    /// The smallest box holding every position; [`Aabb::NORMALIZED_CUBE`] when there are none.
    pub fn from_points(points: &[Point]) -> Aabb {
        let mut iter = points.iter().map(|p| Vec3::from_array(p.position));
        let Some(first) = iter.next() else {
            return Aabb::NORMALIZED_CUBE;
        };
        let (min, max) = iter.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        Aabb { min, max }
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }
}

/// What kind of data a cloud holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataMode {
    /// One track: every STFT bin a point.
    Song,
    /// Many tracks, sampled frames laid out by release year.
    Timeline,
    /// A PLY from another tool, without loudscape metadata.
    Generic,
}

/// The file's metadata (`comment loudscape-meta`), typed. Unknown keys are kept in `raw` only.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudMeta {
    pub mode: DataMode,
    pub axes: Axes,
    /// `point_count` as written by the extractor (checked against the header when present).
    pub point_count: Option<u64>,
    pub source: Option<Source>,
    pub stft: Option<Stft>,
    pub metrics: Option<Metrics>,
    /// Timeline mode: one entry per song.
    pub songs: Vec<SongInfo>,
    /// What the extractor found wrong or odd in the input (`warnings`; empty when none).
    pub warnings: Vec<CloudWarning>,
    /// The whole JSON object as written (`Value::Null` for generic files).
    pub raw: Value,
}

/// One thing the extractor found wrong or odd in the input (docs/FORMAT.md, "Warnings"): a
/// truncated or corrupt file, a DC offset, channels that cancel, clipping. Every command that
/// uses the cloud says it, as [`PointCloud::warning_lines`] writes it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CloudWarning {
    /// `truncated`, `corrupt`, `dc_offset`, `channels_cancel`, `clipping` or a newer kind.
    pub kind: String,
    /// One line, without the file's name (control characters made spaces).
    pub message: String,
    /// Timeline mode: the song it concerns.
    pub path: Option<String>,
}

/// Song mode: the audio the cloud was made from.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct Source {
    /// The audio's path as text (non-UTF-8 bytes shown as U+FFFD); open [`Source::open_path`].
    pub path: Option<String>,
    /// The exact bytes of `path` when the file records them (`path_bytes_b64`).
    #[serde(skip)]
    pub path_bytes: Option<Vec<u8>>,
    #[serde(deserialize_with = "lenient_u32")]
    pub sample_rate: Option<u32>,
    #[serde(deserialize_with = "lenient_u32")]
    pub channels: Option<u32>,
    pub duration_s: Option<f64>,
    /// The song's title and artist from its tags, when it has them (absent in older files).
    pub title: Option<String>,
    pub artist: Option<String>,
}

/// Song mode: the spectrogram parameters.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct Stft {
    #[serde(deserialize_with = "lenient_u32")]
    pub n_fft: Option<u32>,
    #[serde(deserialize_with = "lenient_u32")]
    pub hop_length: Option<u32>,
    pub window: Option<String>,
}

impl Source {
    /// The audio file to open: the exact bytes of `path` when recorded, else `path`.
    pub fn open_path(&self) -> Option<PathBuf> {
        meta::open_path(self.path.as_deref(), self.path_bytes.as_deref())
    }
}

impl SongInfo {
    /// The song's audio file to open: the exact bytes of `path` when recorded, else `path`.
    pub fn open_path(&self) -> Option<PathBuf> {
        meta::open_path(self.path.as_deref(), self.path_bytes.as_deref())
    }
}

/// Whole-track loudness metrics; `None` where not measurable (e.g. audio shorter than one
/// 400 ms block has no integrated loudness).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct Metrics {
    pub integrated_lufs: Option<f64>,
    pub lra_lu: Option<f64>,
    pub sample_peak_dbfs: Option<f64>,
    pub true_peak_dbtp: Option<f64>,
    pub plr_db: Option<f64>,
    pub crest_median_db: Option<f64>,
    pub crest_p95_db: Option<f64>,
    /// The TT Dynamic Range meter's DR value (docs/FORMAT.md, "Metrics").
    pub dr_db: Option<f64>,
    /// Peak to short-term loudness ratio over 3 s windows: median, 10th and 90th percentiles.
    pub psr_median_db: Option<f64>,
    pub psr_p10_db: Option<f64>,
    pub psr_p90_db: Option<f64>,
    /// Crest factor over the same 3 s windows, median.
    pub crest_3s_median_db: Option<f64>,
    /// Largest channel mean removed before the measures (full scale 1).
    pub dc_offset: Option<f64>,
    /// EBU Tech 3341's maximum momentary (400 ms) and short-term (3 s) loudness, over every
    /// window position, and when a meter shows each (the end of its window, seconds); absent
    /// in files written before them (docs/FORMAT.md, "Metrics").
    pub max_momentary_lufs: Option<f64>,
    pub max_momentary_s: Option<f64>,
    pub max_short_term_lufs: Option<f64>,
    pub max_short_term_s: Option<f64>,
}

/// Timeline mode: one song.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct SongInfo {
    pub title: String,
    pub artist: String,
    #[serde(deserialize_with = "lenient_i32")]
    pub year: Option<i32>,
    /// The song's path as text (non-UTF-8 bytes shown as U+FFFD); open [`SongInfo::open_path`].
    pub path: Option<String>,
    /// The exact bytes of `path` when the file records them (`path_bytes_b64`).
    #[serde(skip)]
    pub path_bytes: Option<Vec<u8>>,
    /// Normalized x range of the song's frames.
    pub x_min: Option<f64>,
    pub x_max: Option<f64>,
    pub metrics: Option<Metrics>,
    /// Every other key, as written.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, Value>,
}

/// Why a file could not be loaded. Each message names the file, the place and the reason.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    #[error("{}: cannot open: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{}: header line {line}: {reason}", path.display())]
    Header {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    #[error("{}: header line {line}: loudscape-meta: {reason}", path.display())]
    Meta {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    #[error(
        "{}: byte {offset}: truncated body: header line {line} declares {count} points \
         ({expected} bytes) but only {available} bytes follow the header",
        path.display()
    )]
    Truncated {
        path: PathBuf,
        /// Where the data ends.
        offset: u64,
        line: usize,
        count: u64,
        expected: u64,
        available: u64,
    },
    #[error(
        "{}: byte {offset}: {extra} trailing bytes after the last of {count} points declared \
         on header line {line}",
        path.display()
    )]
    TrailingBytes {
        path: PathBuf,
        /// Where the unexpected data starts.
        offset: u64,
        extra: u64,
        line: usize,
        count: u64,
    },
    #[error("{}: point {index} at byte {offset}: {reason}", path.display())]
    Point {
        path: PathBuf,
        index: u64,
        offset: u64,
        reason: String,
    },
    #[error("{}: byte {offset}: {reason}", path.display())]
    Body {
        path: PathBuf,
        offset: u64,
        reason: String,
    },
    #[error("{}: cannot allocate memory for {count} points ({bytes} bytes)", path.display())]
    OutOfMemory {
        path: PathBuf,
        count: u64,
        bytes: u64,
    },
}

impl CloudError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            CloudError::Io { path, .. }
            | CloudError::Header { path, .. }
            | CloudError::Meta { path, .. }
            | CloudError::Truncated { path, .. }
            | CloudError::TrailingBytes { path, .. }
            | CloudError::Point { path, .. }
            | CloudError::Body { path, .. }
            | CloudError::OutOfMemory { path, .. } => path,
        }
    }
}

/// Loads a loudscape point cloud, or a generic PLY point cloud, from a file.
pub fn load(path: &Path) -> Result<PointCloud, CloudError> {
    let io_error = |source| CloudError::Io {
        path: path.to_owned(),
        source,
    };
    let file = File::open(path).map_err(io_error)?;
    let metadata = file.metadata().map_err(io_error)?;
    if metadata.is_dir() {
        return Err(io_error(io::Error::other("is a directory")));
    }
    // Pipes and devices report no meaningful length: read them as a stream.
    let len = metadata.is_file().then_some(metadata.len());
    load_from_reader(file, path, len)
}

/// The metadata object `value` read as a file's `loudscape-meta` would be (the same checks);
/// `path` names it in errors. For clouds made in memory, such as the points of a song shown
/// while it is extracted (`crate::extract::preview`).
pub fn meta_from_value(value: &Value, path: &Path) -> Result<CloudMeta, CloudError> {
    parse_meta(&value.to_string(), 0, path)
}

/// Loads from bytes in memory; `path` is only used in messages and [`PointCloud::path`].
pub fn load_from_bytes(bytes: &[u8], path: &Path) -> Result<PointCloud, CloudError> {
    load_from_reader(bytes, path, Some(bytes.len() as u64))
}

/// Loads from any reader. `len` is the total length in bytes when known: it lets a wrong point
/// count fail before anything is allocated and read. Without it, the body is read in chunks and
/// the count is checked as the data arrives. `path` is only used in messages.
pub fn load_from_reader<R: Read>(
    reader: R,
    path: &Path,
    len: Option<u64>,
) -> Result<PointCloud, CloudError> {
    let mut reader = BufReader::with_capacity(64 * 1024, reader);
    let mut header = parse_header(&mut reader, path)?;
    let remaining = len.map(|len| len.saturating_sub(header.byte_len));
    // The JSON text goes as soon as it is parsed: only its values are kept.
    let meta = match header.meta.as_mut() {
        Some((line, json)) => {
            let json = std::mem::take(json);
            Some(parse_meta(&json, *line, path)?)
        }
        None => None,
    };
    let mut body = Body {
        reader,
        path,
        header: &header,
        remaining,
    };
    let (points, meta) = match meta {
        Some(meta) => {
            let points = body.read_loudscape(&meta)?;
            (points, meta)
        }
        None => body.read_generic()?,
    };
    Ok(PointCloud {
        path: path.to_owned(),
        bounds: Aabb::from_points(&points),
        points,
        meta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta() -> Value {
        serde_json::json!({
            "format_version": 1,
            "mode": "song",
            "axes": {
                "x": {"label": "time", "unit": "s", "min": 0.0, "max": 10.0, "scale": "linear"},
                "y": {"label": "frequency", "unit": "Hz", "min": 20.0, "max": 20000.0, "scale": "log"},
                "z": {"label": "level", "unit": "dB", "min": -60.0, "max": 0.0},
                "scalar": {"label": "level", "unit": "dB", "min": -60.0, "max": 0.0},
                "hp": {"label": "hp", "unit": "", "min": 0.0, "max": 1.0}
            },
            "source": {"path": "s\u{e9}ance.wav", "sample_rate": 44100, "channels": 2, "duration_s": 10.0},
            "metrics": {"integrated_lufs": -14.2, "lra_lu": null}
        })
    }

    #[test]
    fn the_window_maxima_parse_and_older_files_lack_them() {
        let metrics: Metrics = serde_json::from_value(serde_json::json!({
            "integrated_lufs": -14.0,
            "max_momentary_lufs": -9.25,
            "max_momentary_s": 61.43,
            "max_short_term_lufs": -11.5,
            "max_short_term_s": null
        }))
        .expect("metrics parse");
        assert_eq!(metrics.max_momentary_lufs, Some(-9.25));
        assert_eq!(metrics.max_momentary_s, Some(61.43));
        assert_eq!(metrics.max_short_term_lufs, Some(-11.5));
        assert_eq!(metrics.max_short_term_s, None);
        let older: Metrics = serde_json::from_value(meta()["metrics"].clone()).expect("parse");
        assert_eq!(
            (older.max_momentary_lufs, older.max_short_term_s),
            (None, None)
        );
    }

    #[test]
    fn point_layout() {
        let p = Point {
            position: [1.0, 2.0, 3.0],
            scalar: 4.0,
            hp: 5.0,
        };
        let floats: &[f32] = bytemuck::cast_slice(std::slice::from_ref(&p));
        assert_eq!(floats, [1.0, 2.0, 3.0, 4.0, 5.0]);
    }

    #[test]
    fn round_trip_in_memory() {
        let points: Vec<Point> = (0..100)
            .map(|i| {
                let t = i as f32 / 99.0;
                Point {
                    position: [t * 2.0 - 1.0, 0.5, -t],
                    scalar: t,
                    hp: 1.0 - t,
                }
            })
            .collect();
        let mut bytes = Vec::new();
        write(&mut bytes, &points, Some(&meta())).expect("write to memory");
        assert!(bytes.is_ascii() || bytes.len() > 100);
        let cloud = load_from_bytes(&bytes, Path::new("song.ply")).expect("loads");
        assert_eq!(cloud.points, points);
        assert_eq!(cloud.meta.mode, DataMode::Song);
        assert_eq!(cloud.meta.axes.y.scale, AxisScale::Log);
        let source = cloud.meta.source.as_ref().expect("source");
        assert_eq!(source.path.as_deref(), Some("s\u{e9}ance.wav"));
        assert_eq!(source.sample_rate, Some(44100));
        let metrics = cloud.meta.metrics.as_ref().expect("metrics");
        assert_eq!(metrics.integrated_lufs, Some(-14.2));
        assert_eq!(metrics.lra_lu, None);
        assert_eq!(cloud.bounds.min, Vec3::new(-1.0, 0.5, -1.0));
        assert_eq!(cloud.bounds.max, Vec3::new(1.0, 0.5, 0.0));
        // The same bytes through a stream of unknown length.
        let streamed =
            load_from_reader(bytes.as_slice(), Path::new("song.ply"), None).expect("loads");
        assert_eq!(streamed.points, points);
    }

    #[test]
    fn empty_cloud_bounds() {
        assert_eq!(Aabb::from_points(&[]), Aabb::NORMALIZED_CUBE);
        assert_eq!(Aabb::NORMALIZED_CUBE.center(), Vec3::ZERO);
        assert_eq!(Aabb::NORMALIZED_CUBE.size(), Vec3::splat(2.0));
    }

    #[test]
    fn streamed_truncation_and_trailing() {
        let points = vec![Point::zeroed(); 10];
        let mut bytes = Vec::new();
        write(&mut bytes, &points, Some(&meta())).expect("write");
        let cut = &bytes[..bytes.len() - 7];
        let err = load_from_reader(cut, Path::new("a.ply"), None).expect_err("truncated");
        assert!(
            matches!(err, CloudError::Truncated { available: 193, .. }),
            "{err}"
        );
        let mut long = bytes.clone();
        long.extend_from_slice(b"abc");
        let err =
            load_from_reader(long.as_slice(), Path::new("a.ply"), None).expect_err("trailing");
        assert!(
            matches!(err, CloudError::TrailingBytes { extra: 3, .. }),
            "{err}"
        );
    }
}
