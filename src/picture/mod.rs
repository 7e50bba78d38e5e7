//! Pictures of the 3D view without a window: the same passes as the window, rendered offscreen
//! at any size, read back, with the axis labels and the legend (colour key, the song's or
//! timeline's name; `annotate`) drawn over them on the CPU, saved as PNG through a temporary
//! file and a rename (so a reader never sees half a file). `loudscape render`, `video`, compare
//! pictures ([`compare`]) and the window's Save PNG draw through here; nothing here knows egui.

pub mod compare;

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use thiserror::Error;

use crate::annotate::{Annotation, Rect};
use crate::data::cloud::PointCloud;
use crate::files::TempFile;
use crate::render::gpu::context::GpuContext;
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

#[derive(Debug, Error)]
pub enum ScreenshotError {
    #[error("cannot read the screenshot back from the GPU: {0}")]
    Readback(#[from] crate::render::gpu::readback::ReadbackError),
    #[error("{path}: cannot write the picture: {reason}")]
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
    submit_view(gpu, renderer, scene, view, settings)?.finish(&gpu.device, Wait::Blocking)
}

/// [`render_view`] up to the GPU: the view rendered and its read-back submitted, with the
/// labels and the legend to draw over it once read ([`PendingPicture::finish`]).
pub fn submit_view(
    gpu: &GpuContext,
    renderer: &Renderer,
    scene: Option<(&PointCloud, &SceneData)>,
    view: &FrameView,
    settings: &RenderSettings,
) -> Result<PendingPicture, ScreenshotError> {
    let mut view = *view;
    view.moving = false;
    let target = crate::render::headless::render_frame(
        gpu,
        renderer,
        scene.map(|(_, data)| data),
        &view,
        settings,
    );
    let shapes = match scene {
        Some((cloud, data)) => {
            let what = Overlay {
                labels: settings.show_box,
                legend: true,
            };
            overlay(&view, cloud, data, settings, what)
        }
        None => Annotation::default(),
    };
    let mut picture = PendingPicture::new(target.width, target.height, image::Rgba([0; 4]));
    picture.add(gpu, &target, 0, shapes)?;
    Ok(picture)
}

/// A picture rendered on the GPU whose read-back copies are submitted but not waited for:
/// [`PendingPicture::finish`] waits for them (on any thread), draws each part's overlay on the
/// CPU and puts the parts side by side. Every picture here is one, finished at once; the
/// window's Save PNG finishes it on a thread, so the window keeps drawing meanwhile.
pub struct PendingPicture {
    width: u32,
    height: u32,
    /// What shows where no part lies (the compare's gap).
    background: image::Rgba<u8>,
    parts: Vec<PendingPart>,
}

/// One rendered target of a [`PendingPicture`], its copy in flight.
struct PendingPart {
    reader: crate::render::gpu::target::TargetReader,
    index: wgpu::SubmissionIndex,
    width: u32,
    height: u32,
    /// Its left edge in the picture.
    x: u32,
    overlay: Annotation,
}

/// How [`PendingPicture::finish`] waits for the GPU.
pub enum Wait {
    /// A blocking poll of the device (a command, a test).
    Blocking,
    /// Polling without blocking the device, a millisecond apart, with its queue: from a thread
    /// beside a window, whose frames' submissions a blocking wait would hold up.
    Polling(wgpu::Queue),
}

impl PendingPicture {
    /// A `width` x `height` picture without parts yet, `background` where none lies.
    pub fn new(width: u32, height: u32, background: image::Rgba<u8>) -> Self {
        Self {
            width,
            height,
            background,
            parts: Vec::new(),
        }
    }

    /// Submits the copy of `target` (rendered and submitted) into the picture at `x`, with
    /// `overlay` to draw over it once read.
    pub fn add(
        &mut self,
        gpu: &GpuContext,
        target: &crate::render::gpu::target::RenderTarget,
        x: u32,
        overlay: Annotation,
    ) -> Result<(), ScreenshotError> {
        let reader = crate::render::gpu::target::TargetReader::new(&gpu.device, target);
        let index = reader.submit_copy(&gpu.device, &gpu.queue, target)?;
        self.parts.push(PendingPart {
            reader,
            index,
            width: target.width,
            height: target.height,
            x,
            overlay,
        });
        Ok(())
    }

    /// The picture's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Waits for the copies, draws each part's overlay and returns the picture.
    pub fn finish(
        self,
        device: &wgpu::Device,
        wait: Wait,
    ) -> Result<image::RgbaImage, ScreenshotError> {
        if let Wait::Polling(queue) = &wait {
            crate::render::surface::driver::wait_polling(device, queue).map_err(|e| {
                crate::render::gpu::readback::ReadbackError::Map {
                    what: "the rendered image".into(),
                    reason: e.to_string(),
                }
            })?;
        }
        let whole_part =
            |p: &PendingPart| p.x == 0 && (p.width, p.height) == (self.width, self.height);
        let mut picture = None;
        let single = self.parts.len() == 1 && whole_part(&self.parts[0]);
        for part in self.parts {
            let mut pixels = vec![0; part.width as usize * part.height as usize * 4];
            part.reader.finish_into(device, part.index, &mut pixels)?;
            let mut image = image::RgbaImage::from_raw(part.width, part.height, pixels)
                .ok_or_else(|| crate::render::gpu::readback::ReadbackError::Map {
                    what: "the rendered image".into(),
                    reason: "its size does not match the target's".into(),
                })?;
            crate::annotate::raster::draw(&mut image, &part.overlay.shapes, 1.0);
            if single {
                return Ok(image);
            }
            let whole = picture.get_or_insert_with(|| {
                image::RgbaImage::from_pixel(self.width, self.height, self.background)
            });
            image::imageops::replace(whole, &image, i64::from(part.x), 0);
        }
        Ok(picture.unwrap_or_else(|| {
            image::RgbaImage::from_pixel(self.width, self.height, self.background)
        }))
    }
}

/// What is drawn over a headless picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overlay {
    /// Axis tick labels and titles.
    pub labels: bool,
    /// The colour key and the name (`annotate::legend::layout`).
    pub legend: bool,
}

/// The axis labels and the legend of `cloud`, as `settings` show it, laid out over a picture
/// of `view` (one point a pixel), in the ink of the settings' background.
pub fn overlay(
    view: &FrameView,
    cloud: &PointCloud,
    data: &SceneData,
    settings: &RenderSettings,
    overlay: Overlay,
) -> Annotation {
    let rect = whole(view.width, view.height);
    let legend = if overlay.legend {
        let legend = crate::annotate::legend::picture_legend(cloud, settings);
        crate::annotate::legend::layout(rect, &legend)
    } else {
        Annotation::default()
    };
    let labels = overlay
        .labels
        .then(|| crate::annotate::axes::axis_labels(cloud, data));
    crate::annotate::overlay::labels_and_legend(
        rect,
        view,
        labels.as_ref(),
        settings.colours.background,
        legend,
    )
}

/// Draws [`overlay`] over `image`, a picture of `view`.
pub fn draw_overlay(
    image: &mut image::RgbaImage,
    view: &FrameView,
    cloud: &PointCloud,
    data: &SceneData,
    settings: &RenderSettings,
    overlay: Overlay,
) {
    if !overlay.labels && !overlay.legend {
        return;
    }
    let shapes = self::overlay(view, cloud, data, settings, overlay);
    crate::annotate::raster::draw(image, &shapes.shapes, 1.0);
}

/// The whole of a `width` x `height` picture, in points of one pixel.
pub fn whole(width: u32, height: u32) -> Rect {
    Rect::from_min_size([0.0, 0.0], [width as f32, height as f32])
}

/// Writes `image` to `path` as PNG: first to `PATH.partial` beside it, then renamed; the partial
/// file is removed on every error path and on SIGTERM/SIGINT (see [`crate::files::TempFile`]).
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<(), ScreenshotError> {
    let write_error = |reason: String| ScreenshotError::Write {
        path: path.to_path_buf(),
        reason,
    };
    // A full disk reads as such, however the encoder put it.
    let io_error = |e: std::io::Error| write_error(crate::files::write_reason(&e));
    let mut tmp = TempFile::create(path, ".partial").map_err(io_error)?;
    {
        let mut out = std::io::BufWriter::new(tmp.file());
        image
            .write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| match e {
                image::ImageError::IoError(e) => io_error(e),
                e => write_error(e.to_string()),
            })?;
        std::io::Write::flush(&mut out).map_err(io_error)?;
    }
    tmp.persist(path).map_err(io_error)
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
