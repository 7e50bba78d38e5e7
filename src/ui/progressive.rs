//! Progressive points in the window: at rest, a cloud too large to draw in one frame is drawn a
//! slice a frame (`Renderer::render_points_slice`) into a target of its own, and every frame
//! copies what that target holds into the view's target and draws the box and the markers over
//! it (`Renderer::render_overlay`). So the window never stalls for a whole cloud, the picture
//! fills in over a few frames, and a playhead moving during playback only redraws the markers:
//! it neither restarts the refinement nor, once complete, redraws a point.
//!
//! [`Refine`] is the scheduler (no GPU): which slice a frame draws, when to start over, and the
//! per-frame point budget, adapted from the measured time between refining frames.

use std::ops::Range;
use std::time::{Duration, Instant};

use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{Recording, Renderer, SceneData};
use crate::ui::frame_cache::RenderKey;
use crate::view::frame_view::FrameView;

/// Points drawn in the first slice before any measurement: about what lavapipe draws in 55 ms
/// at 1280x720 (5.3 M points in ~1.5 s, one submission, docs/PERFORMANCE.md).
pub const INITIAL_BUDGET: u64 = 200_000;
/// The frame time a slice aims at while refining at rest (the window answers within it). At
/// 30 ms with a 100,000-point floor a 3.5 M-point song took 4.5-6 s to fill in on lavapipe, most
/// of each ~0.13 s frame not the points (egui, the copy, the present); the sparse stand-in for
/// the points not drawn yet keeps the picture whole meanwhile, so the slices can be longer.
/// At 60 ms the frame's own cost (egui, the copy, the present: about 100 ms on lavapipe) held
/// the budget at its floor, so half of each frame was not points and the same song took 4.8 s;
/// at 150 ms it took 2.6 s (bench/bench_window.py, docs/PERFORMANCE.md). A frame this long is
/// only taken at rest, where the picture is still: a drag or a hover is answered in the next.
/// This is the aim while the user's hand is on the window ([`IDLE_TARGET_FRAME`] otherwise).
pub const TARGET_FRAME: Duration = Duration::from_millis(150);
/// The frame time a slice aims at while refining with no input for a while
/// ([`HAND_WINDOW`]): nobody is waiting for a hover's read-out or a key, so more of each frame
/// goes to points and less to the frame's own cost. The settle after an orbit of a 3.53 M-point
/// song on lavapipe: 3.08 s at 150 ms, 1.39 s at 300 ms (bench/bench_window.py, alternated
/// runs, docs/PERFORMANCE.md). The A/B compare's frames at rest aim at 250 ms likewise.
pub const IDLE_TARGET_FRAME: Duration = Duration::from_millis(300);
/// How long after the last pointer motion, press, scroll or key the slices keep to
/// [`TARGET_FRAME`].
pub const HAND_WINDOW: Duration = Duration::from_millis(800);

/// The frame time a refining frame at `now` aims at, the last input having come at `last_input`.
pub fn target_frame(last_input: Option<Instant>, now: Instant) -> Duration {
    match last_input {
        Some(t) if now.saturating_duration_since(t) < HAND_WINDOW => TARGET_FRAME,
        _ => IDLE_TARGET_FRAME,
    }
}
/// The budget never falls below the measured one: a frame slow for other reasons (egui, the
/// composite, a loaded machine) must not shrink the slices to nothing (with a 20,000 floor a
/// 4.4 M-point cloud needed about 20 s to fill in on lavapipe, most of each frame not points).
pub const MIN_BUDGET: u64 = INITIAL_BUDGET;
/// Gaps longer than this between two refining frames are not a frame's time (the window was
/// hidden or waited for input): they do not adapt the budget.
const MAX_MEASURED: Duration = Duration::from_millis(500);

/// `budget` scaled towards the frame time `target` from one measured `frame` (at most halved
/// or doubled, so one odd frame does not swing it; never below `floor`: [`MIN_BUDGET`] for the
/// single view, the A/B compare's own for its frames, which cost more besides their points:
/// `ui/compare_refine.rs`). A frame of no time or longer than [`MAX_MEASURED`] is no measure:
/// `budget` as it was.
pub fn adapted_towards(budget: u64, frame: Duration, target: Duration, floor: u64) -> u64 {
    if frame.is_zero() || frame > MAX_MEASURED {
        return budget;
    }
    let scale = (target.as_secs_f64() / frame.as_secs_f64()).clamp(0.5, 2.0);
    ((budget as f64 * scale) as u64).max(floor)
}

/// The slice scheduler of one view.
#[derive(Debug)]
pub struct Refine {
    /// The scene the points target holds or is filling: the render key without what the
    /// overlay draws (markers, box), so that a playhead change keeps the slices drawn.
    key: Option<RenderKey>,
    /// Points of the cloud drawn so far into the points target.
    next: u64,
    total: u64,
    /// Points per slice (adapted).
    pub budget: u64,
    /// The frame time the budget adapts towards ([`target_frame`]; [`TARGET_FRAME`] unless set).
    pub target: Duration,
    /// When the last slice was recorded, to measure the frame time.
    last_slice: Option<Instant>,
}

impl Default for Refine {
    fn default() -> Self {
        Self {
            key: None,
            next: 0,
            total: 0,
            budget: INITIAL_BUDGET,
            target: TARGET_FRAME,
            last_slice: None,
        }
    }
}

/// The part of `key` the points depend on: markers and the box are drawn over them, the view
/// kind and the surface's settings do not change the points (a Surface view draws the points
/// while its grid is built), and of the GPU data only the points' revision counts (a grid or a
/// surface built for another view leaves them as they are).
pub fn points_key(key: &RenderKey) -> RenderKey {
    let mut key = key.clone();
    key.settings.markers.clear();
    key.settings.show_box = false;
    key.settings.view = crate::render::scene::ViewKind::Points;
    key.settings.surface = Default::default();
    key.revision = 0;
    key
}

/// How many completed points pictures are kept besides the one shown, for views the window
/// comes back to (R after an orbit, the Points view after a look at the Surface).
pub const KEPT: usize = 2;

impl Refine {
    /// Whether a frame at rest showing `total` points goes the progressive way: the cloud is
    /// larger than one frame's budget, or a refinement of it is under way.
    pub fn wants(&self, total: u64) -> bool {
        total > self.budget || self.under_way(total)
    }

    /// Whether a refinement of a cloud of `total` points is under way (started, not complete).
    pub fn under_way(&self, total: u64) -> bool {
        self.key.is_some() && self.total == total && !self.complete()
    }

    /// Points drawn into the points target and the cloud's total (none before a first slice).
    pub fn drawn(&self) -> (u64, u64) {
        if self.key.is_some() {
            (self.next.min(self.total), self.total)
        } else {
            (0, 0)
        }
    }

    /// The slice a frame of `key` (at rest, `total` points) draws into the points target now,
    /// or `None` when the target already holds all of them. A key whose points differ from
    /// the target's (camera, size, style, cloud, GPU data) starts over from point 0; one that
    /// differs only in markers or the box continues. `now` is the frame's time.
    pub fn step(&mut self, key: &RenderKey, total: u64, now: Instant) -> Option<Range<u64>> {
        if self.begin(key, total) {
            return None;
        }
        if let Some(last) = self.last_slice {
            let frame = now.saturating_duration_since(last);
            self.budget = adapted_towards(self.budget, frame, self.target, MIN_BUDGET);
        }
        let range = self.slice(self.budget);
        self.last_slice = (!self.complete()).then_some(now);
        Some(range)
    }

    /// As [`Refine::step`], with the slice's size given (`points`, at least one) by a budget
    /// shared with other views ([`crate::ui::compare_refine`]) instead of this one's own.
    pub fn step_granted(&mut self, key: &RenderKey, total: u64, points: u64) -> Option<Range<u64>> {
        if self.begin(key, total) {
            return None;
        }
        self.last_slice = None;
        Some(self.slice(points.max(1)))
    }

    /// The points a frame of `key` (`total` points) still has to draw: all of them when the
    /// target holds other points, none when it holds them all.
    pub fn remaining(&self, key: &RenderKey, total: u64) -> u64 {
        if self.holds(&points_key(key), total) {
            total.saturating_sub(self.next)
        } else {
            total
        }
    }

    /// Starts over when `key`'s points are not the ones the target holds or fills; true when
    /// it holds them all already (no slice to draw).
    fn begin(&mut self, key: &RenderKey, total: u64) -> bool {
        let points = points_key(key);
        if self.key.as_ref() != Some(&points) || self.total != total {
            self.key = Some(points);
            self.next = 0;
            self.total = total;
            self.last_slice = None;
            return false;
        }
        self.complete()
    }

    /// The next `points` points (fewer at the end of the cloud), marked drawn.
    fn slice(&mut self, points: u64) -> Range<u64> {
        let range = self.next..(self.next + points).min(self.total);
        self.next = range.end;
        range
    }

    /// All points of the current key are in the points target.
    pub fn complete(&self) -> bool {
        self.next >= self.total
    }

    /// The fraction drawn while a refinement is under way; `None` when complete or idle.
    pub fn progress(&self) -> Option<f32> {
        (self.key.is_some() && !self.complete() && self.total > 0)
            .then(|| self.next as f32 / self.total as f32)
    }

    /// Whether the points target holds (or is filling) the points of `points` (a
    /// [`points_key`]).
    fn holds(&self, points: &RenderKey, total: u64) -> bool {
        self.key.as_ref() == Some(points) && self.total == total
    }

    /// The points target now holds all `total` points of `points` (a [`points_key`]: a kept
    /// picture put back).
    fn adopt(&mut self, points: RenderKey, total: u64) {
        self.key = Some(points);
        self.next = total;
        self.total = total;
        self.last_slice = None;
    }

    /// The first point no slice has drawn yet, while a refinement is under way.
    pub fn rest_from(&self) -> Option<u64> {
        (self.key.is_some() && !self.complete()).then_some(self.next)
    }

    /// Forgets the points target (resized, or shown something else in between).
    pub fn reset(&mut self) {
        self.key = None;
        self.next = 0;
        self.total = 0;
        self.last_slice = None;
    }
}

/// The GPU side: the points target, its scheduler, and up to [`KEPT`] completed pictures.
#[derive(Default)]
pub struct ProgressivePoints {
    target: Option<RenderTarget>,
    pub refine: Refine,
    /// Completed points pictures, the most recent last.
    kept: Vec<Kept>,
    /// The last picture to leave `kept`, reused as the next fresh target of its size.
    spare: Option<RenderTarget>,
}

/// The device, queue, frame encoder and renderer a progressive frame records with.
pub type Gpu<'a, 'e> = (
    &'a wgpu::Device,
    &'a wgpu::Queue,
    &'e mut wgpu::CommandEncoder,
    &'a Renderer,
);

/// A completed points picture: the points key and count it holds.
struct Kept {
    key: RenderKey,
    total: u64,
    target: RenderTarget,
}

impl ProgressivePoints {
    /// The view shows something else now (a moving frame, a surface): a complete picture is
    /// kept for a return to its view, an incomplete one forgotten.
    pub fn set_aside(&mut self) {
        self.keep_current();
        self.refine.reset();
    }

    /// How many completed pictures are kept (for the tests).
    pub fn kept(&self) -> usize {
        self.kept.len()
    }

    /// Moves a complete current picture into `kept` (the oldest leaves past [`KEPT`]).
    fn keep_current(&mut self) {
        if let (Some(key), true) = (self.refine.key.clone(), self.refine.complete())
            && self.target.is_some()
        {
            let total = self.refine.total;
            self.kept.retain(|k| !(k.key == key && k.total == total));
            if let Some(target) = self.target.take() {
                self.kept.push(Kept { key, total, target });
            }
            if self.kept.len() > KEPT {
                self.spare = Some(self.kept.remove(0).target);
            }
        }
    }

    /// Makes the points target the one for `key` at `w` x `h`: the current one when it holds
    /// `key`'s points; else a kept picture of them, complete at once; else a fresh target to
    /// refine (the current one is kept if complete).
    fn target_for(&mut self, device: &wgpu::Device, key: &RenderKey, total: u64, w: u32, h: u32) {
        self.kept.retain(|k| k.target.has_size(w, h));
        if !self.target.as_ref().is_some_and(|t| t.has_size(w, h)) {
            self.target = None;
            self.refine.reset();
        }
        let wanted = points_key(key);
        if self.target.is_some() && self.refine.holds(&wanted, total) {
            return;
        }
        self.keep_current();
        if let Some(i) = self
            .kept
            .iter()
            .position(|k| k.key == wanted && k.total == total)
        {
            self.target = Some(self.kept.remove(i).target);
            self.refine.adopt(wanted, total);
            return;
        }
        if self.target.is_none() {
            let spare = self.spare.take().filter(|t| t.has_size(w, h));
            self.target = Some(spare.unwrap_or_else(|| RenderTarget::new(device, w, h)));
        }
        self.refine.reset();
    }

    /// Records one progressive frame of `key` into `target`: the next slice (if any) into the
    /// points target, then its copy and the overlay into `target`. Returns whether the picture
    /// is complete (false: draw again next frame).
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        renderer: &Renderer,
        target: &RenderTarget,
        data: &SceneData,
        key: &RenderKey,
        view: &FrameView,
        settings: &crate::render::scene::RenderSettings,
    ) -> bool {
        let gpu = (device, queue, encoder, renderer);
        self.record(gpu, target, data, key, view, settings, None)
    }

    /// As [`ProgressivePoints::frame`], the slice `points` long at most (a share of a budget
    /// shared with other views, `ui/compare_refine.rs`) instead of this view's own budget.
    #[allow(clippy::too_many_arguments)]
    pub fn frame_granted(
        &mut self,
        gpu: Gpu<'_, '_>,
        target: &RenderTarget,
        data: &SceneData,
        key: &RenderKey,
        view: &FrameView,
        settings: &crate::render::scene::RenderSettings,
        points: u64,
    ) -> bool {
        self.record(gpu, target, data, key, view, settings, Some(points))
    }

    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        gpu: Gpu<'_, '_>,
        target: &RenderTarget,
        data: &SceneData,
        key: &RenderKey,
        view: &FrameView,
        settings: &crate::render::scene::RenderSettings,
        granted: Option<u64>,
    ) -> bool {
        let (device, queue, encoder, renderer) = gpu;
        let (w, h) = (target.width, target.height);
        self.target_for(device, key, data.points.total, w, h);
        let Some(points) = self.target.as_ref() else {
            return true;
        };
        let total = data.points.total;
        let slice = match granted {
            Some(granted) => self.refine.step_granted(key, total, granted),
            None => self.refine.step(key, total, Instant::now()),
        };
        if let Some(range) = slice.clone() {
            // Only points go into the points target; the overlay is drawn into the view's.
            let mut bare = settings.clone();
            bare.markers.clear();
            bare.show_box = false;
            let recording = Recording {
                queue,
                encoder,
                target: points,
            };
            renderer.render_points_slice(recording, data, view, &bare, range);
        }
        points.copy_into(encoder, target);
        // The points no slice has reached yet stand in sparsely (the subset drawn while moving),
        // so the picture is whole from the first frame at rest; a frame without a slice has
        // not prepared the points' parameters and needs none (the refinement is complete).
        let rest = slice.and(self.refine.rest_from());
        let recording = Recording {
            queue,
            encoder,
            target,
        };
        renderer.render_overlay(recording, data, view, settings, rest);
        self.refine.complete()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::markers::MarkerBox;
    use crate::render::scene::RenderSettings;
    use crate::view::camera::Camera;

    fn key(settings: &RenderSettings) -> RenderKey {
        let view = FrameView::at_rest(Camera::default(), glam::Mat4::IDENTITY, 640, 400);
        RenderKey::new(&view, settings, Some(1), 0)
    }

    /// Runs frames of `key` until complete; returns the ranges drawn.
    fn run(refine: &mut Refine, key: &RenderKey, total: u64, t: &mut Instant) -> Vec<Range<u64>> {
        let mut ranges = Vec::new();
        while let Some(r) = refine.step(key, total, *t) {
            ranges.push(r);
            *t += TARGET_FRAME;
            assert!(ranges.len() < 1000, "never completes");
        }
        ranges
    }

    #[test]
    fn completes_after_total_over_budget_frames_covering_every_point_once() {
        let mut refine = Refine::default();
        let mut t = Instant::now();
        let total = 1_050_000;
        let k = key(&RenderSettings::default());
        assert!(refine.wants(total));
        assert!(
            !refine.wants(INITIAL_BUDGET),
            "a cloud within the budget renders at once"
        );
        // Frames exactly on target: the budget stays, so 6 slices of 200,000 (the last 50,000).
        assert_eq!(INITIAL_BUDGET, 200_000);
        let ranges = run(&mut refine, &k, total, &mut t);
        assert_eq!(ranges.len(), 6);
        assert_eq!(ranges[0].start, 0);
        assert!(ranges.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(ranges.last().unwrap().end, total);
        assert!(refine.complete());
        assert_eq!(refine.progress(), None);
        // Complete: the same key draws nothing more.
        assert_eq!(refine.step(&k, total, t), None);
        // And the progressive path stays: its target holds the points for the overlay.
        assert!(refine.wants(total));
    }

    #[test]
    fn a_camera_change_restarts_and_a_playhead_change_does_not() {
        let mut refine = Refine::default();
        let mut t = Instant::now();
        let b = INITIAL_BUDGET;
        let total = 10 * b;
        let mut settings = RenderSettings::default();
        let k = key(&settings);
        assert_eq!(refine.step(&k, total, t), Some(0..b));
        t += TARGET_FRAME;
        assert_eq!(refine.step(&k, total, t), Some(b..2 * b));
        assert!((refine.progress().unwrap() - 0.2).abs() < 1e-6);

        // Playback: the playhead moves every frame; the slices go on where they were.
        for i in 0..3 {
            settings.markers = vec![MarkerBox::playhead(0.1 * i as f32)];
            t += TARGET_FRAME;
            let r = refine.step(&key(&settings), total, t).expect("a slice");
            assert_eq!(r.start, (2 + i) * b, "playhead frame {i}");
        }
        // The box toggled: drawn by the overlay, the points stay.
        settings.show_box = false;
        t += TARGET_FRAME;
        assert_eq!(refine.step(&key(&settings), total, t).unwrap().start, 5 * b);

        // The camera moved (an orbit ended elsewhere): back to point 0.
        let mut moved = key(&settings);
        moved.camera.orbit(5.0, 0.0, 400.0);
        t += TARGET_FRAME;
        assert_eq!(refine.step(&moved, total, t), Some(0..b));
        // A grid or a surface built (revision), the Surface view's settings: the points stay.
        let mut gridded = moved.clone();
        gridded.revision += 1;
        gridded.settings.surface.iso_value += 0.1;
        t += TARGET_FRAME;
        assert_eq!(refine.step(&gridded, total, t).unwrap().start, b);
        // New points on the GPU (points revision) or another point style: back to 0.
        let mut revised = gridded.clone();
        revised.points_revision += 1;
        t += TARGET_FRAME;
        assert_eq!(refine.step(&revised, total, t).unwrap().start, 0);
        let mut styled = revised.clone();
        styled.settings.points.size_px += 1.0;
        t += TARGET_FRAME;
        assert_eq!(refine.step(&styled, total, t).unwrap().start, 0);

        // Once complete, playhead frames draw no slice (only the overlay).
        let ranges = run(&mut refine, &styled, total, &mut t);
        assert_eq!(ranges.last().unwrap().end, total);
        let mut playing = styled.clone();
        playing.settings.markers = vec![MarkerBox::playhead(0.9)];
        assert_eq!(refine.step(&playing, total, t), None);
    }

    #[test]
    fn the_budget_follows_the_measured_frame_time() {
        let mut refine = Refine::default();
        let mut t = Instant::now();
        let k = key(&RenderSettings::default());
        let total = 100_000_000;
        refine.step(&k, total, t);
        // A slow device: frames of four times the target halve the budget, down to the floor.
        for _ in 0..10 {
            t += 4 * TARGET_FRAME;
            refine.step(&k, total, t);
        }
        assert_eq!(refine.budget, MIN_BUDGET);
        // A fast one: 5 ms frames double it each frame.
        let before = refine.budget;
        t += Duration::from_millis(5);
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before * 2);
        // Twice the target: halved.
        let before = refine.budget;
        t += 2 * TARGET_FRAME;
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before / 2);
        // A long gap (window hidden) is not a frame time.
        let before = refine.budget;
        t += Duration::from_secs(3);
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before);
    }

    #[test]
    fn slices_aim_longer_once_the_hand_has_left_the_window() {
        let t = Instant::now();
        assert_eq!(target_frame(None, t), IDLE_TARGET_FRAME);
        assert_eq!(target_frame(Some(t), t), TARGET_FRAME);
        let later = t + HAND_WINDOW - Duration::from_millis(1);
        assert_eq!(target_frame(Some(t), later), TARGET_FRAME);
        assert_eq!(target_frame(Some(t), t + HAND_WINDOW), IDLE_TARGET_FRAME);
        assert!(IDLE_TARGET_FRAME > TARGET_FRAME);
    }

    #[test]
    fn the_budget_follows_the_target_it_is_given() {
        let mut refine = Refine::default();
        let mut t = Instant::now();
        let k = key(&RenderSettings::default());
        let total = 100_000_000;
        refine.target = IDLE_TARGET_FRAME;
        refine.step(&k, total, t);
        // Frames of the short target's length, aiming at the idle one: the budget doubles.
        let before = refine.budget;
        t += TARGET_FRAME;
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before * 2);
        // Frames of the idle target's length keep it.
        let before = refine.budget;
        t += IDLE_TARGET_FRAME;
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before);
        // The hand back on the window: the same frames now halve it.
        refine.target = TARGET_FRAME;
        t += IDLE_TARGET_FRAME;
        refine.step(&k, total, t);
        assert_eq!(refine.budget, before / 2);
    }
}
