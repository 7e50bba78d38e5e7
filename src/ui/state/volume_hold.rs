//! The notice of a switch to Volume, up while the volume is drawn.
//!
//! A volume's first picture at rest is seconds of rendering on a slow device (about 1.5-4 s at
//! 1600x1000 on lavapipe). It is drawn progressively (`render/volume/progressive.rs`): a coarse
//! picture in the frame of the switch, then a band of full-quality rows a frame, the window
//! answering in between. The view's corner says "drawing the volume… N %" from the frame of the
//! switch until the refinement is complete, and only there (the status area said it too, a
//! second notice of the same work; the points' "refining points… N %" is the corner's alone);
//! leaving the view takes it away.

use crate::render::scene::ViewKind;

/// The notice shown while a volume picture is drawn.
pub const DRAWING_THE_VOLUME: &str = "drawing the volume…";

/// What one frame does about the notice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HoldStep {
    /// Put the notice on screen.
    pub announce: bool,
    /// Take the notice away (the volume is complete, or the view left).
    pub withdraw: bool,
}

/// The view drawn last frame and whether the notice is up.
#[derive(Debug, Default)]
pub struct VolumeHold {
    drawn: Option<ViewKind>,
    /// The notice is on screen.
    announced: bool,
}

impl VolumeHold {
    /// The step of a frame showing `view`; `free` says whether no other work is announced (a
    /// grid build has its own notice), `refining` whether the last frame left a progressive
    /// picture unfinished (`ViewResources::refining`).
    pub fn step(&mut self, view: ViewKind, free: bool, refining: bool) -> HoldStep {
        let before = self.drawn.replace(view);
        if self.announced {
            // The frame of the switch drew the coarse picture; from the next on, the refinement
            // says whether the volume is still being drawn.
            if view != ViewKind::Volume || !refining {
                self.announced = false;
                return HoldStep {
                    withdraw: true,
                    ..Default::default()
                };
            }
            return HoldStep::default();
        }
        if view == ViewKind::Volume && free && before.is_some_and(|b| b != ViewKind::Volume) {
            self.announced = true;
            return HoldStep {
                announce: true,
                ..Default::default()
            };
        }
        HoldStep::default()
    }

    /// What the view's corner says in `view`, `refining` being the share of the progressive
    /// picture drawn (None when it is complete): how far the volume is drawn, from the frame of
    /// a switch (0 % before its first band) and while any later picture refines; nothing in
    /// another view.
    pub fn corner(&self, view: ViewKind, refining: Option<f32>) -> Option<String> {
        if view != ViewKind::Volume {
            return None;
        }
        let done = refining.or(self.announced.then_some(0.0))?;
        Some(format!(
            "{DRAWING_THE_VOLUME} {:.0} %",
            (done * 100.0).floor()
        ))
    }

    /// Whether the notice is up (the window must come back to take it away).
    pub fn pending(&self) -> bool {
        self.announced
    }

    /// The view shows something else than the 3D view's scene (a compare, nothing loaded):
    /// a switch seen later is no first frame of this scene.
    pub fn forget(&mut self) {
        self.drawn = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_switch_to_volume_announces_at_once_until_the_refinement_ends() {
        let mut hold = VolumeHold::default();
        assert_eq!(
            hold.step(ViewKind::Surface, true, false),
            HoldStep::default()
        );
        // The frame of the switch: the notice goes up and the coarse picture is drawn in it.
        let switch = hold.step(ViewKind::Volume, true, false);
        assert!(switch.announce && !switch.withdraw, "{switch:?}");
        assert!(hold.pending());
        // While the bands come, the notice stays.
        for _ in 0..5 {
            assert_eq!(hold.step(ViewKind::Volume, true, true), HoldStep::default());
        }
        // The refinement is complete: away.
        assert!(hold.step(ViewKind::Volume, true, false).withdraw);
        assert!(!hold.pending());
        assert_eq!(
            hold.step(ViewKind::Volume, true, false),
            HoldStep::default()
        );
        // An orbit and back refines again, but it is no switch: no notice (the badge shows it).
        assert_eq!(hold.step(ViewKind::Volume, true, true), HoldStep::default());
    }

    /// The volume's progress is said once, in the view's corner: from the frame of the
    /// switch, before the first band, until the picture is complete.
    #[test]
    fn the_corner_says_how_far_the_volume_is_drawn() {
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Points, true, false);
        assert_eq!(
            hold.corner(ViewKind::Points, Some(0.5)),
            None,
            "the points' own"
        );
        hold.step(ViewKind::Volume, true, false);
        assert_eq!(
            hold.corner(ViewKind::Volume, None).as_deref(),
            Some("drawing the volume… 0 %"),
            "the frame of the switch"
        );
        hold.step(ViewKind::Volume, true, true);
        assert_eq!(
            hold.corner(ViewKind::Volume, Some(0.427)).as_deref(),
            Some("drawing the volume… 42 %")
        );
        hold.step(ViewKind::Volume, true, false);
        assert_eq!(hold.corner(ViewKind::Volume, None), None, "complete");
        // An orbit and back refines again: said there too.
        assert!(hold.corner(ViewKind::Volume, Some(0.1)).is_some());
    }

    #[test]
    fn a_volume_complete_in_its_first_frame_withdraws_the_notice_next_frame() {
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Points, true, false);
        assert!(hold.step(ViewKind::Volume, true, false).announce);
        assert!(hold.step(ViewKind::Volume, true, false).withdraw);
    }

    #[test]
    fn no_notice_at_start_in_volume_or_under_another_notice() {
        let mut hold = VolumeHold::default();
        // Opened in Volume: no view before it.
        assert_eq!(
            hold.step(ViewKind::Volume, true, false),
            HoldStep::default()
        );
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Points, true, false);
        // The grid is built first, with its own notice.
        assert_eq!(
            hold.step(ViewKind::Volume, false, false),
            HoldStep::default()
        );
        assert_eq!(hold.step(ViewKind::Volume, true, true), HoldStep::default());
    }

    #[test]
    fn leaving_volume_before_it_was_drawn_withdraws_the_notice() {
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Surface, true, false);
        assert!(hold.step(ViewKind::Volume, true, false).announce);
        assert!(hold.step(ViewKind::Points, true, true).withdraw);
        hold.forget();
        assert_eq!(
            hold.step(ViewKind::Volume, true, false),
            HoldStep::default()
        );
    }
}
