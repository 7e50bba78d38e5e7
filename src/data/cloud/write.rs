//! Writing loudscape files: the header with its metadata (format version 2 by default:
//! `comment loudscape-meta-v2 I/N CHUNK` lines, docs/FORMAT.md), then the records.

use std::io::{self, Write};

use serde_json::Value;

use super::{FORMAT_VERSION, META_KEYWORD, META_V2_KEYWORD, PROPERTY_NAMES, Point};

/// Bytes of JSON per `loudscape-meta-v2` line (docs/FORMAT.md: lines of at most 1,000 bytes).
pub const META_CHUNK_BYTES: usize = 900;

/// The metadata as the header carries it: compact JSON, every non-ASCII character escaped as
/// `\uXXXX` (surrogate pairs above U+FFFF); in version 2 also every space as `\u0020`, so the
/// text has no whitespace at all.
fn meta_text(meta: &Value, format_version: u64) -> io::Result<String> {
    let mut meta = meta.clone();
    if let Value::Object(object) = &mut meta {
        object.insert("format_version".into(), format_version.into());
    }
    let json = serde_json::to_string(&meta).map_err(io::Error::other)?;
    let mut text = String::with_capacity(json.len() + json.len() / 8);
    for c in json.chars() {
        if c == ' ' && format_version >= 2 {
            text.push_str("\\u0020");
        } else if c.is_ascii() {
            text.push(c);
        } else {
            let mut units = [0u16; 2];
            for unit in c.encode_utf16(&mut units) {
                text.push_str(&format!("\\u{unit:04x}"));
            }
        }
    }
    Ok(text)
}

/// Writes a loudscape header for `point_count` points with `meta` in format version 2 (its
/// `format_version` set to 2). Follow it with [`write_points`].
pub fn write_header<W: Write>(
    writer: &mut W,
    point_count: u64,
    meta: Option<&Value>,
) -> io::Result<()> {
    write_header_version(writer, point_count, meta, FORMAT_VERSION)
}

/// [`write_header`] in a chosen format version: 2, or 1 (one `comment loudscape-meta` line of
/// any length, for tests and for readers that know nothing newer).
pub fn write_header_version<W: Write>(
    writer: &mut W,
    point_count: u64,
    meta: Option<&Value>,
    format_version: u64,
) -> io::Result<()> {
    if !matches!(format_version, 1 | 2) {
        return Err(io::Error::other(format!(
            "format_version must be 1 or 2, not {format_version}"
        )));
    }
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    if let Some(meta) = meta {
        let text = meta_text(meta, format_version)?;
        if format_version == 1 {
            header.push_str(&format!("comment {META_KEYWORD} {text}\n"));
        } else {
            // The text is ASCII, so any byte is a character boundary.
            let chunks: Vec<&str> = text
                .as_bytes()
                .chunks(META_CHUNK_BYTES)
                .map(|c| std::str::from_utf8(c).expect("ASCII"))
                .collect();
            let total = chunks.len();
            for (i, chunk) in chunks.iter().enumerate() {
                header.push_str(&format!(
                    "comment {META_V2_KEYWORD} {}/{total} {chunk}\n",
                    i + 1
                ));
            }
        }
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

/// Writes a whole loudscape file (format version 2): header, then the points.
pub fn write<W: Write>(writer: &mut W, points: &[Point], meta: Option<&Value>) -> io::Result<()> {
    write_header(writer, points.len() as u64, meta)?;
    write_points(writer, points)
}
