//! The volume drawn progressively at rest: a coarse picture first, then the full-quality march a
//! band of rows a frame, so that no frame is one long render on a slow device.
//!
//! Reads: the scene's volume ([`SceneData`]) and the view. Writes: the view's target, every
//! frame. How: the first frame at rest renders the volume at a reduced resolution
//! ([`COARSE_DIVISOR`]) with the moving step into a small target, submitted on its own (its
//! frame uniforms are not the full view's), and scales it up into a coarse target of the view's
//! size. Every later frame marches the next band of rows at full quality into a bands target
//! (the render pass's scissor keeps the fragments to the band; the first band clears it, the
//! others load it). Each frame copies the coarse picture, then the finished rows over it, into
//! the view's target and draws the box and the markers over them (depth from the bands target).
//! When the last band is in, the bands target holds exactly what one full render's volume pass
//! writes, so the view's target holds exactly [`Renderer::render`]'s frame (tests/it/volume.rs
//! reads both back). The jitter of the ray starts is the refinement's first frame's for every
//! band, as one render has one frame index.
//!
//! [`BandSchedule`] is the scheduler (no GPU): coarse or which band a frame draws, when to start
//! over, and the rows per band, adapted from the measured time between band frames towards
//! [`TARGET_FRAME`]. On a device fast enough for the whole frame within it, the rows reach the
//! view's height and the next refinement draws the whole volume in its first frame.

use std::ops::Range;
use std::time::{Duration, Instant};

use crate::render::composite::CompositePass;
use crate::render::gpu::target::{COLOR_FORMAT, RenderTarget};
use crate::render::scene::{Recording, RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

/// The coarse first frame is this many times smaller along each side: 1/25 of the pixels, with
/// the moving step (2.5 voxels). At 4 (1/16 of the pixels) the first frame on real_5m.ply at
/// 1600x1000 took 174 ms on lavapipe at load 7 (the full render 3.6 s), over the 150 ms aimed
/// at; the copies, the upscale and the overlay are part of it (docs/PERFORMANCE.md).
pub const COARSE_DIVISOR: u32 = 5;
/// Rows in the first band before any measurement: on lavapipe a 1600x1000 volume costs about
/// 1.5-4 ms a row (docs/PERFORMANCE.md), so 48 rows are 70-190 ms.
pub const INITIAL_ROWS: u32 = 48;
/// The rows per band never fall below this (a frame slow for other reasons must not shrink the
/// bands to nothing).
pub const MIN_ROWS: u32 = 8;
/// The frame time a band aims at: egui, the copies and the present take about 100 ms of a frame
/// on lavapipe at 1600x1000, so a band gets about half of it; a drag or a click is answered
/// within one such frame.
pub const TARGET_FRAME: Duration = Duration::from_millis(200);
/// Gaps longer than this between two band frames are not a frame's time (the window waited).
const MAX_MEASURED: Duration = Duration::from_millis(1500);

/// What one frame of a refinement draws.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VolumeStep {
    /// The coarse picture (the refinement's first frame).
    Coarse,
    /// These rows at full quality.
    Band(Range<u32>),
    /// Nothing: the picture is complete.
    Done,
}

/// The band scheduler of one view. `K` is what the volume's picture depends on (the window's
/// render key without the box and the markers, which are drawn over it every frame).
#[derive(Debug)]
pub struct BandSchedule<K> {
    key: Option<K>,
    height: u32,
    /// Rows drawn at full quality so far (the bands go top to bottom).
    next: u32,
    /// Rows per band (adapted; kept from one refinement to the next).
    pub rows: u32,
    /// When the last band was recorded, to measure the frame time.
    last_band: Option<Instant>,
    /// The frame index of the refinement's first frame (the jitter of every band).
    frame_index: u32,
}

impl<K> Default for BandSchedule<K> {
    fn default() -> Self {
        Self {
            key: None,
            height: 0,
            next: 0,
            rows: INITIAL_ROWS,
            last_band: None,
            frame_index: 0,
        }
    }
}

impl<K: PartialEq + Clone> BandSchedule<K> {
    /// What a frame of `key`, `height` rows tall, at `now`, draws. A key or a height other than
    /// the refinement's starts over: with the coarse picture, unless the rows per band already
    /// cover the height (then the whole volume at once). `frame_index` is the frame's; the
    /// refinement keeps its first frame's ([`BandSchedule::frame_index`]).
    pub fn step(&mut self, key: &K, height: u32, frame_index: u32, now: Instant) -> VolumeStep {
        if self.key.as_ref() != Some(key) || self.height != height {
            self.key = Some(key.clone());
            self.height = height;
            self.last_band = None;
            self.frame_index = frame_index;
            if self.rows >= height {
                self.next = height;
                return VolumeStep::Band(0..height);
            }
            self.next = 0;
            return VolumeStep::Coarse;
        }
        if self.complete() {
            return VolumeStep::Done;
        }
        if let Some(last) = self.last_band {
            self.adapt(now.saturating_duration_since(last));
        }
        let band = self.next..self.next.saturating_add(self.rows).min(height);
        self.next = band.end;
        self.last_band = (!self.complete()).then_some(now);
        VolumeStep::Band(band)
    }

    /// Scales the rows towards [`TARGET_FRAME`] from one measured frame (at most halving or
    /// doubling them a frame, so one odd frame does not swing them).
    fn adapt(&mut self, frame: Duration) {
        if frame.is_zero() || frame > MAX_MEASURED {
            return;
        }
        let scale = (TARGET_FRAME.as_secs_f64() / frame.as_secs_f64()).clamp(0.5, 2.0);
        self.rows = ((f64::from(self.rows) * scale) as u32).clamp(MIN_ROWS, 1 << 16);
    }

    /// Every row of the current key is drawn at full quality.
    pub fn complete(&self) -> bool {
        self.key.is_some() && self.next >= self.height
    }

    /// Rows drawn at full quality so far.
    pub fn rows_done(&self) -> u32 {
        self.next
    }

    /// The frame index every band of this refinement is drawn with.
    pub fn frame_index(&self) -> u32 {
        self.frame_index
    }

    /// The fraction drawn at full quality while a refinement is under way; `None` when complete
    /// or idle.
    pub fn progress(&self) -> Option<f32> {
        (self.key.is_some() && !self.complete() && self.height > 0)
            .then(|| self.next as f32 / self.height as f32)
    }

    /// Forgets the refinement (the view shows something else, or was resized); the rows per
    /// band stay.
    pub fn reset(&mut self) {
        self.key = None;
        self.height = 0;
        self.next = 0;
        self.last_band = None;
    }
}

/// The targets of one refinement, all of the view's size but `small`.
struct Targets {
    /// The full-quality rows, cleared by the first band.
    bands: RenderTarget,
    /// The coarse picture scaled up.
    coarse: RenderTarget,
    /// The coarse picture as rendered.
    small: RenderTarget,
}

/// The GPU side: the scheduler, its targets and the pass that scales the coarse picture up.
pub struct ProgressiveVolume<K> {
    pub schedule: BandSchedule<K>,
    targets: Option<Targets>,
    upscale: Option<CompositePass>,
}

impl<K> Default for ProgressiveVolume<K> {
    fn default() -> Self {
        Self {
            schedule: BandSchedule::default(),
            targets: None,
            upscale: None,
        }
    }
}

impl<K: PartialEq + Clone> ProgressiveVolume<K> {
    /// The view shows something else now (a moving frame, another view): the refinement is
    /// forgotten, its targets kept for the next.
    pub fn set_aside(&mut self) {
        self.schedule.reset();
    }

    /// The fraction drawn at full quality while a refinement is under way.
    pub fn progress(&self) -> Option<f32> {
        self.schedule.progress()
    }

    /// Records one frame of the volume of `data` (its `key`) into `target`, at rest: the coarse
    /// picture or the next band, then the picture so far, the box and the markers. Returns
    /// whether the picture is complete (false: draw again next frame). The coarse picture is
    /// submitted through `queue` at once; the rest is recorded into `encoder`. `now` is the
    /// frame's time (the rows per band adapt to the time between band frames).
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        renderer: &Renderer,
        target: &RenderTarget,
        data: &SceneData,
        key: &K,
        view: &FrameView,
        settings: &RenderSettings,
        now: Instant,
    ) -> bool {
        let (width, height) = (target.width, target.height);
        if !self
            .targets
            .as_ref()
            .is_some_and(|t| t.bands.has_size(width, height))
        {
            let small = RenderTarget::new(
                device,
                width.div_ceil(COARSE_DIVISOR),
                height.div_ceil(COARSE_DIVISOR),
            );
            let upscale = self
                .upscale
                .get_or_insert_with(|| CompositePass::new(device, COLOR_FORMAT));
            upscale.set_source(device, &small);
            self.targets = Some(Targets {
                bands: RenderTarget::new(device, width, height),
                coarse: RenderTarget::new(device, width, height),
                small,
            });
            self.schedule.reset();
        }
        let (Some(targets), Some(upscale)) = (self.targets.as_ref(), self.upscale.as_ref()) else {
            return true;
        };
        // Only the volume goes into the refinement's targets; the box and the markers are drawn
        // over the view's target every frame.
        let mut bare = settings.clone();
        bare.markers.clear();
        bare.show_box = false;
        let step = self.schedule.step(key, height, view.frame_index, now);
        let mut band_view = *view;
        band_view.frame_index = self.schedule.frame_index();
        band_view.moving = false;
        match step {
            VolumeStep::Coarse => {
                let mut coarse = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("volume::coarse_encoder"),
                });
                let mut small_view = band_view;
                small_view.width = targets.small.width;
                small_view.height = targets.small.height;
                small_view.moving = true;
                renderer.render(
                    queue,
                    &mut coarse,
                    &targets.small,
                    Some(data),
                    &small_view,
                    &bare,
                );
                upscale_into(&mut coarse, upscale, &targets.coarse);
                // Submitted now: the frame uniforms written for the small view must not be the
                // ones the full-size passes below read (written before the next submission).
                queue.submit([coarse.finish()]);
                // The bands target starts cleared: its depth stands behind the coarse rows.
                let recording = Recording {
                    queue,
                    encoder,
                    target: &targets.bands,
                };
                renderer.render_volume_band(recording, data, &band_view, &bare, 0..0, true);
            }
            VolumeStep::Band(rows) => {
                let recording = Recording {
                    queue,
                    encoder,
                    target: &targets.bands,
                };
                let clear = rows.start == 0;
                renderer.render_volume_band(recording, data, &band_view, &bare, rows, clear);
            }
            VolumeStep::Done => {}
        }
        let done = self.schedule.rows_done().min(height);
        let whole = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        if done < height {
            encoder.copy_texture_to_texture(
                targets.coarse.color.as_image_copy(),
                target.color.as_image_copy(),
                whole,
            );
        }
        if done > 0 {
            encoder.copy_texture_to_texture(
                targets.bands.color.as_image_copy(),
                target.color.as_image_copy(),
                wgpu::Extent3d {
                    height: done,
                    ..whole
                },
            );
        }
        encoder.copy_texture_to_texture(
            targets.bands.depth.as_image_copy(),
            target.depth.as_image_copy(),
            whole,
        );
        let recording = Recording {
            queue,
            encoder,
            target,
        };
        renderer.render_overlay(recording, data, &band_view, settings, None);
        self.schedule.complete()
    }
}

/// Scales the small target's colour (the composite pass's source) up into `coarse`.
fn upscale_into(
    encoder: &mut wgpu::CommandEncoder,
    upscale: &CompositePass,
    coarse: &RenderTarget,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("volume::upscale_pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &coarse.color_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    upscale.draw(&mut pass);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs frames of `key` until complete, each `frame` after the last; returns the bands.
    fn run(
        schedule: &mut BandSchedule<u32>,
        key: u32,
        height: u32,
        t: &mut Instant,
        frame: Duration,
    ) -> Vec<Range<u32>> {
        let mut bands = Vec::new();
        loop {
            match schedule.step(&key, height, 7, *t) {
                VolumeStep::Done => return bands,
                VolumeStep::Coarse => assert!(bands.is_empty(), "coarse after a band"),
                VolumeStep::Band(rows) => bands.push(rows),
            }
            *t += frame;
            assert!(bands.len() < 10_000, "never completes");
        }
    }

    #[test]
    fn coarse_first_then_bands_cover_every_row_once() {
        let mut schedule = BandSchedule::default();
        let mut t = Instant::now();
        let height = 1000;
        assert_eq!(schedule.step(&1, height, 3, t), VolumeStep::Coarse);
        assert_eq!(schedule.progress(), Some(0.0));
        assert!(!schedule.complete());
        // Frames exactly on target: the rows stay, so 1000 / 48 bands (the last shorter).
        let bands = run(&mut schedule, 1, height, &mut t, TARGET_FRAME);
        assert_eq!(bands.len(), height.div_ceil(INITIAL_ROWS) as usize);
        assert_eq!(bands[0].start, 0);
        assert!(bands.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(bands.last().unwrap().end, height);
        assert!(bands.iter().all(|b| b.len() as u32 <= INITIAL_ROWS));
        assert!(schedule.complete());
        assert_eq!(schedule.progress(), None);
        // Every band keeps the first frame's jitter.
        assert_eq!(schedule.frame_index(), 3);
        // Complete: the same key draws nothing more.
        assert_eq!(schedule.step(&1, height, 9, t), VolumeStep::Done);
    }

    #[test]
    fn another_key_or_size_starts_over_and_set_aside_forgets() {
        let mut schedule = BandSchedule::default();
        let mut t = Instant::now();
        assert_eq!(schedule.step(&1, 500, 0, t), VolumeStep::Coarse);
        t += TARGET_FRAME;
        assert_eq!(schedule.step(&1, 500, 1, t), VolumeStep::Band(0..48));
        t += TARGET_FRAME;
        assert_eq!(schedule.step(&1, 500, 2, t), VolumeStep::Band(48..96));
        // The camera moved (another key): coarse again, from row 0.
        t += TARGET_FRAME;
        assert_eq!(schedule.step(&2, 500, 3, t), VolumeStep::Coarse);
        t += TARGET_FRAME;
        assert_eq!(schedule.step(&2, 500, 4, t), VolumeStep::Band(0..48));
        assert_eq!(schedule.frame_index(), 3);
        // Resized.
        t += TARGET_FRAME;
        assert_eq!(schedule.step(&2, 400, 5, t), VolumeStep::Coarse);
        schedule.reset();
        assert_eq!(schedule.progress(), None);
        assert_eq!(schedule.step(&2, 400, 6, t), VolumeStep::Coarse);
    }

    #[test]
    fn the_rows_follow_the_measured_frame_time() {
        let mut schedule = BandSchedule::default();
        let mut t = Instant::now();
        let height = 100_000;
        schedule.step(&1, height, 0, t);
        // The coarse frame is not a band's time: the first band keeps the initial rows.
        t += 4 * TARGET_FRAME;
        assert_eq!(
            schedule.step(&1, height, 0, t),
            VolumeStep::Band(0..INITIAL_ROWS)
        );
        // A slow device: frames of four times the target halve the rows, down to the floor.
        for _ in 0..10 {
            t += 4 * TARGET_FRAME;
            schedule.step(&1, height, 0, t);
        }
        assert_eq!(schedule.rows, MIN_ROWS);
        // A fast one: short frames double them each frame.
        t += Duration::from_millis(5);
        schedule.step(&1, height, 0, t);
        assert_eq!(schedule.rows, 2 * MIN_ROWS);
        // A long gap (the window waited) is not a frame time.
        t += Duration::from_secs(5);
        schedule.step(&1, height, 0, t);
        assert_eq!(schedule.rows, 2 * MIN_ROWS);
    }

    #[test]
    fn a_fast_device_draws_the_whole_volume_in_one_frame_after_learning() {
        let mut schedule = BandSchedule::default();
        let mut t = Instant::now();
        let height = 1000;
        // 16 ms frames: the rows double every band (48, 96, 192, 384, then the 280 left).
        let bands = run(&mut schedule, 1, height, &mut t, Duration::from_millis(16));
        assert_eq!(bands.len(), 5, "{bands:?}");
        // The next refinement (the camera moved) needs two bands, by then a band covers it all.
        let bands = run(&mut schedule, 2, height, &mut t, Duration::from_millis(16));
        assert_eq!(bands.len(), 2, "{bands:?}");
        assert!(schedule.rows >= height, "rows {}", schedule.rows);
        // And the one after draws every row in its first frame, with no coarse picture.
        assert_eq!(schedule.step(&3, height, 1, t), VolumeStep::Band(0..height));
        assert!(schedule.complete());
        assert_eq!(schedule.step(&3, height, 2, t), VolumeStep::Done);
    }
}
