//! Progressive points in the A/B compare: at rest, each half of side by side draws its points a
//! slice a frame into a target of its own, as the single view does (`ui/progressive.rs`: one
//! [`ProgressivePoints`] a half, the sparse stand-in for the points not drawn yet), and the two
//! halves share one frame's point budget ([`SharedBudget`], adapted to a target frame time from the
//! time between frames as the single view's is). So a frame in compare draws about the points
//! of a frame of the single view and takes about as long, and both halves fill in together over
//! frames. Each half used to be drawn whole in one frame: about 6 s a frame on lavapipe with a
//! 3.5 M-point song as A, so the end of every orbit and every hover froze the window.
//!
//! A compare frame costs more besides its points than a frame of the single view: two copies,
//! two sparse stand-ins, two halves composited. Held to the single view's 150 ms target and
//! floor, the budget sat at its floor with frames of about 250 ms, most of each not points, and
//! a 3.5 M-point song beside the demo took 4.8 s to fill in (2.1 s in the single view). So the
//! shared budget aims at [`COMPARE_TARGET_FRAME`] and never falls below [`COMPARE_MIN_BUDGET`]:
//! fewer, fuller frames, each still well under the longest frame of the old whole redraws.
//!
//! [`CompareRefine::grant`] is the scheduler (no GPU); [`CompareRefine::frame`] records a half.

use std::time::{Duration, Instant};

use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{RenderSettings, SceneData};
use crate::ui::frame_cache::RenderKey;
#[cfg(doc)]
use crate::ui::progressive::TARGET_FRAME;
use crate::ui::progressive::{Gpu, MIN_BUDGET, ProgressivePoints, adapted_towards};

/// The frame time the compare's shared budget aims at (the single view's
/// [`TARGET_FRAME`] is 150 ms): a frame at rest only, where the picture is still.
pub const COMPARE_TARGET_FRAME: Duration = Duration::from_millis(250);
/// The fewest points a compare frame draws, both halves together (and its first frame's): twice
/// the single view's floor, as the frame's cost besides its points is about twice the single
/// view's.
pub const COMPARE_MIN_BUDGET: u64 = 2 * MIN_BUDGET;
use crate::view::frame_view::FrameView;

/// The two halves' shares of one frame's points.
#[derive(Debug)]
pub struct SharedBudget {
    /// Points a frame, both halves together.
    pub budget: u64,
    /// The frame (its `FrameView::frame_index`) whose shares are worked out, and the shares.
    frame: Option<u32>,
    shares: [u64; 2],
    /// When the last frame that left points to draw began, to measure the frame time.
    last_frame: Option<Instant>,
}

impl Default for SharedBudget {
    fn default() -> Self {
        Self {
            budget: COMPARE_MIN_BUDGET,
            frame: None,
            shares: [0; 2],
            last_frame: None,
        }
    }
}

/// `budget` shared between two halves that still have `remaining` points to draw: half each,
/// and what one does not need goes to the other. The shares never add up to more than `budget`
/// and each is at most its half's `remaining`.
pub fn split(budget: u64, remaining: [u64; 2]) -> [u64; 2] {
    let [a, b] = remaining;
    let half = budget / 2;
    let first = a.min(half.max(budget.saturating_sub(b)));
    [first, b.min(budget - first)]
}

impl SharedBudget {
    /// The points half `side` may draw in the frame `frame` (begun `now`), `remaining` the
    /// points each half still has to draw for this frame's view. The first half to ask in a
    /// frame works out both shares (adapting the budget from the time since the last frame
    /// that left points to draw); the other gets its share.
    pub fn grant(&mut self, frame: u32, now: Instant, side: usize, remaining: [u64; 2]) -> u64 {
        if self.frame != Some(frame) {
            if let Some(last) = self.last_frame {
                let frame = now.saturating_duration_since(last);
                self.budget =
                    adapted_towards(self.budget, frame, COMPARE_TARGET_FRAME, COMPARE_MIN_BUDGET);
            }
            self.frame = Some(frame);
            self.shares = split(self.budget, remaining);
            let granted: u64 = self.shares.iter().sum();
            let left = remaining.iter().sum::<u64>() > granted;
            self.last_frame = left.then_some(now);
        }
        // A half that was thought to need nothing when the frame began still gets its half.
        if self.shares[side] == 0 {
            self.shares[side] = remaining[side].min(self.budget / 2);
        }
        self.shares[side]
    }

    /// The halves are drawn otherwise for a while (moving): the time until the next refining
    /// frame is no frame's time.
    pub fn pause(&mut self) {
        self.frame = None;
        self.last_frame = None;
    }
}

/// A refinement of both halves, once complete (the window logs it: tests wait for it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Refined {
    /// Frames it took.
    pub frames: u32,
    /// The most points one of them drew, both halves together.
    pub most_points: u64,
    /// The shared budget it left: both clouds within it, the next frames at rest draw them
    /// whole (no refinement after an orbit); beyond it, the next ones refine again.
    pub budget: u64,
}

/// The compare's progressive points: one [`ProgressivePoints`] for A and one for the version
/// beside it, and the budget they share.
#[derive(Default)]
pub struct CompareRefine {
    pub halves: [ProgressivePoints; 2],
    pub budget: SharedBudget,
    /// Frames of the refinement under way, and the most points one of them drew.
    frames: u32,
    most_points: u64,
    /// The last refinement completed, until taken.
    finished: Option<Refined>,
}

impl CompareRefine {
    /// Whether a frame at rest of half `side` goes the progressive way: the two clouds
    /// (`totals`) are more than one frame's budget, or a refinement of this half is under way.
    pub fn wants(&self, side: usize, totals: [u64; 2]) -> bool {
        totals.iter().sum::<u64>() > self.budget.budget
            || self.halves[side].refine.under_way(totals[side])
    }

    /// The points half `side` draws in the frame of `view`: its share of the budget, from what
    /// each half (keys `keys`, `totals` points) has left to draw.
    pub fn grant(
        &mut self,
        side: usize,
        keys: [&RenderKey; 2],
        totals: [u64; 2],
        view: &FrameView,
        now: Instant,
    ) -> u64 {
        let remaining = [0, 1].map(|s| self.halves[s].refine.remaining(keys[s], totals[s]));
        self.budget.grant(view.frame_index, now, side, remaining)
    }

    /// Records one progressive frame of half `side` into `target` (its slice, the copy, the
    /// overlay). `keys` and `totals` are both halves' (the other's to share the budget with).
    /// Returns whether the half's picture is complete (false: draw again next frame).
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        side: usize,
        gpu: Gpu<'_, '_>,
        target: &RenderTarget,
        data: &SceneData,
        keys: [&RenderKey; 2],
        totals: [u64; 2],
        view: &FrameView,
        settings: &RenderSettings,
    ) -> bool {
        let opens = self.budget.frame != Some(view.frame_index);
        let points = self.grant(side, keys, totals, view, Instant::now());
        if opens {
            self.frames += 1;
            self.most_points = self.most_points.max(self.budget.shares.iter().sum());
        }
        let complete =
            self.halves[side].frame_granted(gpu, target, data, keys[side], view, settings, points);
        // Both halves hold all their points of this frame's view (a half not begun yet is not
        // complete, though its scheduler has nothing left of no cloud).
        let done = (0..2).all(|s| self.halves[s].refine.remaining(keys[s], totals[s]) == 0);
        if done && self.frames > 0 {
            self.finished = Some(Refined {
                frames: self.frames,
                most_points: self.most_points,
                budget: self.budget.budget,
            });
            (self.frames, self.most_points) = (0, 0);
        }
        complete
    }

    /// The refinement completed since the last call.
    pub fn take_finished(&mut self) -> Option<Refined> {
        self.finished.take()
    }

    /// Half `side` shows something else now (a moving frame, a surface, a volume).
    pub fn set_aside(&mut self, side: usize) {
        self.halves[side].set_aside();
        self.budget.pause();
        (self.frames, self.most_points) = (0, 0);
    }

    /// The fraction of both halves' points drawn while either is filling in; `None` when both
    /// are complete or idle.
    pub fn progress(&self) -> Option<f32> {
        let filling = self.halves.iter().any(|h| h.refine.progress().is_some());
        let (drawn, total) = self.halves.iter().fold((0, 0), |(d, t), h| {
            let (dh, th) = h.refine.drawn();
            (d + dh, t + th)
        });
        (filling && total > 0).then(|| drawn as f32 / total as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::RenderSettings;
    use crate::ui::progressive::Refine;
    use crate::view::camera::Camera;
    use std::ops::Range;
    use std::time::Duration;

    fn view(frame_index: u32) -> FrameView {
        let mut view = FrameView::at_rest(Camera::default(), glam::Mat4::IDENTITY, 640, 400);
        view.frame_index = frame_index;
        view
    }

    fn keys(view: &FrameView, settings: &RenderSettings) -> [RenderKey; 2] {
        [0, 1].map(|side| RenderKey::new(view, settings, Some(side), 0))
    }

    /// The compare's frames as the bridge runs them: each half at rest asks for its grant and
    /// draws that slice. Returns each frame's slices (None: the half drew whole) and whether
    /// both halves were complete at the end.
    fn frames(
        compare: &mut CompareRefine,
        totals: [u64; 2],
        frame_time: Duration,
        count: u32,
    ) -> Vec<[Option<Range<u64>>; 2]> {
        let settings = RenderSettings::default();
        let mut t = Instant::now();
        let mut drawn = Vec::new();
        for i in 0..count {
            let view = view(i);
            let keys = keys(&view, &settings);
            let mut frame = [None, None];
            for side in 0..2 {
                if !compare.wants(side, totals) {
                    continue;
                }
                let points = compare.grant(side, [&keys[0], &keys[1]], totals, &view, t);
                frame[side] =
                    compare.halves[side]
                        .refine
                        .step_granted(&keys[side], totals[side], points);
            }
            drawn.push(frame);
            t += frame_time;
        }
        drawn
    }

    fn slice_len(r: &Option<Range<u64>>) -> u64 {
        r.as_ref().map_or(0, |r| r.end - r.start)
    }

    #[test]
    fn the_budget_is_split_and_what_one_half_leaves_goes_to_the_other() {
        assert_eq!(split(1000, [5000, 5000]), [500, 500]);
        assert_eq!(split(1000, [100, 5000]), [100, 900]);
        assert_eq!(split(1000, [5000, 100]), [900, 100]);
        assert_eq!(split(1000, [0, 5000]), [0, 1000]);
        assert_eq!(split(1000, [5000, 0]), [1000, 0]);
        assert_eq!(split(1000, [0, 0]), [0, 0]);
        assert_eq!(split(1001, [5000, 5000]), [500, 501]);
    }

    /// A 3.5 M-point song as A beside a 300,000-point one: each compare frame draws its budget,
    /// which starts at the compare's floor, stays there at frames of the compare's target or
    /// slower and doubles each frame at a third of it (never the single view's 150 ms target
    /// and 200,000 floor: the compare's frames cost more besides their points); both halves draw
    /// every point once and become complete, and then draw nothing more.
    #[test]
    fn compare_frames_draw_the_compare_budget_and_both_halves_complete() {
        let totals = [3_500_000, 300_000];
        for frame_time in [
            COMPARE_TARGET_FRAME,
            2 * COMPARE_TARGET_FRAME,
            COMPARE_TARGET_FRAME / 3,
        ] {
            let mut compare = CompareRefine::default();
            let drawn = frames(&mut compare, totals, frame_time, 200);
            let mut budget = COMPARE_MIN_BUDGET;
            let mut left = totals.iter().sum::<u64>();
            for (i, frame) in drawn.iter().enumerate() {
                let points = slice_len(&frame[0]) + slice_len(&frame[1]);
                assert_eq!(
                    points,
                    budget.min(left),
                    "frame {i} at {frame_time:?}: the compare's budget"
                );
                left -= points;
                if frame_time < COMPARE_TARGET_FRAME {
                    budget = budget.saturating_mul(2);
                }
            }
            // Frames as slow as the compare's target hold the single view at its floor; a
            // compare frame draws twice that (its frame's cost besides the points is more).
            if frame_time == COMPARE_TARGET_FRAME {
                let settings = RenderSettings::default();
                let mut single = Refine::default();
                let mut t = Instant::now();
                for (i, frame) in drawn.iter().enumerate().take(5) {
                    let key = RenderKey::new(&view(i as u32), &settings, Some(0), 0);
                    let slice = single.step(&key, 100_000_000, t).expect("a slice");
                    let points = slice_len(&frame[0]) + slice_len(&frame[1]);
                    assert!(
                        points >= 2 * (slice.end - slice.start),
                        "frame {i}: {points} points in compare, {slice:?} in the single view"
                    );
                    t += frame_time;
                }
            }
            for side in 0..2 {
                let ranges: Vec<_> = drawn.iter().filter_map(|f| f[side].clone()).collect();
                assert_eq!(ranges[0].start, 0, "half {side}");
                assert!(
                    ranges.windows(2).all(|w| w[0].end == w[1].start),
                    "half {side}"
                );
                assert_eq!(ranges.last().unwrap().end, totals[side], "half {side}");
                assert!(
                    compare.halves[side].refine.complete(),
                    "half {side} complete"
                );
                // Both fill in from the first frame, not one after the other.
                assert!(drawn[0][side].as_ref().is_some_and(|r| !r.is_empty()));
            }
            assert_eq!(compare.progress(), None);
            let last = drawn.last().unwrap();
            assert!(
                last[0].is_none() && last[1].is_none(),
                "complete: no slices"
            );
        }
    }

    /// While both fill in, the progress is the share of both clouds drawn; an orbit (a new
    /// camera) starts both halves over.
    #[test]
    fn progress_covers_both_halves_and_a_new_camera_restarts_both() {
        let totals = [2_000_000, 2_000_000];
        let mut compare = CompareRefine::default();
        let drawn = frames(&mut compare, totals, COMPARE_TARGET_FRAME, 2);
        let sum: u64 = drawn.iter().flatten().map(slice_len).sum();
        let progress = compare.progress().expect("filling in");
        assert!((progress - sum as f32 / 4_000_000.0).abs() < 1e-6);
        assert_eq!(
            slice_len(&drawn[0][0]),
            slice_len(&drawn[0][1]),
            "an even split"
        );

        let settings = RenderSettings::default();
        let mut moved = view(7);
        moved.camera.orbit(5.0, 0.0, 400.0);
        let keys = keys(&moved, &settings);
        compare.set_aside(0);
        compare.set_aside(1);
        for side in 0..2 {
            let points = compare.grant(side, [&keys[0], &keys[1]], totals, &moved, Instant::now());
            let range = compare.halves[side]
                .refine
                .step_granted(&keys[side], totals[side], points)
                .expect("a slice");
            assert_eq!(range.start, 0, "half {side} starts over");
        }
    }

    /// A small compare (both clouds within one frame's budget) is drawn whole, as before.
    #[test]
    fn clouds_within_one_frame_are_drawn_whole() {
        let compare = CompareRefine::default();
        assert!(!compare.wants(0, [200_000, 200_000]));
        assert!(compare.wants(0, [250_000, 200_000]));
    }
}
