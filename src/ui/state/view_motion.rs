//! The 3D view's camera and its motion ([`ViewMotion`], the `motion` field of `LoudscapeApp`):
//! the camera and each data slot's, the fit (the one place a fit is asked for and done: on a new
//! cloud, a resize of a camera left as fitted, the F and R keys, the panel's buttons, a compare's
//! layout), the camera input of a frame, whether the view is moving, and how much it draws while
//! moving (the points' subset and the grid views' resolution follow the device's pace).

use std::time::{Duration, Instant};

use super::slot::Slot;
use crate::render::points::PointStyle;
use crate::render::scene::ViewKind;
/// While the camera moves, the Volume and Surface views render at a reduced resolution, chosen
/// so a frame takes about this long (the device's pace measured while moving); the Surface
/// view's coarse mesh stands in past the same pace.
use crate::render::surface::lod::MOVING_FRAME_MS;
use crate::view::camera::Camera;

/// How long after the last input the view still counts as moving (drawn at reduced quality).
const SETTLE: Duration = Duration::from_millis(180);
/// How far (in wheel notches) the window's fit steps back from a tight fit of the box, so the
/// labels outside the box stay in view: 0.9^-1 = 11 % farther.
const LABEL_MARGIN_STEPS: f32 = 1.0;
/// The fewest points the Points view draws while moving (fewer no longer show the music's shape).
const MIN_MOVING_POINTS: u32 = 5_000;
/// The most it draws while moving, whatever the device's pace.
const MAX_MOVING_POINTS: u32 = 1 << 30;
/// The coarsest reduction while moving: one pixel in `MAX_MOVING_DIVISOR` per side.
const MAX_MOVING_DIVISOR: u32 = 4;
/// Scroll (points) per wheel notch of zoom.
const SCROLL_PER_STEP: f32 = 50.0;

/// What a fit frames: the active cloud's world box, in a view that is half of a side-by-side
/// compare or not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::ui) struct FitBox {
    pub(in crate::ui) min: glam::Vec3,
    pub(in crate::ui) max: glam::Vec3,
    /// Each half is narrow: one step more for the level axis's title.
    pub(in crate::ui) half: bool,
}

/// A drag over the view, in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::ui) enum Drag {
    /// The primary button turns the camera around its target.
    Orbit(f32, f32),
    /// The secondary or middle button moves it sideways.
    Pan(f32, f32),
}

/// The camera input of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(in crate::ui) struct CameraInput {
    pub(in crate::ui) drag: Option<Drag>,
    /// The wheel's scroll over the view, in points (0 when the pointer is elsewhere).
    pub(in crate::ui) scroll: f32,
    /// F: frame the data, keeping the viewing direction.
    pub(in crate::ui) fit: bool,
    /// R: the default viewing direction, framed.
    pub(in crate::ui) reset: bool,
}

/// The camera, its fit and its motion.
pub(in crate::ui) struct ViewMotion {
    camera: Camera,
    /// Fit at the next frame that has a cloud to fit ([`ViewMotion::request_fit`]).
    fit_pending: bool,
    /// The camera is as the last fit left it (not moved by hand since): refit on resize.
    fitted: bool,
    /// The view's width over its height when last drawn.
    aspect: f32,
    /// The view's height and the window's when last drawn (points), where known.
    heights: Option<(f32, f32)>,
    last_motion: Option<Instant>,
    /// The camera each data slot (Song, Timeline) was left with.
    slot_cameras: [Option<Camera>; 2],
    /// Loads that keep the camera instead of fitting (a remembered view, a re-extraction).
    keep_camera_loads: usize,
    /// Per view (Points, Surface, Volume): the moving resolution's divisor per side.
    moving_divisor: [u32; 3],
    /// Points the Points view draws while moving, following the device's pace.
    moving_points: u32,
    /// When the window last had input (pointer motion, a button held, a scroll, a key).
    last_hand: Option<Instant>,
}

impl Default for ViewMotion {
    fn default() -> Self {
        Self {
            camera: Camera::default(),
            fit_pending: true,
            fitted: false,
            aspect: 1.6,
            heights: None,
            last_motion: None,
            slot_cameras: [None, None],
            keep_camera_loads: 0,
            moving_divisor: [1; 3],
            moving_points: PointStyle::default().max_points_moving,
            last_hand: None,
        }
    }
}

impl ViewMotion {
    /// Notes whether this frame had input (`hand`) and returns the frame time the points'
    /// slices aim at now: short while the user's hand is on the window, so that a hover or a
    /// key is answered soon, longer once it has left it ([`crate::ui::progressive::target_frame`]).
    pub(in crate::ui) fn refine_target(&mut self, hand: bool, now: Instant) -> Duration {
        if hand {
            self.last_hand = Some(now);
        }
        crate::ui::progressive::target_frame(self.last_hand, now)
    }

    pub(in crate::ui) fn camera(&self) -> Camera {
        self.camera
    }

    /// Whether the camera still waits for its fit.
    pub(in crate::ui) fn fit_pending(&self) -> bool {
        self.fit_pending
    }

    /// The camera worth keeping (a video's, a slot's): none while it waits for its first fit.
    pub(in crate::ui) fn settled_camera(&self) -> Option<Camera> {
        (!self.fit_pending).then_some(self.camera)
    }

    /// Fits the camera at the next frame that has a cloud (the Fit button, a compare's layout).
    pub(in crate::ui) fn request_fit(&mut self) {
        self.fit_pending = true;
    }

    /// A remembered camera, kept by the next `loads` loads (the files it was left with).
    pub(in crate::ui) fn restore(&mut self, camera: Camera, loads: usize) {
        self.camera = camera;
        self.fit_pending = false;
        self.keep_camera_loads = loads;
    }

    /// The remembered camera is not for the clouds that come (its slot's load failed): the
    /// next load is fitted.
    pub(in crate::ui) fn abandon_restore(&mut self) {
        self.keep_camera_loads = 0;
    }

    /// A load that was to keep the camera was installed unseen: it keeps nothing.
    pub(in crate::ui) fn forget_kept_load(&mut self) {
        self.keep_camera_loads = self.keep_camera_loads.saturating_sub(1);
    }

    /// The view's height and the window's (points) when last drawn, where known.
    pub(in crate::ui) fn heights(&self) -> Option<(f32, f32)> {
        self.heights
    }

    /// The view's and the window's heights a restored camera was left at: the first frames
    /// of a view of another height (the loudness strip not there yet) keep its framing, as a
    /// resize of the view does ([`ViewMotion::size_view_within`]).
    pub(in crate::ui) fn restore_heights(&mut self, heights: (f32, f32)) {
        self.heights = Some(heights);
    }

    /// The next load keeps the camera (the same data, seen the same way).
    pub(in crate::ui) fn keep_camera_for_next_load(&mut self) {
        self.keep_camera_loads += 1;
    }

    /// The active slot turns from `from` to `to`: the camera left behind is remembered, the
    /// one switched to comes back as it was (or is fitted the first time).
    pub(in crate::ui) fn switch_slot(&mut self, from: Slot, to: Slot) {
        // A camera still waiting for its first fit is not worth keeping.
        self.slot_cameras[from as usize] = self.settled_camera();
        match self.slot_cameras[to as usize] {
            Some(camera) => {
                self.camera = camera;
                self.fit_pending = false;
            }
            None => {
                self.camera = Camera::default();
                self.fit_pending = true;
            }
        }
    }

    /// A cloud was installed in `to` (the active slot was `from`): it starts from its own
    /// fitted camera, unless this load keeps the camera.
    pub(in crate::ui) fn cloud_installed(&mut self, from: Slot, to: Slot) {
        if from != to && !self.fit_pending {
            self.slot_cameras[from as usize] = Some(self.camera);
        }
        self.slot_cameras[to as usize] = None;
        if self.keep_camera_loads > 0 {
            self.keep_camera_loads -= 1;
        } else {
            self.camera = Camera::default();
            self.fit_pending = true;
        }
    }

    /// The view is `aspect` wide over high this frame. A camera left as fitted is fitted again
    /// when that changed (an 800x600 window cut the labels off); a pending fit is done when
    /// there is a cloud (`target`).
    #[cfg(test)]
    pub(in crate::ui) fn size_view(&mut self, aspect: f32, target: Option<FitBox>) {
        self.size_view_within(aspect, target, None);
    }

    /// As [`ViewMotion::size_view`], `heights` being the view's height and the window's (in
    /// points). When the view's height changed and the window's did not, the window itself
    /// took or gave the room (the loudness strip arriving with the whole song, a line under
    /// the view): the picture keeps its framing, the camera stepping back or closer so a
    /// world unit at the target keeps its size on screen, instead of being fitted again.
    pub(in crate::ui) fn size_view_within(
        &mut self,
        aspect: f32,
        target: Option<FitBox>,
        heights: Option<(f32, f32)>,
    ) {
        if let (Some((view, window)), Some((old_view, old_window))) = (heights, self.heights)
            && (window - old_window).abs() < 0.5
            && (view - old_view).abs() >= 0.5
            && old_view > 0.0
            && view > 0.0
            && !self.fit_pending
        {
            self.camera.distance *= view / old_view;
            self.aspect = aspect;
        }
        if heights.is_some() {
            self.heights = heights;
        }
        if (aspect - self.aspect).abs() > 1e-3 && self.fitted {
            self.fit_pending = true;
        }
        self.aspect = aspect;
        if let Some(target) = target
            && self.fit_pending
        {
            self.fit(target);
            self.fit_pending = false;
            self.fitted = true;
        }
    }

    /// Frames `target`, keeping the viewing direction, with room around the box for the tick
    /// labels and axis titles drawn outside it (a tight fit put them under the side panel).
    fn fit(&mut self, target: FitBox) {
        self.camera.fit(target.min, target.max, self.aspect);
        self.camera.zoom(-LABEL_MARGIN_STEPS);
        if target.half {
            self.camera.zoom(-1.0);
        }
    }

    /// The default viewing direction, fitted to `target` when there is one (R, "Reset view").
    pub(in crate::ui) fn reset(&mut self, target: Option<FitBox>) {
        self.camera = Camera::default();
        if let Some(target) = target {
            self.fit(target);
        }
        self.fitted = true;
    }

    /// Applies a frame's camera input to a view `height` pixels high at `now`; returns whether
    /// the view is moving (input within the last [`SETTLE`]).
    pub(in crate::ui) fn input(
        &mut self,
        input: &CameraInput,
        height: f32,
        target: Option<FitBox>,
        now: Instant,
    ) -> bool {
        let mut moved = false;
        match input.drag {
            Some(Drag::Orbit(dx, dy)) => self.camera.orbit(dx, dy, height),
            Some(Drag::Pan(dx, dy)) => self.camera.pan(dx, dy, height),
            None => {}
        }
        moved |= input.drag.is_some();
        if input.scroll != 0.0 {
            self.camera.zoom(input.scroll / SCROLL_PER_STEP);
            moved = true;
        }
        let mut fitted_now = false;
        if input.fit {
            if let Some(target) = target {
                self.fit(target);
            }
            (moved, fitted_now) = (true, true);
        }
        if input.reset {
            self.reset(target);
            (moved, fitted_now) = (true, true);
        }
        if moved {
            self.last_motion = Some(now);
            self.fitted = fitted_now;
        }
        self.last_motion.is_some_and(|t| now - t < SETTLE)
    }

    /// Whether the view needs another frame for its motion: while moving, and once more at
    /// full quality when it settles.
    pub(in crate::ui) fn wants_frame(&mut self, moving: bool) -> bool {
        moving || self.last_motion.take().is_some()
    }

    /// A moving frame of `view` took `frame_ms` (None: it did not follow the last at once): the
    /// points' subset or the grid view's resolution follows the pace.
    pub(in crate::ui) fn pace(&mut self, view: ViewKind, frame_ms: Option<f32>) {
        if view == ViewKind::Points {
            self.moving_points = next_moving_points(self.moving_points, frame_ms);
        } else {
            let divisor = &mut self.moving_divisor[view as usize];
            *divisor = next_moving_divisor(*divisor, frame_ms);
        }
    }

    /// Points the Points view draws while moving.
    pub(in crate::ui) fn moving_points(&self) -> u32 {
        self.moving_points
    }

    /// The divisor per side of `view`'s resolution while moving.
    pub(in crate::ui) fn moving_divisor(&self, view: ViewKind) -> u32 {
        self.moving_divisor[view as usize].max(1)
    }
}

/// The divisor of the moving resolution after a frame that took `frame_ms` (None: the frame
/// did not follow the last at once, so its time says nothing about the device): one step
/// coarser when frames are slower than [`MOVING_FRAME_MS`], one finer when well under it.
fn next_moving_divisor(divisor: u32, frame_ms: Option<f32>) -> u32 {
    match frame_ms {
        Some(ms) if ms > MOVING_FRAME_MS => (divisor + 1).min(MAX_MOVING_DIVISOR),
        Some(ms) if ms < MOVING_FRAME_MS * 0.4 => divisor.saturating_sub(1).max(1),
        _ => divisor.max(1),
    }
}

/// The points drawn while moving after a frame that took `frame_ms` (None: says nothing about
/// the device): fewer when frames are slower than [`MOVING_FRAME_MS`], more when well under it,
/// never below [`MIN_MOVING_POINTS`]. On a fast device it grows past any cloud's size, so every
/// point is drawn while moving too.
fn next_moving_points(points: u32, frame_ms: Option<f32>) -> u32 {
    let next = match frame_ms {
        Some(ms) if ms > MOVING_FRAME_MS => points as f32 * 0.75,
        Some(ms) if ms < MOVING_FRAME_MS * 0.6 => points as f32 * 1.25,
        _ => points as f32,
    };
    (next as u32).clamp(MIN_MOVING_POINTS, MAX_MOVING_POINTS)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOX: FitBox = FitBox {
        min: glam::Vec3::splat(-1.0),
        max: glam::Vec3::splat(1.0),
        half: false,
    };

    fn dragged(drag: Drag) -> CameraInput {
        CameraInput {
            drag: Some(drag),
            ..Default::default()
        }
    }

    fn fitted() -> ViewMotion {
        let mut motion = ViewMotion::default();
        motion.size_view(1.6, Some(BOX));
        motion
    }

    #[test]
    fn the_first_fit_waits_for_a_cloud() {
        let mut motion = ViewMotion::default();
        assert_eq!(motion.settled_camera(), None);
        motion.size_view(1.6, None);
        assert!(motion.fit_pending(), "nothing to fit yet");
        assert_eq!(motion.camera(), Camera::default());
        motion.size_view(1.6, Some(BOX));
        assert!(!motion.fit_pending());
        assert_ne!(motion.camera(), Camera::default(), "fitted to the box");
        assert_eq!(motion.settled_camera(), Some(motion.camera()));
    }

    #[test]
    fn a_camera_left_as_fitted_follows_a_resize_and_one_moved_by_hand_stays() {
        let mut motion = fitted();
        let wide = motion.camera();
        motion.size_view(0.8, Some(BOX));
        assert_ne!(motion.camera(), wide, "fitted again to the narrower view");

        let now = Instant::now();
        let orbit = dragged(Drag::Orbit(30.0, 0.0));
        assert!(motion.input(&orbit, 600.0, Some(BOX), now));
        let by_hand = motion.camera();
        motion.size_view(1.6, Some(BOX));
        assert_eq!(
            motion.camera(),
            by_hand,
            "a resize keeps a camera moved by hand"
        );

        let fit = CameraInput {
            fit: true,
            ..Default::default()
        };
        motion.input(&fit, 600.0, Some(BOX), now);
        let refit = motion.camera();
        motion.size_view(0.8, Some(BOX));
        assert_ne!(motion.camera(), refit, "F leaves it as fitted again");
    }

    /// Pixels a world unit at the camera's target takes in a view `height` pixels high.
    fn scale(camera: &Camera, height: f32) -> f32 {
        let fov = crate::view::camera::FOV_Y_DEGREES.to_radians();
        height / (2.0 * camera.distance * (fov / 2.0).tan())
    }

    #[test]
    fn the_window_taking_room_from_the_view_keeps_the_framing() {
        // Fitted, then moved by hand: both keep their scale when the strip takes 110 points.
        for by_hand in [false, true] {
            let mut motion = ViewMotion::default();
            motion.size_view_within(1200.0 / 700.0, Some(BOX), Some((700.0, 800.0)));
            if by_hand {
                let orbit = dragged(Drag::Orbit(30.0, 10.0));
                motion.input(&orbit, 700.0, Some(BOX), Instant::now());
            }
            let before = motion.camera();
            motion.size_view_within(1200.0 / 590.0, Some(BOX), Some((590.0, 800.0)));
            let after = motion.camera();
            assert!(
                (scale(&before, 700.0) - scale(&after, 590.0)).abs() < 1e-4,
                "the picture jumped: {} px a unit before, {} after",
                scale(&before, 700.0),
                scale(&after, 590.0)
            );
            assert_eq!(
                (after.target, after.azimuth, after.elevation),
                (before.target, before.azimuth, before.elevation),
                "the same view, only its size kept"
            );
        }
        // The user resizing the window: a fitted camera is fitted again as before.
        let mut motion = ViewMotion::default();
        motion.size_view_within(1.6, Some(BOX), Some((700.0, 800.0)));
        let wide = motion.camera();
        motion.size_view_within(0.8, Some(BOX), Some((400.0, 500.0)));
        let mut fitted = ViewMotion::default();
        fitted.size_view(0.8, Some(BOX));
        assert_ne!(motion.camera(), wide);
        assert_eq!(motion.camera(), fitted.camera(), "fitted to the new window");
    }

    #[test]
    fn a_restored_camera_is_kept_by_its_load_and_abandoned_when_it_fails() {
        let mut camera = Camera::default();
        camera.azimuth += 0.7;
        let mut motion = ViewMotion::default();
        motion.restore(camera, 1);
        motion.cloud_installed(Slot::Song, Slot::Song);
        assert_eq!(
            motion.camera(),
            camera,
            "the song comes back as it was left"
        );
        motion.cloud_installed(Slot::Song, Slot::Song);
        assert!(motion.fit_pending(), "a later cloud is fitted");

        let mut motion = ViewMotion::default();
        motion.restore(camera, 1);
        motion.abandon_restore();
        motion.cloud_installed(Slot::Song, Slot::Timeline);
        assert!(
            motion.fit_pending(),
            "the timeline is fitted, not given the song's camera"
        );
    }

    #[test]
    fn input_moves_the_view_until_it_settles_and_asks_for_one_more_frame() {
        let mut motion = fitted();
        let now = Instant::now();
        assert!(!motion.input(&CameraInput::default(), 600.0, Some(BOX), now));
        assert!(!motion.wants_frame(false), "nothing moved");
        let scroll = CameraInput {
            scroll: 100.0,
            ..Default::default()
        };
        let before = motion.camera();
        assert!(motion.input(&scroll, 600.0, Some(BOX), now));
        assert!(
            motion.camera().distance < before.distance,
            "scrolling up zooms in"
        );
        assert!(motion.wants_frame(true));
        let later = now + SETTLE + Duration::from_millis(1);
        assert!(!motion.input(&CameraInput::default(), 600.0, Some(BOX), later));
        assert!(motion.wants_frame(false), "one more frame at full quality");
        assert!(!motion.wants_frame(false), "then none");
        let pan = dragged(Drag::Pan(10.0, 5.0));
        assert!(motion.input(&pan, 600.0, Some(BOX), later));
        assert_ne!(
            motion.camera().target,
            before.target,
            "a pan moves the target"
        );
    }

    #[test]
    fn reset_and_fit_frame_the_box_and_a_half_view_steps_back_further() {
        let mut motion = fitted();
        let whole = motion.camera();
        motion.input(
            &dragged(Drag::Orbit(80.0, 20.0)),
            600.0,
            Some(BOX),
            Instant::now(),
        );
        motion.reset(Some(BOX));
        assert_eq!(
            motion.camera(),
            whole,
            "R: the default direction, fitted as at first"
        );
        let half = FitBox { half: true, ..BOX };
        motion.reset(Some(half));
        assert!(motion.camera().distance > whole.distance);
        motion.reset(None);
        assert_eq!(
            motion.camera(),
            Camera::default(),
            "no cloud: only the direction"
        );
    }

    #[test]
    fn each_slot_keeps_its_camera_and_a_new_cloud_is_fitted_unless_kept() {
        let mut motion = fitted();
        motion.input(
            &dragged(Drag::Orbit(40.0, 0.0)),
            600.0,
            Some(BOX),
            Instant::now(),
        );
        let song = motion.camera();
        motion.switch_slot(Slot::Song, Slot::Timeline);
        assert!(motion.fit_pending(), "the timeline's first visit is fitted");
        motion.size_view(1.6, Some(BOX));
        motion.switch_slot(Slot::Timeline, Slot::Song);
        assert_eq!(motion.camera(), song, "the song's camera as it was left");
        assert!(!motion.fit_pending());

        motion.cloud_installed(Slot::Song, Slot::Timeline);
        assert!(motion.fit_pending(), "a new cloud is fitted");
        motion.switch_slot(Slot::Timeline, Slot::Song);
        assert_eq!(
            motion.camera(),
            song,
            "the song's camera was kept at the install"
        );

        motion.restore(song, 1);
        assert_eq!(motion.settled_camera(), Some(song));
        motion.cloud_installed(Slot::Song, Slot::Song);
        assert_eq!(
            motion.camera(),
            song,
            "a restored camera is kept by its load"
        );
        motion.keep_camera_for_next_load();
        motion.cloud_installed(Slot::Song, Slot::Song);
        assert_eq!(motion.camera(), song, "and by a re-extraction");
        motion.cloud_installed(Slot::Song, Slot::Song);
        assert!(motion.fit_pending(), "the next load is fitted");
    }

    #[test]
    fn the_pace_of_one_view_leaves_the_others_alone() {
        let mut motion = ViewMotion::default();
        for _ in 0..10 {
            motion.pace(ViewKind::Volume, Some(400.0));
        }
        assert_eq!(motion.moving_divisor(ViewKind::Volume), MAX_MOVING_DIVISOR);
        assert_eq!(motion.moving_divisor(ViewKind::Surface), 1);
        assert_eq!(
            motion.moving_points(),
            PointStyle::default().max_points_moving
        );
        motion.pace(ViewKind::Points, Some(400.0));
        assert!(motion.moving_points() < PointStyle::default().max_points_moving);
    }

    #[test]
    fn moving_points_follow_the_pace_and_stay_in_range() {
        let mut n = PointStyle::default().max_points_moving;
        for _ in 0..40 {
            n = next_moving_points(n, Some(400.0));
        }
        assert_eq!(
            n, MIN_MOVING_POINTS,
            "slow frames shrink the subset to the floor"
        );
        assert_eq!(next_moving_points(n, None), n, "idle frames say nothing");
        assert_eq!(next_moving_points(n, Some(MOVING_FRAME_MS * 0.8)), n);
        let mut grown = n;
        for _ in 0..5 {
            grown = next_moving_points(grown, Some(5.0));
        }
        assert!(grown > 2 * n, "fast frames grow it: {n} -> {grown}");
        for _ in 0..200 {
            grown = next_moving_points(grown, Some(5.0));
        }
        assert_eq!(grown, MAX_MOVING_POINTS);
    }

    #[test]
    fn moving_divisor_follows_the_pace_and_stays_in_range() {
        let mut d = 1;
        for _ in 0..10 {
            d = next_moving_divisor(d, Some(400.0));
        }
        assert_eq!(d, MAX_MOVING_DIVISOR);
        assert_eq!(next_moving_divisor(d, None), d, "idle frames say nothing");
        assert_eq!(next_moving_divisor(d, Some(MOVING_FRAME_MS * 0.8)), d);
        for _ in 0..10 {
            d = next_moving_divisor(d, Some(5.0));
        }
        assert_eq!(d, 1);
    }

    #[test]
    fn the_refine_target_is_short_while_input_comes_and_long_after() {
        use crate::ui::progressive::{HAND_WINDOW, IDLE_TARGET_FRAME, TARGET_FRAME};
        let mut motion = ViewMotion::default();
        let t = Instant::now();
        assert_eq!(motion.refine_target(false, t), IDLE_TARGET_FRAME);
        assert_eq!(motion.refine_target(true, t), TARGET_FRAME);
        assert_eq!(
            motion.refine_target(false, t + HAND_WINDOW / 2),
            TARGET_FRAME
        );
        assert_eq!(
            motion.refine_target(false, t + HAND_WINDOW),
            IDLE_TARGET_FRAME
        );
    }
}
