//! Writing loudscape files: the header with its `loudscape-meta` comment, then the records.

use std::io::{self, Write};

use serde_json::Value;

use super::{META_KEYWORD, PROPERTY_NAMES, Point};

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
