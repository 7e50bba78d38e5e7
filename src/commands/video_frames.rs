//! A video's frames from the GPU to ffmpeg, in two stages that overlap: the command's thread
//! renders frame k+1 and reads it back (two targets in turn: frame k+1 is read once frame k+2
//! is submitted) while a second thread finishes frame k (the labels and legend over it, the
//! loudness strip under it) and writes it to the encoder.
//!
//! Nothing is allocated per frame: the two targets and their staging buffers are the
//! command's, and a few frame buffers go round between the stages. Labels that stay put (a still
//! camera) are laid out and rasterized once ([`raster::Prepared`]) and painted over every frame,
//! to the same pixels as drawing them afresh.

use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

use anyhow::{Context, anyhow};
use loudscape::annotate::strip::{LoudnessStrip, STRIP_HEIGHT, x_of_time};
use loudscape::annotate::{Rect, Shape, raster};

use super::video_encode::{Encoder, Progress};

/// Frame buffers in flight: one being rendered, one being read back, one being finished, one
/// in the pipe's wait.
const BUFFERS: usize = 4;

/// The loudness strip under the view: its picture (without a playhead) and where its playhead
/// goes.
pub struct StripLayer {
    pub strip: LoudnessStrip,
    pub image: image::RgbaImage,
}

/// What the second stage needs to know of every frame.
pub struct Layout {
    pub width: u32,
    pub view_height: u32,
    pub strip: Option<StripLayer>,
}

impl Layout {
    /// Bytes of a whole frame (view and strip).
    pub fn frame_bytes(&self) -> usize {
        let strip = self.strip.as_ref().map_or(0, |s| s.image.height());
        self.width as usize * (self.view_height + strip) as usize * 4
    }

    /// Bytes of the view at the top of a frame.
    pub fn view_bytes(&self) -> usize {
        self.width as usize * self.view_height as usize * 4
    }
}

/// A frame rendered and read back into the top of `pixels`, with what goes over it (in pixels)
/// and its moment `t` in seconds (the strip's playhead).
pub struct Rendered {
    pub pixels: Vec<u8>,
    pub overlay: Vec<Shape>,
    pub t: f64,
}

enum Job {
    Frame(Rendered),
    /// Every frame was sent: close the file.
    Finish,
}

/// The first stage's end of the pipeline.
pub struct Frames {
    jobs: Option<SyncSender<Job>>,
    buffers: Receiver<Vec<u8>>,
}

impl Frames {
    /// A frame buffer to render into (`Layout::frame_bytes` long); `None` when the second
    /// stage has stopped (its error says why).
    pub fn buffer(&self) -> Option<Vec<u8>> {
        self.buffers.recv().ok()
    }

    /// Hands a rendered frame on; false when the second stage has stopped.
    pub fn send(&self, frame: Rendered) -> bool {
        self.jobs
            .as_ref()
            .is_some_and(|jobs| jobs.send(Job::Frame(frame)).is_ok())
    }

    /// Every frame was sent: the file may be closed.
    pub fn finish(mut self) {
        if let Some(jobs) = self.jobs.take() {
            let _ = jobs.send(Job::Finish);
        }
    }
}

/// Runs `render` (the first stage, on this thread) against a second stage that finishes and
/// encodes each frame in order, then closes the file. A failure in either stage stops both; the
/// encoder's temporary file goes, and the first failure is the error.
pub fn run(
    layout: Layout,
    encoder: Encoder,
    progress: Progress,
    render: impl FnOnce(&Frames) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let (job_sender, jobs) = sync_channel(1);
    let (buffer_sender, buffers) = channel();
    for _ in 0..BUFFERS {
        let _ = buffer_sender.send(vec![0; layout.frame_bytes()]);
    }
    let frames = Frames {
        jobs: Some(job_sender),
        buffers,
    };
    std::thread::scope(|scope| {
        let finisher = std::thread::Builder::new()
            .name("video frames".into())
            .spawn_scoped(scope, move || {
                finish_frames(&layout, encoder, progress, jobs, buffer_sender)
            })
            .context("starting the video's encoding thread")?;
        let rendered = render(&frames);
        if rendered.is_ok() {
            frames.finish();
        } else {
            drop(frames);
        }
        let finished = finisher
            .join()
            .unwrap_or_else(|_| Err(anyhow!("internal: the video's encoding thread panicked")));
        match (rendered, finished) {
            // The second stage stopped first: the renderer only saw its channel close.
            (Err(_), Err(e)) | (Ok(()), Err(e)) => Err(e),
            (Err(e), Ok(())) => Err(e),
            (Ok(()), Ok(())) => Ok(()),
        }
    })
}

/// The second stage: the overlay and the strip onto each frame, into the encoder, in order.
fn finish_frames(
    layout: &Layout,
    mut encoder: Encoder,
    mut progress: Progress,
    jobs: Receiver<Job>,
    buffers: Sender<Vec<u8>>,
) -> anyhow::Result<()> {
    let mut overlay = OverlayCache::default();
    let mut done = 0;
    let result = loop {
        match jobs.recv() {
            Ok(Job::Frame(mut frame)) => {
                let view = &mut frame.pixels[..layout.view_bytes()];
                overlay.paint(view, &frame.overlay, layout.width, layout.view_height);
                if let Some(strip) = &layout.strip {
                    put_strip(
                        &mut frame.pixels[layout.view_bytes()..],
                        layout.width,
                        strip,
                        frame.t,
                    );
                }
                if let Err(e) = encoder.push(&frame.pixels) {
                    break Err(e);
                }
                done += 1;
                progress.frame(done);
                // The first stage may have stopped; the buffer is then not wanted.
                let _ = buffers.send(frame.pixels);
            }
            Ok(Job::Finish) => break encoder.finish(),
            // The first stage stopped with an error of its own: the encoder's drop removes
            // the unfinished file.
            Err(_) => break Err(anyhow!("the video was not finished")),
        }
    };
    if result.is_err() {
        progress.abandon();
    }
    result
}

/// The last overlay laid out, kept while frames ask for the same shapes.
#[derive(Default)]
struct OverlayCache {
    shapes: Vec<Shape>,
    prepared: Option<raster::Prepared>,
}

impl OverlayCache {
    fn paint(&mut self, rgba: &mut [u8], shapes: &[Shape], width: u32, height: u32) {
        if self.prepared.is_none() || self.shapes != shapes {
            self.prepared = raster::Prepared::new(shapes, 1.0, width, height);
            self.shapes = shapes.to_vec();
        }
        if let Some(prepared) = &mut self.prepared {
            prepared.paint(rgba);
        }
    }
}

/// The strip's picture into `rgba` (the frame's rows under the view), with its playhead at `t`
/// seconds: a white line two points wide down the plot.
fn put_strip(rgba: &mut [u8], width: u32, strip: &StripLayer, t: f64) {
    rgba.copy_from_slice(strip.image.as_raw());
    let sh = strip.image.height();
    // The strip was painted in points, STRIP_HEIGHT tall; back to pixels.
    let ppp = sh as f32 / STRIP_HEIGHT;
    let rect = Rect::from_min_size([0.0, 0.0], [width as f32 / ppp, STRIP_HEIGHT]);
    let plot = LoudnessStrip::plot_rect(rect);
    let plot = Rect::from_min_max(
        [plot.left() * ppp, plot.top() * ppp],
        [plot.right() * ppp, plot.bottom() * ppp],
    );
    let x = x_of_time(t, plot.left(), plot.right(), strip.strip.duration_s());
    let half_width = 0.75 * ppp;
    let (x0, x1) = (
        (x - half_width).floor().max(0.0) as usize,
        ((x + half_width).ceil() as usize).min(width as usize),
    );
    let rows = (plot.bottom().ceil() as usize).min(sh as usize);
    for row in rgba.chunks_exact_mut(width as usize * 4).take(rows) {
        if x0 < x1 {
            row[x0 * 4..x1 * 4].fill(255);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loudscape::annotate::{Anchor, Annotation, Text};

    fn labels() -> Vec<Shape> {
        let mut a = Annotation::default();
        a.fill(
            Rect::from_min_size([4.0, 4.0], [30.0, 12.0]),
            3.0,
            [20, 20, 20, 200],
        );
        a.text(Text::new(
            "-14 LUFS",
            [6.0, 4.0],
            Anchor::LEFT_TOP,
            11.0,
            [255; 4],
        ));
        a.shapes
    }

    fn picture(seed: u8) -> image::RgbaImage {
        image::RgbaImage::from_fn(64, 24, |x, y| {
            image::Rgba([seed.wrapping_mul(x as u8), y as u8 * 9, seed, 255])
        })
    }

    #[test]
    fn the_kept_overlay_paints_what_drawing_it_afresh_does_on_every_frame() {
        let shapes = labels();
        let mut cache = OverlayCache::default();
        for seed in [3u8, 90, 200] {
            let mut drawn = picture(seed);
            raster::draw(&mut drawn, &shapes, 1.0);
            let mut kept = picture(seed);
            cache.paint(kept.as_mut(), &shapes, 64, 24);
            assert_eq!(drawn, kept, "frame over picture {seed}");
            assert_ne!(drawn, picture(seed), "the labels were drawn");
        }
        // New shapes are laid out anew, not the kept ones painted.
        let mut moved = shapes.clone();
        if let Shape::Fill { rect, .. } = &mut moved[0] {
            *rect = Rect::from_min_size([30.0, 8.0], [30.0, 12.0]);
        }
        let mut drawn = picture(7);
        raster::draw(&mut drawn, &moved, 1.0);
        let mut kept = picture(7);
        cache.paint(kept.as_mut(), &moved, 64, 24);
        assert_eq!(drawn, kept);
    }

    #[test]
    fn the_strips_playhead_is_white_down_the_plot_and_moves_with_time() {
        let width = 320;
        let height = 118;
        let image = image::RgbaImage::from_pixel(width, height, image::Rgba([10, 20, 30, 255]));
        let demo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
        let cloud = crate::commands::args::load_cloud(&demo).expect("the demo song");
        let strip = LoudnessStrip::for_cloud(&cloud).expect("the demo song's strip");
        let layer = StripLayer { strip, image };
        let white_columns = |t: f64| {
            let mut rgba = vec![0u8; (width * height * 4) as usize];
            put_strip(&mut rgba, width, &layer, t);
            let frame = image::RgbaImage::from_raw(width, height, rgba).unwrap();
            (0..width)
                .filter(|&x| frame.get_pixel(x, height / 2).0 == [255; 4])
                .collect::<Vec<_>>()
        };
        let start = white_columns(0.0);
        let end = white_columns(layer.strip.duration_s());
        assert!(!start.is_empty() && start.len() <= 4, "{start:?}");
        assert!(end[0] > start[0] + width / 2, "{start:?} then {end:?}");
    }
}
