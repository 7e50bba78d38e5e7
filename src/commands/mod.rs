//! One module per subcommand. Each parses its own arguments (clap `Args`) and returns
//! `anyhow::Result`, so every failure reaches the user as one line.

pub mod bench;
pub mod bench_surface;
pub mod bench_volume;
pub mod mesh;
pub mod npy;
pub mod render;
pub mod voxelize;

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

/// Writes through `PATH.tmp` and renames, so no half-written file is left under the name.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let tmp = PathBuf::from(format!("{}.tmp", path.display()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut out = std::io::BufWriter::new(file);
        write(&mut out)?;
        out.flush()?;
        Ok::<_, anyhow::Error>(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e.context(format!("{}: cannot write", path.display())));
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write", path.display()))
}

/// Parses `WxH` (e.g. `1280x720`).
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .with_context(|| format!("size '{text}' is not WIDTHxHEIGHT, e.g. 1280x720"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("width in '{text}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("height in '{text}'"))?;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        bail!("size '{text}' is out of range: each side must be 16 to 8192 pixels");
    }
    Ok((w, h))
}

/// Parses `AZ,EL,DIST` (degrees, degrees, distance in world units).
pub fn parse_camera(text: &str) -> anyhow::Result<(f32, f32, f32)> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [az, el, dist] = parts.as_slice() else {
        bail!("camera '{text}' is not AZ,EL,DIST, e.g. -35,25,4");
    };
    let number = |s: &str, what: &str| -> anyhow::Result<f32> {
        let v: f32 = s
            .parse()
            .with_context(|| format!("{what} '{s}' in camera '{text}' is not a number"))?;
        if !v.is_finite() {
            bail!("{what} in camera '{text}' is not finite");
        }
        Ok(v)
    };
    let dist_v = number(dist, "distance")?;
    if dist_v <= 0.0 {
        bail!("distance in camera '{text}' must be positive");
    }
    Ok((number(az, "azimuth")?, number(el, "elevation")?, dist_v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_cameras_parse() {
        assert_eq!(parse_size("1280x720").unwrap(), (1280, 720));
        assert!(parse_size("1280").is_err());
        assert!(parse_size("0x720").is_err());
        assert_eq!(parse_camera("-35, 25, 4").unwrap(), (-35.0, 25.0, 4.0));
        assert!(parse_camera("1,2").is_err());
        assert!(parse_camera("1,2,-3").is_err());
        assert!(parse_camera("a,2,3").is_err());
    }
}
