//! The points of a song while it is extracted (docs/FORMAT.md, "Points while extracting"): with
//! `--progress json` the extractor appends each block's rows to a body file beside its output
//! (`.<output name>.points-<pid>`, float32 little-endian, 5 columns `x y z scalar hp`, exactly
//! the rows the PLY body will hold) and says after each block how many rows it holds, with the
//! final cloud's axes ([`PointsSoFar`], parsed by `child.rs`). [`BodyReader`] reads the rows
//! added since its last read, keeping its handle and offset; [`Preview`] gathers them and makes
//! the growing cloud the window shows, at most every [`Preview::interval`].
//!
//! The preview is a bonus: whatever goes wrong reading the body file (removed, short, a bad
//! value) loses the preview, never the extraction, whose PLY is read as it always was.

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::data::cloud::{Aabb, POINT_BYTES, Point, PointCloud, RANGE_EPSILON};

use super::Settings;

/// The `points` member of a progress line: how many whole rows the body file holds so far, and
/// the final cloud's axes (they do not change during a run).
#[derive(Clone, Debug, PartialEq)]
pub struct PointsSoFar {
    /// The body file (absolute).
    pub path: PathBuf,
    /// Whole rows written so far (never fewer than the line before).
    pub rows: u64,
    /// The axes object exactly as the PLY metadata will hold it.
    pub axes: Value,
    /// `"linear"` or `"log"`.
    pub freq_scale: String,
}

impl PointsSoFar {
    /// The `points` member of a progress line; `None` when it is missing or not one a song
    /// window can show (another mode, no path, no axes object).
    pub fn parse(value: &Value) -> Option<PointsSoFar> {
        let points = value.get("points")?;
        if points.get("mode").and_then(Value::as_str) != Some("song") {
            return None;
        }
        let path = points.get("path").and_then(Value::as_str)?;
        let rows = points.get("rows").and_then(Value::as_u64)?;
        let axes = points.get("axes").filter(|a| a.is_object())?.clone();
        let freq_scale = points
            .get("freq_scale")
            .and_then(Value::as_str)
            .unwrap_or("linear")
            .to_string();
        Some(PointsSoFar {
            path: PathBuf::from(path),
            rows,
            axes,
            freq_scale,
        })
    }
}

/// Reads a growing body file a piece at a time: the handle stays open (the extractor may
/// remove the file meanwhile: on Unix the open file stays readable, on Windows Rust opens with
/// delete sharing) and each read starts where the last one stopped.
#[derive(Debug)]
pub struct BodyReader {
    path: PathBuf,
    file: Option<File>,
    /// Rows read so far.
    rows: u64,
    /// The bytes of a row read only in part (the file was shorter than its line said).
    carry: Vec<u8>,
}

impl BodyReader {
    pub fn new(path: &Path) -> BodyReader {
        BodyReader {
            path: path.to_owned(),
            file: None,
            rows: 0,
            carry: Vec::new(),
        }
    }

    /// The file it reads.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows read so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends to `into` the rows after those already read, up to `rows` in all; returns how
    /// many it appended. A file that cannot be opened yet (not there: already removed, as the
    /// protocol allows) gives none; once open, a failed read or a value out of the format's
    /// ranges is an error (the caller gives up the preview).
    pub fn read_up_to(&mut self, rows: u64, into: &mut Vec<Point>) -> io::Result<usize> {
        if rows <= self.rows {
            return Ok(0);
        }
        if self.file.is_none() {
            match File::open(&self.path) {
                Ok(mut file) => {
                    file.seek(SeekFrom::Start(self.rows * POINT_BYTES as u64))?;
                    self.file = Some(file);
                }
                Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(0),
                Err(e) => return Err(e),
            }
        }
        let Some(file) = self.file.as_mut() else {
            return Ok(0);
        };
        let wanted = (rows - self.rows) as usize * POINT_BYTES - self.carry.len();
        let mut bytes = std::mem::take(&mut self.carry);
        bytes.reserve(wanted);
        file.take(wanted as u64).read_to_end(&mut bytes)?;
        let whole = bytes.len() / POINT_BYTES;
        into.reserve(whole);
        let before = into.len();
        for row in bytes.chunks_exact(POINT_BYTES) {
            let value = |i: usize| {
                f32::from_le_bytes([row[4 * i], row[4 * i + 1], row[4 * i + 2], row[4 * i + 3]])
            };
            let point = Point {
                position: [value(0), value(1), value(2)],
                scalar: value(3),
                hp: value(4),
            };
            if let Some(reason) = out_of_range(&point) {
                let row = self.rows as usize + into.len() - before;
                into.truncate(before);
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("row {row}: {reason}"),
                ));
            }
            into.push(point);
        }
        self.carry = bytes.split_off(whole * POINT_BYTES);
        self.rows += whole as u64;
        Ok(whole)
    }
}

/// Why `point` is not a row of a loudscape body (positions in [-1, 1], scalar and hp in
/// [0, 1], all finite), if it is not.
fn out_of_range(point: &Point) -> Option<String> {
    let in_range =
        |v: f32, lo: f32| v.is_finite() && v >= lo - RANGE_EPSILON && v <= 1.0 + RANGE_EPSILON;
    if !point.position.iter().all(|&v| in_range(v, -1.0)) {
        return Some(format!("position {:?} is outside [-1, 1]", point.position));
    }
    if !in_range(point.scalar, 0.0) || !in_range(point.hp, 0.0) {
        return Some(format!(
            "scalar {} or hp {} is outside [0, 1]",
            point.scalar, point.hp
        ));
    }
    None
}

/// The growing cloud of one extraction: the rows read so far, with the metadata the progress
/// lines give (the final axes), handed on at most every [`Preview::interval`].
pub struct Preview {
    /// The song: the cloud's path (as the final cloud's is) and its `source.path`.
    audio: PathBuf,
    n_fft: u32,
    hop: u32,
    reader: Option<BodyReader>,
    points: Vec<Point>,
    meta: Option<crate::data::cloud::CloudMeta>,
    last_handed: Option<Instant>,
    /// Rows in the last cloud handed on.
    handed: usize,
    /// Why the preview was given up, once it was.
    failed: Option<String>,
}

impl Preview {
    /// A preview of `audio` (the absolute path the extractor records) extracted with
    /// `settings`.
    pub fn new(audio: &Path, settings: &Settings) -> Preview {
        Preview {
            audio: audio.to_owned(),
            n_fft: settings.n_fft,
            hop: settings.hop,
            reader: None,
            points: Vec::new(),
            meta: None,
            last_handed: None,
            handed: 0,
            failed: None,
        }
    }

    /// How long after handing on a cloud of `rows` points the next one may go: a quarter of a
    /// second, longer for large clouds (the window uploads the whole cloud each time: about
    /// 0.25 s per million points, so the uploads take a small share of the window's time).
    pub fn interval(rows: usize) -> Duration {
        Duration::from_millis(250).max(Duration::from_secs_f64(rows as f64 / 4.0e6))
    }

    /// Why the preview was given up, if it was.
    pub fn failed(&self) -> Option<&str> {
        self.failed.as_deref()
    }

    /// Rows read so far.
    pub fn rows(&self) -> usize {
        self.points.len()
    }

    /// Takes one progress line's points at `now`: reads the new rows, and returns the cloud
    /// to show when one is due (new rows, and the interval passed since the last one). After a
    /// failure (returned as `Err` once, with the reason) it reads nothing more.
    pub fn hear(&mut self, line: &PointsSoFar, now: Instant) -> Result<Option<PointCloud>, String> {
        if self.failed.is_some() {
            return Ok(None);
        }
        match self.read(line) {
            Ok(()) => Ok(self.due(now)),
            Err(reason) => {
                self.failed = Some(reason.clone());
                self.points = Vec::new();
                Err(reason)
            }
        }
    }

    fn read(&mut self, line: &PointsSoFar) -> Result<(), String> {
        if self.meta.is_none() {
            self.meta = Some(self.meta_for(line)?);
        }
        let reader = self
            .reader
            .get_or_insert_with(|| BodyReader::new(&line.path));
        if reader.path() != line.path {
            return Err(format!(
                "the points moved from {} to {}",
                reader.path().display(),
                line.path.display()
            ));
        }
        reader
            .read_up_to(line.rows, &mut self.points)
            .map_err(|e| format!("{}: {e}", line.path.display()))?;
        Ok(())
    }

    /// The cloud of the rows read so far, when it has grown and the interval has passed.
    fn due(&mut self, now: Instant) -> Option<PointCloud> {
        let grown = self.points.len() > self.handed;
        let waited = self
            .last_handed
            .is_none_or(|at| now.duration_since(at) >= Preview::interval(self.handed));
        if !(grown && waited) {
            return None;
        }
        let meta = self.meta.clone()?;
        self.last_handed = Some(now);
        self.handed = self.points.len();
        Some(PointCloud {
            path: self.audio.clone(),
            bounds: Aabb::from_points(&self.points),
            points: self.points.clone(),
            meta,
        })
    }

    /// The metadata of the growing cloud: the final axes, and what the window needs to remap
    /// the frequency axis (`source.sample_rate`: twice the z axis's top, which is Nyquist;
    /// `stft.n_fft`). The rest (metrics, warnings, loudness) comes with the final cloud.
    fn meta_for(&self, line: &PointsSoFar) -> Result<crate::data::cloud::CloudMeta, String> {
        let nyquist = line
            .axes
            .get("z")
            .and_then(|z| z.get("max"))
            .and_then(Value::as_f64)
            .filter(|&hz| hz.is_finite() && hz > 0.0);
        let mut source = json!({ "path": self.audio.to_string_lossy() });
        if let Some(hz) = nyquist {
            source["sample_rate"] = json!((2.0 * hz).round() as u64);
        }
        let value = json!({
            "format_version": crate::data::cloud::FORMAT_VERSION,
            "mode": "song",
            "axes": line.axes,
            "source": source,
            "stft": { "n_fft": self.n_fft, "hop_length": self.hop },
            "extraction": { "freq_scale": line.freq_scale },
        });
        crate::data::cloud::meta_from_value(&value, &line.path)
            .map_err(|e| format!("the axes of the points so far: {e}"))
    }
}

#[cfg(test)]
#[path = "preview_tests.rs"]
mod tests;
