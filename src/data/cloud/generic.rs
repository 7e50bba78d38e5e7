//! Generic PLY point clouds (no `loudscape-meta`, as MeshLab, Open3D or CloudCompare write):
//! ascii or binary little-endian, any scalar types, extra properties and later elements; the
//! positions are centred and scaled into [-1, 1] with one factor.

use std::io::{BufRead, Read};

use serde_json::Value;

use super::body::{Body, read_full};
use super::header::{Element, Encoding, PropertyKind, excerpt};
use super::{
    Axes, CHUNK_RECORDS, CloudError, CloudMeta, DataMode, GENERIC_HP, GENERIC_SCALAR,
    MAX_ASCII_LINE_BYTES, POINT_BYTES, Point,
};

impl<R: Read> Body<'_, R> {
    pub(super) fn read_generic(&mut self) -> Result<(Vec<Point>, CloudMeta), CloudError> {
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
        let (mut relative, end) = match header.encoding {
            Encoding::Ascii => self.read_generic_ascii(vertex, count, columns)?,
            _ => self.read_generic_binary(vertex, count, columns)?,
        };
        // Where the vertices are the file's only element, anything after them means the count is
        // wrong (or the file is two files): refused, as loading the first N would show part of
        // the data as if it were all of it.
        if header.elements.len() == 1 {
            self.check_nothing_after(vertex, end)?;
        }
        let (points, ranges) = normalize_generic(&mut relative);
        let meta = CloudMeta {
            mode: DataMode::Generic,
            axes: Axes::generic(ranges),
            point_count: None,
            source: None,
            stft: None,
            metrics: None,
            songs: Vec::new(),
            warnings: Vec::new(),
            raw: Value::Null,
        };
        Ok((points, meta))
    }

    /// Fails when data follows the last declared vertex, which ended at byte `end` (binary: any
    /// byte; ascii: anything but white space).
    fn check_nothing_after(&mut self, vertex: &Element, end: u64) -> Result<(), CloudError> {
        let mut buf = [0u8; 64 * 1024];
        let mut read = 0u64;
        loop {
            let n = read_full(&mut self.reader, &mut buf)
                .map_err(|e| self.body_error(end + read, format!("cannot read: {e}")))?;
            if n == 0 {
                return Ok(());
            }
            let data = match self.header.encoding {
                Encoding::Ascii => buf[..n].iter().position(|b| !b.is_ascii_whitespace()),
                _ => Some(0),
            };
            if let Some(i) = data {
                return Err(self.body_error(
                    end + read + i as u64,
                    format!(
                        "data follows the last of the {} points declared on header line {} (the \
                         file holds more points than it declares, or is damaged)",
                        vertex.count, vertex.line
                    ),
                ));
            }
            read += n as u64;
        }
    }

    /// Positions relative to the first point (kept as f32 without losing the precision of
    /// large coordinates), and that first point.
    pub(super) fn read_generic_binary(
        &mut self,
        vertex: &Element,
        count: usize,
        columns: [usize; 3],
    ) -> Result<(GenericPositions, u64), CloudError> {
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
        Ok((
            positions,
            self.header.byte_len + (count * record_bytes) as u64,
        ))
    }

    pub(super) fn read_generic_ascii(
        &mut self,
        vertex: &Element,
        count: usize,
        columns: [usize; 3],
    ) -> Result<(GenericPositions, u64), CloudError> {
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
            if buf.last() != Some(&b'\n') {
                // The last line of an ascii PLY ends with a line break like every other: a file
                // that stops inside a record may have lost digits of its last number.
                return Err(self.body_error(
                    offset,
                    format!(
                        "line {line_no}: the file ends inside vertex record {index} (no line \
                         break after it): cut short?"
                    ),
                ));
            }
            index += 1;
        }
        Ok((positions, offset))
    }
}

/// Positions of a generic file while reading: relative to the first point, as f32.
pub(super) struct GenericPositions {
    pub(super) origin: Option<[f64; 3]>,
    pub(super) relative: Vec<Point>,
}

impl GenericPositions {
    /// Reserves `count` points, or fewer when the remaining bytes cannot hold that many.
    pub(super) fn with_capacity(
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
    pub(super) fn push(&mut self, xyz: [f64; 3]) -> Result<(), (usize, String)> {
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
pub(super) fn normalize_generic(positions: &mut GenericPositions) -> (Vec<Point>, [(f64, f64); 3]) {
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
