//! The argument checks the subcommands share, with one set of messages: sizes, cameras, the
//! `--view` choice, isovalue, grid resolution and smoothing, value ranges, output folders, and
//! loading the input cloud. Closed vocabularies are typed where clap parses them
//! (`clap::ValueEnum`): clap lists their values in its messages.

use std::ops::RangeInclusive;
use std::path::Path;

use anyhow::{Context, bail};
use loudscape::data::cloud::PointCloud;
use loudscape::render::grid::voxelize::{MAX_RESOLUTION, MAX_SMOOTHING_SIGMA, MIN_RESOLUTION};
use loudscape::render::scene::ViewKind;
use loudscape::view::camera::Camera;

/// The demo song, the default input of commands that measure (`bench`).
pub const DEMO_SONG: &str = "data/demo_song.ply";

/// Loads a cloud, with the file named in the error; audio (anything not a PLY) is extracted
/// first, or found in the cloud cache. The error's own line already carries its cause (an OS
/// error, say), so it goes on as one message, not as a chain that repeats it.
pub fn load_cloud(path: &Path) -> anyhow::Result<PointCloud> {
    let cloud = loudscape::extract::open_for_command(path).map_err(|e| anyhow::anyhow!("{e}"))?;
    // An empty picture or grid with exit 0 would read as "the song is silent".
    if cloud.is_empty() {
        bail!(
            "{}: the cloud holds no points (`element vertex 0`); there is nothing to draw",
            path.display()
        );
    }
    Ok(cloud)
}

/// The checks every output gets before any work: it is none of `inputs` (not even through a
/// link), it ends in one of `extensions` (lowercase, without the dot), and its folder exists.
pub fn check_output(output: &Path, extensions: &[&str], inputs: &[&Path]) -> anyhow::Result<()> {
    check_not_input(output, inputs)?;
    check_extension(output, extensions)?;
    check_output_folder(output)
}

/// Fails unless `output` ends in one of `extensions`, listing them.
pub fn check_extension(output: &Path, extensions: &[&str]) -> anyhow::Result<()> {
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref().is_some_and(|e| extensions.contains(&e)) {
        return Ok(());
    }
    let list: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
    bail!(
        "{}: cannot write this file type; supported: {}",
        output.display(),
        list.join(", ")
    );
}

/// Fails when `output` is one of `inputs` (the same path, or the same file through a link).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    loudscape::files::check_not_input(output, inputs).map_err(anyhow::Error::msg)
}

/// Fails, naming the output, when the folder it would be written into does not exist or
/// cannot be written into (a read-only folder or file system), before any work.
pub fn check_output_folder(output: &Path) -> anyhow::Result<()> {
    let dir = output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        bail!(
            "{}: the folder {} does not exist",
            output.display(),
            dir.display()
        );
    }
    if let Err(reason) = folder_writable(dir) {
        bail!(
            "{}: cannot write into the folder {}: {reason}",
            output.display(),
            dir.display()
        );
    }
    Ok(())
}

/// Whether this process may create files in `dir` (access(2) with W_OK and X_OK: the rights of
/// the user the process runs as, and a read-only file system).
#[cfg(unix)]
fn folder_writable(dir: &Path) -> Result<(), String> {
    use std::os::unix::ffi::OsStrExt;
    let Ok(name) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
        return Ok(());
    };
    // SAFETY: `name` is a valid NUL-terminated string for the duration of the call.
    if unsafe { libc::access(name.as_ptr(), libc::W_OK | libc::X_OK) } == 0 {
        return Ok(());
    }
    let error = std::io::Error::last_os_error();
    Err(match error.raw_os_error() {
        Some(libc::EACCES) | Some(libc::EPERM) => "permission denied".into(),
        Some(libc::EROFS) => "the file system is read-only".into(),
        _ => error.to_string(),
    })
}

#[cfg(not(unix))]
fn folder_writable(_dir: &Path) -> Result<(), String> {
    Ok(())
}

/// Fails unless `value` (the option `what`) lies in `range`.
pub fn check_range(value: f32, range: RangeInclusive<f32>, what: &str) -> anyhow::Result<()> {
    if !range.contains(&value) {
        bail!(
            "{what} {value} is out of range {} to {}",
            range.start(),
            range.end()
        );
    }
    Ok(())
}

/// Checks `--res` (voxels per side) when given.
pub fn check_resolution(res: Option<u32>) -> anyhow::Result<()> {
    if let Some(res) = res
        && !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&res)
    {
        bail!(
            "resolution {res} is out of range {MIN_RESOLUTION} to {MAX_RESOLUTION} voxels per side"
        );
    }
    Ok(())
}

/// Checks `--smooth` (Gaussian sigma in voxels).
pub fn check_smoothing(sigma: f32) -> anyhow::Result<()> {
    check_range(sigma, 0.0..=MAX_SMOOTHING_SIGMA, "smoothing sigma")
}

/// `--view` of `render` and `video`: a view of one cloud, a view of two (with `--compare`), or
/// a timeline's sweep (`video`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewChoice {
    Points,
    Surface,
    Volume,
    /// A and B side by side (with --compare).
    Compare,
    /// The difference B - A (with --compare).
    Difference,
    /// The points of a timeline, swept across its years (video).
    Timeline,
}

impl ViewChoice {
    /// The view of one cloud; None for the compare's views and the timeline's sweep.
    pub fn view_kind(self) -> Option<ViewKind> {
        match self {
            ViewChoice::Points => Some(ViewKind::Points),
            ViewChoice::Surface => Some(ViewKind::Surface),
            ViewChoice::Volume => Some(ViewKind::Volume),
            ViewChoice::Compare | ViewChoice::Difference | ViewChoice::Timeline => None,
        }
    }

    /// Whether it is one of the views of `--compare`.
    pub fn compares(self) -> bool {
        matches!(self, ViewChoice::Compare | ViewChoice::Difference)
    }
}

/// Checks `--iso`.
pub fn check_iso(iso: f32) -> anyhow::Result<f32> {
    if !iso.is_finite() {
        bail!("isovalue {iso} is not a number in [0, 1]");
    }
    if !(0.0..=1.0).contains(&iso) {
        bail!("isovalue {iso} is outside [0, 1] (the density is normalized)");
    }
    Ok(iso)
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

/// `--size WxH` as clap parses it ([`parse_size`]'s message when it is not one).
pub fn size_arg(text: &str) -> Result<(u32, u32), String> {
    parse_size(text).map_err(|e| format!("{e:#}"))
}

/// `--camera AZ,EL,DIST` (render) or `--camera-at` (video) as clap parses it: the camera at
/// those angles and distance ([`parse_camera`]'s message when it is not one).
pub fn camera_arg(text: &str) -> Result<Camera, String> {
    let (azimuth, elevation, distance) = parse_camera(text).map_err(|e| format!("{e:#}"))?;
    Ok(Camera::from_angles(azimuth, elevation, distance))
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

    #[test]
    fn output_extensions_are_listed() {
        assert!(check_extension(Path::new("a.PNG"), &["png"]).is_ok());
        let error = check_extension(Path::new("a.jpg"), &["png"]).unwrap_err();
        assert_eq!(
            error.to_string(),
            "a.jpg: cannot write this file type; supported: .png"
        );
        assert!(check_extension(Path::new("a"), &["ply", "obj"]).is_err());
    }
}
