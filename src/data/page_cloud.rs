//! The cloud a web page carries (`loudscape page`, src/web/): thinned to at most a given number
//! of points and quantized to 16 bits a value, half the bytes of the PLY records.
//!
//! Layout, little-endian: the magic `LSPC1`, a u32 header length, the cloud's loudscape PLY
//! header (its metadata as in the file, `point_count` and `element vertex` the thinned count),
//! then 5 u16 per point: x, y, z mapped from [-1, 1] and scalar, hp from [0, 1] onto 0..=65535.
//! [`decode`] turns it back into PLY bytes and reads them with the cloud reader, so the page's
//! cloud passes the same checks as a file. Thinning keeps every k-th point in file order (the
//! smallest k that fits), so every part of the song keeps the same share of its points.

use serde_json::Value;

use crate::data::cloud::{self, CloudError, Point, PointCloud};

const MAGIC: &[u8; 5] = b"LSPC1";
/// Steps of a quantized value.
const STEPS: f32 = 65535.0;

/// What [`encode`] kept: the page says it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Thinning {
    /// Points in the cloud.
    pub total: usize,
    /// Points kept (every `stride`-th).
    pub kept: usize,
    pub stride: usize,
}

fn quantize(value: f32, min: f32, max: f32) -> u16 {
    let t = ((value - min) / (max - min)).clamp(0.0, 1.0);
    (t * STEPS).round() as u16
}

fn dequantize(q: u16, min: f32, max: f32) -> f32 {
    min + (max - min) * (q as f32 / STEPS)
}

/// `axes` as the metadata's `axes` object.
fn axes_value(axes: &crate::data::axes::Axes) -> Value {
    let object = axes
        .named()
        .into_iter()
        .map(|(name, axis)| {
            let value = serde_json::to_value(axis).expect("an axis is plain data");
            (name.to_string(), value)
        })
        .collect();
    Value::Object(object)
}

/// The page's bytes of `cloud`, at most `max_points` points (at least one).
pub fn encode(cloud: &PointCloud, max_points: usize) -> (Vec<u8>, Thinning) {
    let total = cloud.points.len();
    let stride = total.div_ceil(max_points.max(1)).max(1);
    let kept: Vec<&Point> = cloud.points.iter().step_by(stride).collect();
    let meta = match &cloud.meta.raw {
        Value::Object(object) => {
            let mut object = object.clone();
            if object.contains_key("point_count") {
                object.insert("point_count".into(), Value::from(kept.len() as u64));
            }
            // The axes the points are on: the file's, or the union of an A/B compare's
            // (`data::compare::on_union_axes`), which the raw metadata does not know.
            if object.contains_key("axes") {
                object.insert("axes".into(), axes_value(&cloud.meta.axes));
            }
            Some(Value::Object(object))
        }
        _ => None,
    };
    let mut header = Vec::new();
    cloud::write_header(&mut header, kept.len() as u64, meta.as_ref()).expect("writing to memory");
    let mut out = Vec::with_capacity(MAGIC.len() + 4 + header.len() + kept.len() * 10);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    for point in &kept {
        let [x, y, z] = point.position;
        let values = [
            quantize(x, -1.0, 1.0),
            quantize(y, -1.0, 1.0),
            quantize(z, -1.0, 1.0),
            quantize(point.scalar, 0.0, 1.0),
            quantize(point.hp, 0.0, 1.0),
        ];
        for v in values {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let thinning = Thinning {
        total,
        kept: kept.len(),
        stride,
    };
    (out, thinning)
}

/// The cloud of a page's bytes, named `name` in messages.
pub fn decode(bytes: &[u8], name: &str) -> Result<PointCloud, CloudError> {
    let path = std::path::Path::new(name);
    let bad = |reason: &str| CloudError::Body {
        path: path.to_path_buf(),
        offset: 0,
        reason: format!("page data: {reason}"),
    };
    let rest = bytes
        .strip_prefix(MAGIC.as_slice())
        .ok_or_else(|| bad("not loudscape page data (no LSPC1 mark)"))?;
    let (len, rest) = rest
        .split_first_chunk::<4>()
        .ok_or_else(|| bad("cut short before the header"))?;
    let len = u32::from_le_bytes(*len) as usize;
    if rest.len() < len || !(rest.len() - len).is_multiple_of(10) {
        return Err(bad(
            "cut short or padded: the body is not whole 10-byte records",
        ));
    }
    let (header, body) = rest.split_at(len);
    let mut ply = Vec::with_capacity(header.len() + body.len() * 2);
    ply.extend_from_slice(header);
    for record in body.chunks_exact(10) {
        let q = |i: usize| u16::from_le_bytes([record[2 * i], record[2 * i + 1]]);
        let point = Point {
            position: [
                dequantize(q(0), -1.0, 1.0),
                dequantize(q(1), -1.0, 1.0),
                dequantize(q(2), -1.0, 1.0),
            ],
            scalar: dequantize(q(3), 0.0, 1.0),
            hp: dequantize(q(4), 0.0, 1.0),
        };
        ply.extend_from_slice(bytemuck::bytes_of(&point));
    }
    cloud::load_from_bytes(&ply, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn song() -> PointCloud {
        let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/data/demo_song.ply"))
            .expect("demo song");
        cloud::load_from_bytes(&bytes, std::path::Path::new("demo_song.ply")).expect("loads")
    }

    /// Every k-th point comes back within half a quantization step, with the song's metadata
    /// (axes in units) and the thinned count; the page says what was kept.
    #[test]
    fn a_thinned_quantized_song_decodes_to_its_points() {
        let song = song();
        let max = song.len() / 3;
        let (bytes, thinning) = encode(&song, max);
        assert_eq!(thinning.total, song.len());
        assert!(thinning.kept <= max && thinning.kept > 0);
        assert_eq!(thinning.kept, song.len().div_ceil(thinning.stride));
        let back = decode(&bytes, "demo_song.ply").expect("decodes");
        assert_eq!(back.len(), thinning.kept);
        assert_eq!(back.meta.mode, song.meta.mode);
        assert_eq!(back.meta.axes, song.meta.axes);
        let half_step = 1.0 / STEPS;
        for (i, p) in back.points.iter().enumerate() {
            let q = song.points[i * thinning.stride];
            for a in 0..3 {
                assert!((p.position[a] - q.position[a]).abs() <= 2.0 * half_step + 1e-6);
            }
            assert!((p.scalar - q.scalar).abs() <= half_step + 1e-6);
            assert!((p.hp - q.hp).abs() <= half_step + 1e-6);
        }
        // A 10-byte record a point, half the PLY's 20.
        assert!(bytes.len() < song.len() * 20 / 2);
    }

    /// A cloud moved onto other axes (an A/B compare's union) carries those axes, not the
    /// file's.
    #[test]
    fn a_cloud_on_other_axes_carries_them() {
        let song = song();
        let mut louder = song.clone();
        louder.meta.axes.y.min += 6.0;
        louder.meta.axes.y.max += 6.0;
        let (a, _) = crate::data::compare::on_union_axes(&song, &louder).expect("one mode");
        assert_ne!(a.meta.axes, song.meta.axes);
        let (bytes, _) = encode(&a, a.len());
        let back = decode(&bytes, "a").expect("decodes");
        assert_eq!(back.meta.axes, a.meta.axes);
    }

    #[test]
    fn bytes_that_are_not_page_data_are_refused_with_the_reason() {
        let song = song();
        let (bytes, _) = encode(&song, 100);
        let cut = decode(&bytes[..bytes.len() - 3], "x")
            .unwrap_err()
            .to_string();
        assert!(cut.contains("10-byte records"), "{cut}");
        let other = decode(b"ply\nformat", "x").unwrap_err().to_string();
        assert!(other.contains("LSPC1"), "{other}");
    }
}
