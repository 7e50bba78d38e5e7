//! The body of a loudscape file, the fast path: one read straight into a `Vec<Point>` of exactly
//! the declared count, then every value checked in place. Also the body reader's shared checks.

use std::io::{self, BufReader, Read};

use bytemuck::Zeroable;
use std::path::Path;

use super::header::{Element, Encoding, Header, PropertyKind, ScalarType};
use super::{
    CHUNK_RECORDS, CloudError, CloudMeta, META_KEYWORD, POINT_BYTES, PROPERTY_NAMES, Point,
    RANGE_EPSILON,
};

pub(super) struct Body<'a, R> {
    pub(super) reader: BufReader<R>,
    pub(super) path: &'a Path,
    pub(super) header: &'a Header,
    /// Bytes after the header, when the total length is known.
    pub(super) remaining: Option<u64>,
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
pub(super) fn read_full<R: Read>(reader: &mut R, buf: &mut [u8]) -> io::Result<usize> {
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

pub(super) fn check_value(name: &str, value: f32, lo: f32, hi: f32) -> Result<(), String> {
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
    pub(super) fn header_error(&self, line: usize, reason: String) -> CloudError {
        CloudError::Header {
            path: self.path.to_owned(),
            line,
            reason,
        }
    }

    pub(super) fn body_error(&self, offset: u64, reason: String) -> CloudError {
        CloudError::Body {
            path: self.path.to_owned(),
            offset,
            reason,
        }
    }

    pub(super) fn out_of_memory(&self, count: u64, record_bytes: u64) -> CloudError {
        CloudError::OutOfMemory {
            path: self.path.to_owned(),
            count,
            bytes: count.saturating_mul(record_bytes),
        }
    }

    /// Fails unless `count` records of `record_bytes` fit in what follows the header.
    pub(super) fn check_body_fits(
        &self,
        element: &Element,
        record_bytes: u64,
    ) -> Result<u64, CloudError> {
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

    pub(super) fn vertex_count_as_usize(&self, element: &Element) -> Result<usize, CloudError> {
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

    pub(super) fn read_loudscape(&mut self, meta: &CloudMeta) -> Result<Vec<Point>, CloudError> {
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
}
