//! Screenshots of the 3D view: the same passes as the window, rendered offscreen at any size with
//! the axis labels drawn over them, saved as PNG through a temporary file and a rename (so a
//! reader never sees half a file).

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use thiserror::Error;

use crate::data::cloud::PointCloud;
use crate::files::TempFile;
use crate::render::gpu::context::GpuContext;
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

#[derive(Debug, Error)]
pub enum ScreenshotError {
    #[error("cannot read the screenshot back from the GPU: {0}")]
    Readback(#[from] crate::render::gpu::readback::ReadbackError),
    #[error("{path}: cannot write the screenshot: {reason}")]
    Write { path: PathBuf, reason: String },
}

/// Renders the view (labels included when the settings show the box) and reads it back.
pub fn render_view(
    gpu: &GpuContext,
    renderer: &Renderer,
    scene: Option<(&PointCloud, &SceneData)>,
    view: &FrameView,
    settings: &RenderSettings,
) -> Result<image::RgbaImage, ScreenshotError> {
    let mut view = *view;
    view.moving = false;
    let target = crate::render::headless::render_frame(
        gpu,
        renderer,
        scene.map(|(_, data)| data),
        &view,
        settings,
    );
    if let Some((cloud, data)) = scene
        && settings.show_box
    {
        crate::ui::labels::draw_headless(gpu, &target, &view, cloud, data);
    }
    Ok(target.read_rgba(&gpu.device, &gpu.queue)?)
}

/// Writes `image` to `path` as PNG: first to `PATH.partial` beside it, then renamed; the partial
/// file is removed on every error path and on SIGTERM/SIGINT (see [`crate::files::TempFile`]).
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<(), ScreenshotError> {
    let write_error = |reason: String| ScreenshotError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let mut tmp = TempFile::create(path, ".partial").map_err(|e| write_error(e.to_string()))?;
    {
        let mut out = std::io::BufWriter::new(tmp.file());
        image
            .write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| write_error(e.to_string()))?;
        std::io::Write::flush(&mut out).map_err(|e| write_error(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| write_error(e.to_string()))
}

/// `loudscape-20260123-142501.png` (UTC) for the given moment.
pub fn timestamped_name(now: SystemTime) -> PathBuf {
    let secs = now.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    PathBuf::from(format!(
        "loudscape-{year:04}{month:02}{day:02}-{:02}{:02}{:02}.png",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    ))
}

/// Days since 1970-01-01 to (year, month, day), proleptic Gregorian (Howard Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn names_carry_the_utc_time() {
        let t = UNIX_EPOCH + Duration::from_secs(1_700_000_000);
        assert_eq!(
            timestamped_name(t),
            PathBuf::from("loudscape-20231114-221320.png")
        );
        assert_eq!(
            timestamped_name(UNIX_EPOCH),
            PathBuf::from("loudscape-19700101-000000.png")
        );
    }
}
