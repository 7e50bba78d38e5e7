//! NumPy `.npy` files of float fields on a grid: the writer behind `loudscape voxelize` and
//! `loudscape bench --fields-dir`, and the reader behind `loudscape mesh FIELD.npy` (with the
//! `FIELD.npy.json` description `voxelize` writes beside it, checked against the array).
//!
//! Layout: C order, x (the grid's first axis) varying fastest, so an array of shape
//! `(nz, ny, nx)` or `(fields, nz, ny, nx)` holds voxel (i, j, k) of field f at
//! `[f, k, j, i]`, the GPU buffers' layout.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use glam::{UVec3, Vec3};

/// Writes `fields` (each `dims` voxels) as one float32 array: shape `(nz, ny, nx)` for one
/// field, `(fields, nz, ny, nx)` for several. Format version 1.0, header padded to 64 bytes.
pub fn write(out: &mut impl Write, fields: &[&[f32]], dims: UVec3) -> std::io::Result<()> {
    let shape = match fields.len() {
        1 => format!("({}, {}, {})", dims.z, dims.y, dims.x),
        n => format!("({n}, {}, {}, {})", dims.z, dims.y, dims.x),
    };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6) + version (2) + header length (2) + header + newline, padded to 64 bytes.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    header.push('\n');
    out.write_all(b"\x93NUMPY\x01\x00")?;
    out.write_all(&(header.len() as u16).to_le_bytes())?;
    out.write_all(header.as_bytes())?;
    for field in fields {
        out.write_all(bytemuck::cast_slice(field))?;
    }
    Ok(())
}

/// A grid of fields read from a `.npy` file.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyFields {
    pub dims: UVec3,
    /// One `Vec` per field, `dims` voxels each, x fastest.
    pub fields: Vec<Vec<f32>>,
    /// The file's element type: `<f4` or `<f8`.
    pub dtype: &'static str,
}

/// Reads a float32 or float64 array of shape `(nz, ny, nx)` (one field) or
/// `(fields, nz, ny, nx)`, C order, little endian, format version 1, 2 or 3.
pub fn read(path: &Path) -> anyhow::Result<NpyFields> {
    crate::files::check_regular(path).map_err(anyhow::Error::msg)?;
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    parse(&bytes).with_context(|| format!("{}", path.display()))
}

/// [`read`] on the file's bytes.
pub fn parse(bytes: &[u8]) -> anyhow::Result<NpyFields> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        bail!("not a NumPy .npy file (no \\x93NUMPY magic)");
    }
    let (header_len, header_start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => bail!("unsupported .npy format version {v}"),
    };
    let body_start = header_start + header_len;
    let header = bytes
        .get(header_start..body_start)
        .context("the header is cut short")?;
    let header = std::str::from_utf8(header).context("the header is not text")?;
    let descr = dict_value(header, "descr").context("the header has no 'descr'")?;
    let (size, dtype) = match descr.trim_matches(['\'', '"']) {
        "<f4" | "=f4" => (4, "<f4"),
        "<f8" | "=f8" => (8, "<f8"),
        other => bail!("the array holds '{other}'; expected little-endian float32 or float64"),
    };
    if dict_value(header, "fortran_order").map(str::trim) != Some("False") {
        bail!("the array is in Fortran order; save it in C order (np.ascontiguousarray)");
    }
    let shape_text = dict_value(header, "shape").context("the header has no 'shape'")?;
    let shape: Vec<usize> = shape_text
        .trim_matches(['(', ')'])
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("the shape {shape_text} is not a tuple of sizes"))?;
    let (count, [nz, ny, nx]) = match *shape.as_slice() {
        [nz, ny, nx] => (1, [nz, ny, nx]),
        [f, nz, ny, nx] if f >= 1 => (f, [nz, ny, nx]),
        _ => {
            bail!("the array has shape {shape_text}; expected (nz, ny, nx) or (fields, nz, ny, nx)")
        }
    };
    let axis = |n: usize| u32::try_from(n).ok().filter(|&n| n >= 1);
    let (Some(x), Some(y), Some(z)) = (axis(nx), axis(ny), axis(nz)) else {
        bail!("the array has shape {shape_text}; every axis must be at least 1 long");
    };
    let dims = UVec3::new(x, y, z);
    let voxels = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(nz))
        .context("the array is too large")?;
    let expected = voxels
        .checked_mul(count)
        .and_then(|n| n.checked_mul(size))
        .context("the array is too large")?;
    let body = &bytes[body_start..];
    if body.len() < expected {
        bail!(
            "the data is cut short: {} bytes where shape {shape_text} needs {expected}",
            body.len()
        );
    }
    // One field at a time, straight from the bytes.
    let fields = body[..expected]
        .chunks_exact(voxels * size)
        .map(|field| {
            field
                .chunks_exact(size)
                .map(|c| match *c {
                    [a, b, c, d] => f32::from_le_bytes([a, b, c, d]),
                    _ => f64::from_le_bytes(c.try_into().expect("8 bytes")) as f32,
                })
                .collect()
        })
        .collect();
    Ok(NpyFields {
        dims,
        fields,
        dtype,
    })
}

/// The box of a field: from `FIELD.npy.json` when there is one (which must describe this array:
/// its `dims`, `dtype` and `fields` when it gives them), else voxel units.
pub fn field_box(path: &Path, npy: &NpyFields) -> anyhow::Result<(Vec3, Vec3)> {
    let meta_path = PathBuf::from(format!("{}.json", path.display()));
    if !meta_path.exists() {
        return Ok((Vec3::splat(-0.5), npy.dims.as_vec3() - 0.5));
    }
    crate::files::check_regular(&meta_path).map_err(anyhow::Error::msg)?;
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut std::io::Read::take(
            std::fs::File::open(&meta_path)
                .with_context(|| format!("{}: cannot read", meta_path.display()))?,
            MAX_SIDECAR_BYTES + 1,
        ),
        &mut text,
    )
    .with_context(|| format!("{}: cannot read", meta_path.display()))?;
    if text.len() as u64 > MAX_SIDECAR_BYTES {
        bail!(
            "{}: longer than {} MiB; a grid's description is a few hundred bytes",
            meta_path.display(),
            MAX_SIDECAR_BYTES >> 20
        );
    }
    field_box_of(&text, &meta_path, path, npy)
}

/// The longest `FIELD.npy.json` read.
pub const MAX_SIDECAR_BYTES: u64 = 1 << 20;

/// [`field_box`] on the description's text (`meta_path`, `path`: for messages).
pub fn field_box_of(
    text: &str,
    meta_path: &Path,
    path: &Path,
    npy: &NpyFields,
) -> anyhow::Result<(Vec3, Vec3)> {
    let meta: serde_json::Value =
        serde_json::from_str(text).with_context(|| format!("{}: not JSON", meta_path.display()))?;
    let corner = |key: &str| -> anyhow::Result<Vec3> {
        let v: [f32; 3] = serde_json::from_value(meta[key].clone())
            .with_context(|| format!("{}: '{key}' is not three numbers", meta_path.display()))?;
        Ok(Vec3::from_array(v))
    };
    check_sidecar(&meta, meta_path, path, npy)?;
    let (min, max) = (corner("box_min")?, corner("box_max")?);
    if !(min.is_finite() && max.is_finite() && min.cmplt(max).all()) {
        bail!("{}: the box is empty or not finite", meta_path.display());
    }
    Ok((min, max))
}

/// Refuses a description that is not of this array (a pair written apart, or half replaced):
/// `dims` `[x, y, z]`, `dtype` and the number of `fields`, each when the description has it.
pub fn check_sidecar(
    meta: &serde_json::Value,
    meta_path: &Path,
    path: &Path,
    npy: &NpyFields,
) -> anyhow::Result<()> {
    let mismatch = |what: &str, says: String, holds: String| {
        anyhow::anyhow!(
            "{}: describes {what} {says} but {} holds {holds}; the pair does not belong \
             together (write both again with `loudscape voxelize`)",
            meta_path.display(),
            path.display()
        )
    };
    let dims = npy.dims;
    if let Some(value) = meta.get("dims") {
        let said: [u32; 3] = serde_json::from_value(value.clone())
            .with_context(|| format!("{}: 'dims' is not three sizes", meta_path.display()))?;
        if said != dims.to_array() {
            return Err(mismatch(
                "a grid of",
                format!("{}x{}x{}", said[0], said[1], said[2]),
                format!("{}x{}x{}", dims.x, dims.y, dims.z),
            ));
        }
    }
    if let Some(value) = meta.get("dtype") {
        let said = value.as_str().unwrap_or_default();
        if said != npy.dtype {
            return Err(mismatch(
                "dtype",
                format!("{value}"),
                format!("'{}'", npy.dtype),
            ));
        }
    }
    if let Some(fields) = meta.get("fields").and_then(|f| f.as_array())
        && fields.len() != npy.fields.len()
    {
        return Err(mismatch(
            "fields:",
            fields.len().to_string(),
            npy.fields.len().to_string(),
        ));
    }
    Ok(())
}

/// The text of `key`'s value in the header's Python dict literal (up to the next top-level
/// comma or the closing brace).
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let quoted = [format!("'{key}'"), format!("\"{key}\"")];
    let start = quoted
        .iter()
        .find_map(|q| header.find(q.as_str()).map(|i| i + q.len()))?;
    let rest = header[start..].trim_start().strip_prefix(':')?.trim_start();
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '}' if depth == 0 => return Some(rest[..i].trim()),
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_fields_read_back() {
        let dims = UVec3::new(3, 2, 4);
        let a: Vec<f32> = (0..24).map(|i| i as f32 * 0.5).collect();
        let b: Vec<f32> = (0..24).map(|i| 1.0 - i as f32).collect();
        for fields in [vec![&a[..]], vec![&a[..], &b[..]]] {
            let mut bytes = Vec::new();
            write(&mut bytes, &fields, dims).unwrap();
            // The header ends on a 64-byte boundary, as NumPy requires for version 1.0.
            let header_len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
            assert_eq!((10 + header_len) % 64, 0);
            let read = parse(&bytes).unwrap();
            assert_eq!(read.dims, dims);
            assert_eq!(read.fields.len(), fields.len());
            for (r, f) in read.fields.iter().zip(&fields) {
                assert_eq!(r.as_slice(), *f);
            }
        }
    }

    /// A header the way NumPy writes one, around `body`.
    fn npy(descr: &str, fortran: bool, shape: &str, body: &[u8]) -> Vec<u8> {
        let fortran = if fortran { "True" } else { "False" };
        let header =
            format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}\n");
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
        bytes.extend_from_slice(header.as_bytes());
        bytes.extend_from_slice(body);
        bytes
    }

    #[test]
    fn float64_is_converted() {
        let body: Vec<u8> = [0.25f64, 2.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let read = parse(&npy("<f8", false, "(1, 1, 2)", &body)).unwrap();
        assert_eq!(read.dims, UVec3::new(2, 1, 1));
        assert_eq!(read.fields, vec![vec![0.25, 2.0]]);
    }

    #[test]
    fn bad_files_say_why() {
        let four = [0u8; 16];
        let message = |bytes: &[u8]| format!("{:#}", parse(bytes).unwrap_err());
        assert!(message(b"PK\x03\x04 not numpy").contains("magic"));
        assert!(message(&npy("<i4", false, "(2, 2)", &four)).contains("float32"));
        assert!(message(&npy("<f4", true, "(1, 2, 2)", &four)).contains("Fortran"));
        assert!(message(&npy("<f4", false, "(2, 2)", &four)).contains("expected (nz, ny, nx)"));
        assert!(message(&npy("<f4", false, "(2, 2, 2)", &four)).contains("cut short"));
        assert!(message(&npy("<f4", false, "(0, 2, 2)", &four)).contains("at least 1"));
        assert!(message(&npy(">f4", false, "(1, 2, 2)", &four)).contains("little-endian"));
    }
}
