//! PLY point-cloud loading.
//!
//! Reads the loudscape point-cloud file (docs/FORMAT.md): a PLY header with one
//! `comment loudscape-meta {JSON}` line and `element vertex N` of `float x, y, z, scalar, hp`,
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

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use serde::{Deserialize, Deserializer};
use serde_json::Value;

pub use crate::axes::{Axes, Axis, AxisScale, Tick};

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

/// The `format_version` this build reads.
pub const FORMAT_VERSION: u64 = 1;
/// The header may not be longer than this; a file without `end_header` fails after it.
pub const MAX_HEADER_BYTES: u64 = 64 * 1024;
/// Slack allowed on the [-1, 1] and [0, 1] ranges, for float rounding in the writer.
pub const RANGE_EPSILON: f32 = 1e-5;
/// The vertex properties of a loudscape file, in order.
pub const PROPERTY_NAMES: [&str; 5] = ["x", "y", "z", "scalar", "hp"];
/// `scalar` of points from a generic PLY.
pub const GENERIC_SCALAR: f32 = 1.0;
/// `hp` of points from a generic PLY.
pub const GENERIC_HP: f32 = 0.5;

const META_KEYWORD: &str = "loudscape-meta";
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

    /// Half the edge lengths.
    pub fn half_size(&self) -> Vec3 {
        self.size() * 0.5
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
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
    /// The whole JSON object as written (`Value::Null` for generic files).
    pub raw: Value,
}

/// Song mode: the audio the cloud was made from.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct Source {
    pub path: Option<String>,
    #[serde(deserialize_with = "lenient_u32")]
    pub sample_rate: Option<u32>,
    #[serde(deserialize_with = "lenient_u32")]
    pub channels: Option<u32>,
    pub duration_s: Option<f64>,
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
}

/// Timeline mode: one song.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub struct SongInfo {
    pub title: String,
    pub artist: String,
    #[serde(deserialize_with = "lenient_i32")]
    pub year: Option<i32>,
    pub path: Option<String>,
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
    let header = parse_header(&mut reader, path)?;
    let remaining = len.map(|len| len.saturating_sub(header.byte_len));
    let mut body = Body {
        reader,
        path,
        header: &header,
        remaining,
    };
    let (points, meta) = match &header.meta {
        Some((line, json)) => {
            let meta = parse_meta(json, *line, path)?;
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

// ---------------------------------------------------------------------------------------------
// Header

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

impl Encoding {
    fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    fn parse(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// Reads a little-endian value from the front of `bytes` (which holds at least `size()`).
    fn read_le(self, bytes: &[u8]) -> Option<f64> {
        fn take<const N: usize>(bytes: &[u8]) -> Option<[u8; N]> {
            bytes.get(..N)?.try_into().ok()
        }
        Some(match self {
            ScalarType::I8 => f64::from(i8::from_le_bytes(take(bytes)?)),
            ScalarType::U8 => f64::from(u8::from_le_bytes(take(bytes)?)),
            ScalarType::I16 => f64::from(i16::from_le_bytes(take(bytes)?)),
            ScalarType::U16 => f64::from(u16::from_le_bytes(take(bytes)?)),
            ScalarType::I32 => f64::from(i32::from_le_bytes(take(bytes)?)),
            ScalarType::U32 => f64::from(u32::from_le_bytes(take(bytes)?)),
            ScalarType::F32 => f64::from(f32::from_le_bytes(take(bytes)?)),
            ScalarType::F64 => f64::from_le_bytes(take(bytes)?),
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PropertyKind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: PropertyKind,
    /// The property's text, for messages.
    text: String,
    line: usize,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    line: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Debug)]
struct Header {
    encoding: Encoding,
    format_line: usize,
    /// Line and JSON text of `comment loudscape-meta`.
    meta: Option<(usize, String)>,
    elements: Vec<Element>,
    end_line: usize,
    /// Bytes up to and including the `end_header` line.
    byte_len: u64,
}

/// A short, printable excerpt of header bytes for messages.
fn excerpt(bytes: &[u8]) -> String {
    let text: String = String::from_utf8_lossy(&bytes[..bytes.len().min(40)])
        .chars()
        .flat_map(char::escape_debug)
        .collect();
    if bytes.len() > 40 {
        format!("`{text}...`")
    } else {
        format!("`{text}`")
    }
}

fn parse_header<R: BufRead>(reader: &mut R, path: &Path) -> Result<Header, CloudError> {
    let error = |line: usize, reason: String| CloudError::Header {
        path: path.to_owned(),
        line,
        reason,
    };
    let mut consumed: u64 = 0;
    let mut line_no = 0;
    let mut buf = Vec::new();
    let mut format: Option<(Encoding, usize)> = None;
    let mut meta: Option<(usize, String)> = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line_no += 1;
        buf.clear();
        let n = reader
            .by_ref()
            .take(MAX_HEADER_BYTES - consumed)
            .read_until(b'\n', &mut buf)
            .map_err(|e| error(line_no, format!("cannot read the header: {e}")))?;
        consumed += n as u64;
        let complete = buf.last() == Some(&b'\n');
        if complete {
            buf.pop();
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        if line_no == 1 {
            if n == 0 {
                return Err(error(1, "the file is empty (expected a PLY header)".into()));
            }
            if buf.as_slice() != b"ply" {
                return Err(error(
                    1,
                    format!("not a PLY file: expected `ply`, found {}", excerpt(&buf)),
                ));
            }
        }
        let text = std::str::from_utf8(&buf).map_err(|e| {
            error(
                line_no,
                format!(
                    "not valid UTF-8 at column {} (PLY headers are ASCII text)",
                    e.valid_up_to() + 1
                ),
            )
        })?;
        let (keyword, rest) = match text.trim().split_once(char::is_whitespace) {
            Some((keyword, rest)) => (keyword, rest.trim()),
            None => (text.trim(), ""),
        };
        let tokens: Vec<&str> = rest.split_whitespace().collect();
        if !complete && keyword != "end_header" {
            return Err(if consumed >= MAX_HEADER_BYTES {
                error(
                    line_no,
                    format!(
                        "the header is longer than {} KiB without `end_header`",
                        MAX_HEADER_BYTES / 1024
                    ),
                )
            } else {
                error(line_no, "the file ends before `end_header`".into())
            });
        }
        match keyword {
            "ply" if line_no == 1 => {}
            "format" => {
                if let Some((_, first)) = format {
                    return Err(error(
                        line_no,
                        format!("second `format` line (the first is line {first})"),
                    ));
                }
                let encoding = match tokens.first() {
                    Some(&"ascii") => Encoding::Ascii,
                    Some(&"binary_little_endian") => Encoding::BinaryLittleEndian,
                    Some(&"binary_big_endian") => Encoding::BinaryBigEndian,
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "unknown format {}: expected `format binary_little_endian 1.0`, \
                                 `format ascii 1.0` or `format binary_big_endian 1.0`",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                if tokens.len() != 2 || !matches!(tokens[1], "1.0" | "1") {
                    return Err(error(
                        line_no,
                        format!(
                            "expected `format {} 1.0`, found {}",
                            encoding.name(),
                            excerpt(text.as_bytes())
                        ),
                    ));
                }
                format = Some((encoding, line_no));
            }
            "comment" => {
                let is_meta = rest == META_KEYWORD
                    || rest
                        .strip_prefix(META_KEYWORD)
                        .is_some_and(|after| after.starts_with(char::is_whitespace));
                if is_meta {
                    if let Some((first, _)) = meta {
                        return Err(CloudError::Meta {
                            path: path.to_owned(),
                            line: line_no,
                            reason: format!(
                                "second loudscape-meta comment (the first is line {first})"
                            ),
                        });
                    }
                    meta = Some((line_no, rest[META_KEYWORD.len()..].trim().to_owned()));
                }
            }
            "obj_info" | "" => {}
            "element" => {
                let (name, count) = match tokens.as_slice() {
                    [name, count] => (*name, *count),
                    [name] => {
                        return Err(error(
                            line_no,
                            format!("`element {name}` has no count, e.g. `element {name} 1000`"),
                        ));
                    }
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "expected `element NAME COUNT`, found {}",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                let count: u64 = count.parse().map_err(|_| {
                    error(
                        line_no,
                        format!(
                            "element count {} is not a whole number of at most {}",
                            excerpt(count.as_bytes()),
                            u64::MAX
                        ),
                    )
                })?;
                if let Some(previous) = elements.iter().find(|e| e.name == name) {
                    return Err(error(
                        line_no,
                        format!(
                            "second `element {name}` (the first is line {})",
                            previous.line
                        ),
                    ));
                }
                elements.push(Element {
                    name: name.to_owned(),
                    count,
                    line: line_no,
                    properties: Vec::new(),
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(error(line_no, "`property` before any `element`".into()));
                };
                let scalar = |name: &str| {
                    ScalarType::parse(name).ok_or_else(|| {
                        error(
                            line_no,
                            format!("unknown property type {}", excerpt(name.as_bytes())),
                        )
                    })
                };
                let (kind, name) = match tokens.as_slice() {
                    ["list", count, item, name] => (
                        PropertyKind::List {
                            count: scalar(count)?,
                            item: scalar(item)?,
                        },
                        *name,
                    ),
                    [kind, name] if *kind != "list" => (PropertyKind::Scalar(scalar(kind)?), *name),
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "expected `property TYPE NAME` or `property list COUNT_TYPE \
                                 ITEM_TYPE NAME`, found {}",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                if let Some(previous) = element.properties.iter().find(|p| p.name == name) {
                    return Err(error(
                        line_no,
                        format!(
                            "second property `{name}` in `element {}` (the first is line {})",
                            element.name, previous.line
                        ),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_owned(),
                    kind,
                    text: text.trim().to_owned(),
                    line: line_no,
                });
            }
            "end_header" => {
                if !tokens.is_empty() {
                    return Err(error(
                        line_no,
                        format!(
                            "unexpected text after `end_header`: {}",
                            excerpt(rest.as_bytes())
                        ),
                    ));
                }
                let Some((encoding, format_line)) = format else {
                    return Err(error(
                        line_no,
                        "no `format` line before `end_header` (expected `format \
                         binary_little_endian 1.0` on line 2)"
                            .into(),
                    ));
                };
                return Ok(Header {
                    encoding,
                    format_line,
                    meta,
                    elements,
                    end_line: line_no,
                    byte_len: consumed,
                });
            }
            other => {
                return Err(error(
                    line_no,
                    format!("unknown header keyword {}", excerpt(other.as_bytes())),
                ));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Metadata

fn lenient_u32<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<u32>, D::Error> {
    lenient_integer(deserializer)
}

fn lenient_i32<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<i32>, D::Error> {
    lenient_integer(deserializer)
}

/// A whole number that may be written as `44100` or `44100.0`; `null` is None.
fn lenient_integer<'de, D, T>(deserializer: D) -> Result<Option<T>, D::Error>
where
    D: Deserializer<'de>,
    T: TryFrom<i64>,
{
    use serde::de::Error;
    let value = Option::<f64>::deserialize(deserializer)?;
    match value {
        None => Ok(None),
        Some(v) if v.fract() == 0.0 && v.abs() < 1e15 => T::try_from(v as i64)
            .map(Some)
            .map_err(|_| D::Error::custom(format!("{v} is out of range"))),
        Some(v) => Err(D::Error::custom(format!(
            "expected a whole number, found {v}"
        ))),
    }
}

fn parse_meta(json: &str, line: usize, path: &Path) -> Result<CloudMeta, CloudError> {
    let error = |reason: String| CloudError::Meta {
        path: path.to_owned(),
        line,
        reason,
    };
    let raw: Value = serde_json::from_str(json).map_err(|e| error(format!("invalid JSON: {e}")))?;
    let Some(object) = raw.as_object() else {
        return Err(error("expected a JSON object `{...}`".into()));
    };
    match object.get("format_version") {
        None => return Err(error("missing `format_version`".into())),
        Some(v) if v.as_u64() == Some(FORMAT_VERSION) => {}
        Some(v) => {
            return Err(error(format!(
                "format_version {v} is not supported (this build reads format_version \
                 {FORMAT_VERSION})"
            )));
        }
    }
    let mode = match object.get("mode") {
        None => return Err(error("missing `mode`".into())),
        Some(Value::String(s)) if s == "song" => DataMode::Song,
        Some(Value::String(s)) if s == "timeline" => DataMode::Timeline,
        Some(v) => {
            return Err(error(format!(
                "`mode` must be \"song\" or \"timeline\", found {v}"
            )));
        }
    };
    let Some(axes_value) = object.get("axes") else {
        return Err(error("missing `axes`".into()));
    };
    let Some(axes_object) = axes_value.as_object() else {
        return Err(error(format!(
            "`axes` must be an object, found {axes_value}"
        )));
    };
    let axis = |name: &str| -> Result<Axis, CloudError> {
        let value = axes_object
            .get(name)
            .ok_or_else(|| error(format!("`axes` has no `{name}` axis")))?;
        let axis: Axis = serde_json::from_value(value.clone())
            .map_err(|e| error(format!("`axes.{name}`: {e}")))?;
        if let Some(problem) = axis.problem() {
            return Err(error(format!("`axes.{name}`: {problem}")));
        }
        Ok(axis)
    };
    let axes = Axes {
        x: axis("x")?,
        y: axis("y")?,
        z: axis("z")?,
        scalar: axis("scalar")?,
        hp: axis("hp")?,
    };
    let point_count = match object.get("point_count") {
        None | Some(Value::Null) => None,
        Some(v) => Some(
            v.as_u64()
                .ok_or_else(|| error(format!("`point_count` must be a whole number, found {v}")))?,
        ),
    };
    fn optional<T: serde::de::DeserializeOwned>(
        object: &serde_json::Map<String, Value>,
        key: &str,
    ) -> Result<Option<T>, String> {
        match object.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => serde_json::from_value(v.clone())
                .map(Some)
                .map_err(|e| format!("`{key}`: {e}")),
        }
    }
    let source = optional::<Source>(object, "source").map_err(error)?;
    let stft = optional::<Stft>(object, "stft").map_err(error)?;
    let metrics = optional::<Metrics>(object, "metrics").map_err(error)?;
    let songs = match object.get("songs") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                serde_json::from_value::<SongInfo>(item.clone())
                    .map_err(|e| error(format!("`songs[{i}]`: {e}")))
            })
            .collect::<Result<_, _>>()?,
        Some(v) => return Err(error(format!("`songs` must be an array, found {v}"))),
    };
    Ok(CloudMeta {
        mode,
        axes,
        point_count,
        source,
        stft,
        metrics,
        songs,
        raw,
    })
}

// ---------------------------------------------------------------------------------------------
// Body

struct Body<'a, R> {
    reader: BufReader<R>,
    path: &'a Path,
    header: &'a Header,
    /// Bytes after the header, when the total length is known.
    remaining: Option<u64>,
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_full<R: Read>(reader: &mut R, buf: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match reader.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

fn check_value(name: &str, value: f32, lo: f32, hi: f32) -> Result<(), String> {
    if value.is_nan() {
        Err(format!("{name} is NaN"))
    } else if value.is_infinite() {
        Err(format!(
            "{name} is {}inf",
            if value > 0.0 { "+" } else { "-" }
        ))
    } else if value < lo - RANGE_EPSILON || value > hi + RANGE_EPSILON {
        Err(format!("{name} = {value} is outside [{lo}, {hi}]"))
    } else {
        Ok(())
    }
}

impl<R: Read> Body<'_, R> {
    fn header_error(&self, line: usize, reason: String) -> CloudError {
        CloudError::Header {
            path: self.path.to_owned(),
            line,
            reason,
        }
    }

    fn body_error(&self, offset: u64, reason: String) -> CloudError {
        CloudError::Body {
            path: self.path.to_owned(),
            offset,
            reason,
        }
    }

    fn out_of_memory(&self, count: u64, record_bytes: u64) -> CloudError {
        CloudError::OutOfMemory {
            path: self.path.to_owned(),
            count,
            bytes: count.saturating_mul(record_bytes),
        }
    }

    /// Fails unless `count` records of `record_bytes` fit in what follows the header.
    fn check_body_fits(&self, element: &Element, record_bytes: u64) -> Result<u64, CloudError> {
        let expected = element.count.checked_mul(record_bytes).ok_or_else(|| {
            self.header_error(
                element.line,
                format!(
                    "`element {} {}` is too large: {} records of {record_bytes} bytes overflow",
                    element.name, element.count, element.count
                ),
            )
        })?;
        match self.remaining {
            Some(available) if available < expected => Err(CloudError::Truncated {
                path: self.path.to_owned(),
                offset: self.header.byte_len + available,
                line: element.line,
                count: element.count,
                expected,
                available,
            }),
            _ => Ok(expected),
        }
    }

    fn vertex_count_as_usize(&self, element: &Element) -> Result<usize, CloudError> {
        usize::try_from(element.count).map_err(|_| {
            self.header_error(
                element.line,
                format!(
                    "{} points do not fit in this machine's memory",
                    element.count
                ),
            )
        })
    }

    fn read_loudscape(&mut self, meta: &CloudMeta) -> Result<Vec<Point>, CloudError> {
        let header = self.header;
        if header.encoding != Encoding::BinaryLittleEndian {
            return Err(self.header_error(
                header.format_line,
                format!(
                    "a loudscape file (it has `comment {META_KEYWORD}`) must be `format \
                     binary_little_endian 1.0`, found `format {} 1.0`",
                    header.encoding.name()
                ),
            ));
        }
        let Some(vertex) = header.elements.first() else {
            return Err(self.header_error(
                header.end_line,
                "no `element vertex N` before `end_header`".into(),
            ));
        };
        if vertex.name != "vertex" {
            return Err(self.header_error(
                vertex.line,
                format!(
                    "expected `element vertex N`, found `element {} {}`",
                    vertex.name, vertex.count
                ),
            ));
        }
        if let Some(extra) = header.elements.get(1) {
            return Err(self.header_error(
                extra.line,
                format!(
                    "unexpected `element {}`: a loudscape file holds only `element vertex`",
                    extra.name
                ),
            ));
        }
        for (i, expected) in PROPERTY_NAMES.iter().enumerate() {
            let Some(property) = vertex.properties.get(i) else {
                let line = vertex
                    .properties
                    .last()
                    .map_or(vertex.line, |p| p.line)
                    .saturating_add(1);
                return Err(self.header_error(
                    line,
                    format!(
                        "missing `property float {expected}`: a loudscape vertex has exactly \
                         float x, y, z, scalar, hp (found {} properties)",
                        vertex.properties.len()
                    ),
                ));
            };
            if property.name != *expected || property.kind != PropertyKind::Scalar(ScalarType::F32)
            {
                return Err(self.header_error(
                    property.line,
                    format!(
                        "expected `property float {expected}`, found `{}` (a loudscape vertex \
                         has exactly float x, y, z, scalar, hp in this order)",
                        property.text
                    ),
                ));
            }
        }
        if let Some(extra) = vertex.properties.get(PROPERTY_NAMES.len()) {
            return Err(self.header_error(
                extra.line,
                format!(
                    "unexpected `{}`: a loudscape vertex has exactly float x, y, z, scalar, hp",
                    extra.text
                ),
            ));
        }
        if let Some(declared) = meta.point_count.filter(|&d| d != vertex.count) {
            let (line, _) = header
                .meta
                .as_ref()
                .map_or((0, ""), |(l, j)| (*l, j.as_str()));
            return Err(CloudError::Meta {
                path: self.path.to_owned(),
                line,
                reason: format!(
                    "point_count {declared} does not match `element vertex {}` on header line {}",
                    vertex.count, vertex.line
                ),
            });
        }

        let expected = self.check_body_fits(vertex, POINT_BYTES as u64)?;
        if let Some(available) = self.remaining.filter(|&a| a > expected) {
            return Err(CloudError::TrailingBytes {
                path: self.path.to_owned(),
                offset: header.byte_len + expected,
                extra: available - expected,
                line: vertex.line,
                count: vertex.count,
            });
        }
        let count = self.vertex_count_as_usize(vertex)?;

        // Exactly N, read in place, when the length is known (checked above); in growing chunks
        // otherwise, so a huge count on a short stream fails when the data runs out, not when
        // allocating.
        let mut points: Vec<Point> = Vec::new();
        let mut start = 0usize;
        while start < count {
            // Grow geometrically for streams of unknown length.
            let chunk = if self.remaining.is_some() {
                count - start
            } else {
                (count - start).min(start.max(CHUNK_RECORDS))
            };
            points
                .try_reserve_exact(chunk)
                .map_err(|_| self.out_of_memory(vertex.count, POINT_BYTES as u64))?;
            points.resize(start + chunk, Point::zeroed());
            let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut points[start..]);
            let read_at = header.byte_len + (start * POINT_BYTES) as u64;
            let got = read_full(&mut self.reader, bytes)
                .map_err(|e| self.body_error(read_at, format!("cannot read point data: {e}")))?;
            if got < bytes.len() {
                let available = (start * POINT_BYTES + got) as u64;
                return Err(CloudError::Truncated {
                    path: self.path.to_owned(),
                    offset: header.byte_len + available,
                    line: vertex.line,
                    count: vertex.count,
                    expected,
                    available,
                });
            }
            start += chunk;
        }
        // The file may have grown since its length was read, or the length was unknown.
        let mut probe = [0u8; 1];
        let extra = read_full(&mut self.reader, &mut probe).map_err(|e| {
            self.body_error(header.byte_len + expected, format!("cannot read: {e}"))
        })?;
        if extra > 0 {
            let rest = io::copy(&mut self.reader, &mut io::sink()).unwrap_or(0);
            return Err(CloudError::TrailingBytes {
                path: self.path.to_owned(),
                offset: header.byte_len + expected,
                extra: 1 + rest,
                line: vertex.line,
                count: vertex.count,
            });
        }

        #[cfg(target_endian = "big")]
        for word in bytemuck::cast_slice_mut::<Point, u32>(&mut points) {
            *word = u32::from_le(*word);
        }

        for (index, point) in points.iter().enumerate() {
            let values = [
                point.position[0],
                point.position[1],
                point.position[2],
                point.scalar,
                point.hp,
            ];
            for (k, (&value, name)) in values.iter().zip(PROPERTY_NAMES).enumerate() {
                let (lo, hi) = if k < 3 { (-1.0, 1.0) } else { (0.0, 1.0) };
                if !(value >= lo && value <= hi)
                    && let Err(reason) = check_value(name, value, lo, hi)
                {
                    return Err(CloudError::Point {
                        path: self.path.to_owned(),
                        index: index as u64,
                        offset: header.byte_len + (index * POINT_BYTES + k * 4) as u64,
                        reason,
                    });
                }
            }
        }
        Ok(points)
    }

    fn read_generic(&mut self) -> Result<(Vec<Point>, CloudMeta), CloudError> {
        let header = self.header;
        if header.encoding == Encoding::BinaryBigEndian {
            return Err(self.header_error(
                header.format_line,
                "binary_big_endian PLY is not supported: save it as binary_little_endian or \
                 ascii (MeshLab, CloudCompare and Open3D can)"
                    .into(),
            ));
        }
        let Some(vertex) = header.elements.first() else {
            return Err(self.header_error(
                header.end_line,
                "no `element vertex N` before `end_header`".into(),
            ));
        };
        if vertex.name != "vertex" {
            let line = header
                .elements
                .iter()
                .find(|e| e.name == "vertex")
                .map_or(vertex.line, |e| e.line);
            return Err(self.header_error(
                line,
                format!(
                    "`element vertex` must be the first element (found `element {}` first, on \
                     line {})",
                    vertex.name, vertex.line
                ),
            ));
        }
        let mut columns = [0usize; 3];
        for (column, axis) in columns.iter_mut().zip(["x", "y", "z"]) {
            let Some(index) = vertex.properties.iter().position(|p| p.name == axis) else {
                return Err(self.header_error(
                    vertex.line,
                    format!(
                        "`element vertex` has no property `{axis}` (a point cloud needs x, y, z)"
                    ),
                ));
            };
            let property = &vertex.properties[index];
            if let PropertyKind::List { .. } = property.kind {
                return Err(self.header_error(
                    property.line,
                    format!(
                        "`{axis}` must be a number, found a list: `{}`",
                        property.text
                    ),
                ));
            }
            *column = index;
        }
        let count = self.vertex_count_as_usize(vertex)?;
        let mut relative = match header.encoding {
            Encoding::Ascii => self.read_generic_ascii(vertex, count, columns)?,
            _ => self.read_generic_binary(vertex, count, columns)?,
        };
        let (points, ranges) = normalize_generic(&mut relative);
        let meta = CloudMeta {
            mode: DataMode::Generic,
            axes: Axes::generic(ranges),
            point_count: None,
            source: None,
            stft: None,
            metrics: None,
            songs: Vec::new(),
            raw: Value::Null,
        };
        Ok((points, meta))
    }

    /// Positions relative to the first point (kept as f32 without losing the precision of
    /// large coordinates), and that first point.
    fn read_generic_binary(
        &mut self,
        vertex: &Element,
        count: usize,
        columns: [usize; 3],
    ) -> Result<GenericPositions, CloudError> {
        let mut offsets = Vec::new();
        let mut record_bytes = 0usize;
        for property in &vertex.properties {
            match property.kind {
                PropertyKind::Scalar(t) => {
                    offsets.push((record_bytes, t));
                    record_bytes += t.size();
                }
                PropertyKind::List { .. } => {
                    return Err(self.header_error(
                        property.line,
                        format!(
                            "list property `{}` in `element vertex` is not supported in binary \
                             files",
                            property.name
                        ),
                    ));
                }
            }
        }
        self.check_body_fits(vertex, record_bytes as u64)?;
        let mut positions = GenericPositions::with_capacity(count, self.remaining, record_bytes)
            .map_err(|_| self.out_of_memory(vertex.count, POINT_BYTES as u64))?;
        // About 4 MiB per read, whatever the record size.
        let chunk_records = ((4 << 20) / record_bytes).clamp(1, CHUNK_RECORDS);
        let mut buf = vec![0u8; record_bytes * chunk_records.min(count.max(1))];
        let mut done = 0usize;
        while done < count {
            let records = (count - done).min(chunk_records);
            let bytes = &mut buf[..records * record_bytes];
            let read_at = self.header.byte_len + (done * record_bytes) as u64;
            let got = read_full(&mut self.reader, bytes)
                .map_err(|e| self.body_error(read_at, format!("cannot read vertex data: {e}")))?;
            if got < bytes.len() {
                let available = (done * record_bytes + got) as u64;
                return Err(CloudError::Truncated {
                    path: self.path.to_owned(),
                    offset: self.header.byte_len + available,
                    line: vertex.line,
                    count: vertex.count,
                    expected: vertex.count.saturating_mul(record_bytes as u64),
                    available,
                });
            }
            for (i, record) in bytes.chunks_exact(record_bytes).enumerate() {
                let index = done + i;
                let mut xyz = [0f64; 3];
                for (value, &column) in xyz.iter_mut().zip(&columns) {
                    let (offset, kind) = offsets[column];
                    *value = record
                        .get(offset..)
                        .and_then(|b| kind.read_le(b))
                        .unwrap_or(f64::NAN);
                }
                positions
                    .push(xyz)
                    .map_err(|(axis, reason)| CloudError::Point {
                        path: self.path.to_owned(),
                        index: index as u64,
                        offset: read_at
                            + (i * record_bytes) as u64
                            + offsets[columns[axis]].0 as u64,
                        reason,
                    })?;
            }
            done += records;
        }
        Ok(positions)
    }

    fn read_generic_ascii(
        &mut self,
        vertex: &Element,
        count: usize,
        columns: [usize; 3],
    ) -> Result<GenericPositions, CloudError> {
        // Each value takes at least one character and one separator.
        let min_record_bytes = 2 * vertex.properties.len() as u64;
        let expected = vertex.count.saturating_mul(min_record_bytes);
        if let Some(available) = self.remaining.filter(|&a| a < expected) {
            return Err(self.header_error(
                vertex.line,
                format!(
                    "`element vertex {}` needs at least {expected} bytes of ascii data but only \
                     {available} bytes follow the header (truncated file or wrong count)",
                    vertex.count
                ),
            ));
        }
        let mut positions =
            GenericPositions::with_capacity(count, self.remaining, min_record_bytes as usize)
                .map_err(|_| self.out_of_memory(vertex.count, POINT_BYTES as u64))?;
        let mut offset = self.header.byte_len;
        let mut line_no = self.header.end_line;
        let mut buf = Vec::new();
        let mut index = 0usize;
        while index < count {
            buf.clear();
            line_no += 1;
            let line_start = offset;
            let n = self
                .reader
                .by_ref()
                .take(MAX_ASCII_LINE_BYTES)
                .read_until(b'\n', &mut buf)
                .map_err(|e| self.body_error(line_start, format!("cannot read: {e}")))?;
            offset += n as u64;
            if n == 0 {
                return Err(self.body_error(
                    line_start,
                    format!(
                        "the file ends after {index} of {} vertex records declared on header \
                         line {} (truncated file or wrong count)",
                        vertex.count, vertex.line
                    ),
                ));
            }
            if n as u64 >= MAX_ASCII_LINE_BYTES && buf.last() != Some(&b'\n') {
                return Err(self.body_error(
                    line_start,
                    format!(
                        "line {line_no}: longer than {} KiB",
                        MAX_ASCII_LINE_BYTES / 1024
                    ),
                ));
            }
            let Ok(text) = std::str::from_utf8(&buf) else {
                return Err(self.body_error(
                    line_start,
                    format!("line {line_no}: not ASCII text (vertex record {index})"),
                ));
            };
            let mut tokens = text.split_ascii_whitespace();
            let Some(first) = tokens.next() else {
                continue; // blank line
            };
            let mut tokens = std::iter::once(first).chain(tokens);
            let mut values = Vec::with_capacity(vertex.properties.len());
            for property in &vertex.properties {
                let mut next_number = |what: &str| -> Result<f64, CloudError> {
                    let token = tokens.next().ok_or_else(|| {
                        self.body_error(
                            line_start,
                            format!(
                                "line {line_no}: vertex record {index} ends before {what} `{}`",
                                property.name
                            ),
                        )
                    })?;
                    token.parse::<f64>().map_err(|_| {
                        self.body_error(
                            line_start,
                            format!(
                                "line {line_no}: {} is not a number ({what} `{}` of vertex \
                                 record {index})",
                                excerpt(token.as_bytes()),
                                property.name
                            ),
                        )
                    })
                };
                match property.kind {
                    PropertyKind::Scalar(_) => values.push(next_number("property")?),
                    PropertyKind::List { .. } => {
                        let length = next_number("the length of list")?;
                        if !(length >= 0.0 && length.fract() == 0.0 && length <= 1e6) {
                            return Err(self.body_error(
                                line_start,
                                format!(
                                    "line {line_no}: list length {length} of `{}` is not a \
                                     whole number in 0..=1000000",
                                    property.name
                                ),
                            ));
                        }
                        for _ in 0..length as usize {
                            next_number("an item of list")?;
                        }
                        values.push(f64::NAN); // lists are not positions
                    }
                }
            }
            let xyz = columns.map(|c| values[c]);
            positions
                .push(xyz)
                .map_err(|(_, reason)| CloudError::Point {
                    path: self.path.to_owned(),
                    index: index as u64,
                    offset: line_start,
                    reason: format!("line {line_no}: {reason}"),
                })?;
            index += 1;
        }
        Ok(positions)
    }
}

/// Positions of a generic file while reading: relative to the first point, as f32.
struct GenericPositions {
    origin: Option<[f64; 3]>,
    relative: Vec<Point>,
}

impl GenericPositions {
    /// Reserves `count` points, or fewer when the remaining bytes cannot hold that many.
    fn with_capacity(
        count: usize,
        remaining: Option<u64>,
        min_record_bytes: usize,
    ) -> Result<GenericPositions, std::collections::TryReserveError> {
        let cap = match remaining {
            Some(r) => {
                count.min(usize::try_from(r / min_record_bytes.max(1) as u64).unwrap_or(count))
            }
            None => count.min(CHUNK_RECORDS),
        };
        let mut relative = Vec::new();
        relative.try_reserve_exact(cap)?;
        Ok(GenericPositions {
            origin: None,
            relative,
        })
    }

    /// Adds a position; on a non-finite coordinate, returns its axis and the reason.
    fn push(&mut self, xyz: [f64; 3]) -> Result<(), (usize, String)> {
        for (axis, (&value, name)) in xyz.iter().zip(["x", "y", "z"]).enumerate() {
            if !value.is_finite() {
                let sign = if value > 0.0 { "+" } else { "-" };
                let what = if value.is_nan() {
                    "NaN".to_owned()
                } else {
                    format!("{sign}inf")
                };
                return Err((axis, format!("{name} is {what}")));
            }
        }
        let origin = *self.origin.get_or_insert(xyz);
        let rel = [0, 1, 2].map(|i| (xyz[i] - origin[i]) as f32);
        if rel.iter().any(|v| !v.is_finite()) {
            return Err((
                0,
                "coordinates are too far apart to be shown together".into(),
            ));
        }
        self.relative.push(Point {
            position: rel,
            scalar: GENERIC_SCALAR,
            hp: GENERIC_HP,
        });
        Ok(())
    }
}

/// Centers the bounding box and scales its longest side to [-1, 1] (one factor for all axes).
/// Returns the points and, per axis, the file values at normalized -1 and +1.
fn normalize_generic(positions: &mut GenericPositions) -> (Vec<Point>, [(f64, f64); 3]) {
    let origin = positions.origin.unwrap_or([0.0; 3]);
    let mut points = std::mem::take(&mut positions.relative);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &points {
        for i in 0..3 {
            let v = f64::from(p.position[i]);
            lo[i] = lo[i].min(v);
            hi[i] = hi[i].max(v);
        }
    }
    if points.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    let center = [0, 1, 2].map(|i| (lo[i] + hi[i]) * 0.5);
    let longest = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    // A single point (or all points equal) has no extent: show it in a box of side 2.
    let half = if longest > 0.0 { longest * 0.5 } else { 1.0 };
    for p in &mut points {
        for (coordinate, c) in p.position.iter_mut().zip(center) {
            let v = (f64::from(*coordinate) - c) / half;
            *coordinate = (v as f32).clamp(-1.0, 1.0);
        }
    }
    let ranges = [0, 1, 2].map(|i| {
        let c = origin[i] + center[i];
        (c - half, c + half)
    });
    (points, ranges)
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Writes a loudscape header for `point_count` points, with `meta` as the `loudscape-meta`
/// comment (non-ASCII escaped, one line). Follow it with [`write_points`].
pub fn write_header<W: Write>(
    writer: &mut W,
    point_count: u64,
    meta: Option<&Value>,
) -> io::Result<()> {
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    if let Some(meta) = meta {
        let json = serde_json::to_string(meta).map_err(io::Error::other)?;
        header.push_str("comment ");
        header.push_str(META_KEYWORD);
        header.push(' ');
        for c in json.chars() {
            if c.is_ascii() {
                header.push(c);
            } else {
                let mut units = [0u16; 2];
                for unit in c.encode_utf16(&mut units) {
                    header.push_str(&format!("\\u{unit:04x}"));
                }
            }
        }
        header.push('\n');
    }
    header.push_str(&format!("element vertex {point_count}\n"));
    for name in PROPERTY_NAMES {
        header.push_str(&format!("property float {name}\n"));
    }
    header.push_str("end_header\n");
    writer.write_all(header.as_bytes())
}

/// Writes point records, little-endian.
pub fn write_points<W: Write>(writer: &mut W, points: &[Point]) -> io::Result<()> {
    #[cfg(target_endian = "little")]
    {
        writer.write_all(bytemuck::cast_slice(points))
    }
    #[cfg(target_endian = "big")]
    {
        for point in points {
            let words: [u32; 5] = bytemuck::cast(*point);
            for word in words {
                writer.write_all(&word.to_le_bytes())?;
            }
        }
        Ok(())
    }
}

/// Writes a whole loudscape file: header, then the points.
pub fn write<W: Write>(writer: &mut W, points: &[Point], meta: Option<&Value>) -> io::Result<()> {
    write_header(writer, points.len() as u64, meta)?;
    write_points(writer, points)
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
