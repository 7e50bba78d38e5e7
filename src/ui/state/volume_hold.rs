//! The first Volume frame after another view, announced a frame before it is drawn.
//!
//! A volume's first picture at rest is one long render on a slow device (about 1.5 s at 720p on
//! lavapipe, where the grid itself is already built for the Surface view): drawn in the frame
//! of the click, the window showed nothing (not even the view's button taken) until it was done.
//! So the frame of the switch and the next keep the picture the view holds and show "drawing the
//! volume…" (and the view's button taken), the one after draws the volume under that notice, and
//! the next takes the notice away.

use crate::render::scene::ViewKind;

/// The notice shown while the first volume frame is drawn.
pub const DRAWING_THE_VOLUME: &str = "drawing the volume…";

/// What one frame does about the first Volume frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HoldStep {
    /// Keep the picture the 3D view holds this frame (draw nothing new).
    pub hold: bool,
    /// Put the notice on screen.
    pub announce: bool,
    /// Take the notice away (the volume was drawn last frame).
    pub withdraw: bool,
}

/// The view drawn last frame and where a switch to Volume is.
#[derive(Debug, Default)]
pub struct VolumeHold {
    drawn: Option<ViewKind>,
    /// 1: the notice is on screen; 2: the volume is drawn next frame; 3: it was drawn.
    stage: u8,
    /// This frame keeps the picture the view holds.
    holding: bool,
}

impl VolumeHold {
    /// The step of a frame showing `view`; `free` says whether no other blocking work is
    /// announced (a grid build has its own notice, under which the volume is drawn too).
    pub fn step(&mut self, view: ViewKind, free: bool) -> HoldStep {
        let step = self.next(view, free);
        self.holding = step.hold;
        step
    }

    /// Whether this frame keeps the picture the view holds (the step said so).
    pub fn holding(&self) -> bool {
        self.holding
    }

    fn next(&mut self, view: ViewKind, free: bool) -> HoldStep {
        let before = self.drawn.replace(view);
        match self.stage {
            // Held once more: the panel drew its choice before the click changed it in the
            // frame of the switch, so the button taken shows from this frame on.
            1 => {
                self.stage = 2;
                HoldStep {
                    hold: view == ViewKind::Volume,
                    ..Default::default()
                }
            }
            2 => {
                self.stage = 3;
                HoldStep::default()
            }
            3 => {
                self.stage = 0;
                HoldStep {
                    withdraw: true,
                    ..Default::default()
                }
            }
            _ if view == ViewKind::Volume
                && free
                && before.is_some_and(|b| b != ViewKind::Volume) =>
            {
                self.stage = 1;
                HoldStep {
                    hold: true,
                    announce: true,
                    withdraw: false,
                }
            }
            _ => HoldStep::default(),
        }
    }

    /// Whether a switch is under way (the window must come back for its next frame).
    pub fn pending(&self) -> bool {
        self.stage != 0
    }

    /// The view shows something else than the 3D view's scene (a compare, nothing loaded):
    /// a switch seen later is no first frame of this scene.
    pub fn forget(&mut self) {
        self.drawn = None;
        self.holding = false;
        if self.stage == 1 {
            self.stage = 2;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_switch_to_volume_holds_one_frame_then_draws_under_the_notice() {
        let mut hold = VolumeHold::default();
        assert_eq!(hold.step(ViewKind::Surface, true), HoldStep::default());
        let switch = hold.step(ViewKind::Volume, true);
        assert!(switch.hold && switch.announce, "{switch:?}");
        assert!(hold.holding());
        let again = hold.step(ViewKind::Volume, true);
        assert!(again.hold && !again.announce, "{again:?}");
        let draw = hold.step(ViewKind::Volume, true);
        assert!(!hold.holding());
        assert!(
            !draw.hold && !draw.withdraw,
            "drawn under the notice: {draw:?}"
        );
        assert!(hold.step(ViewKind::Volume, true).withdraw);
        assert_eq!(hold.step(ViewKind::Volume, true), HoldStep::default());
    }

    #[test]
    fn no_hold_at_start_in_volume_or_under_another_notice() {
        let mut hold = VolumeHold::default();
        // Opened in Volume: no view before it.
        assert_eq!(hold.step(ViewKind::Volume, true), HoldStep::default());
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Points, true);
        // The grid is built first, with its own notice.
        assert_eq!(hold.step(ViewKind::Volume, false), HoldStep::default());
        assert_eq!(hold.step(ViewKind::Volume, true), HoldStep::default());
    }

    #[test]
    fn leaving_volume_before_it_was_drawn_still_withdraws_the_notice() {
        let mut hold = VolumeHold::default();
        hold.step(ViewKind::Surface, true);
        assert!(hold.step(ViewKind::Volume, true).announce);
        assert!(!hold.step(ViewKind::Points, true).hold);
        hold.step(ViewKind::Points, true);
        assert!(hold.step(ViewKind::Points, true).withdraw);
        hold.forget();
        assert_eq!(hold.step(ViewKind::Volume, true), HoldStep::default());
    }
}
