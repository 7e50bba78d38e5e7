//! Save PNG waiting for the view: at the view's size, in the Points, Surface and Volume views,
//! the picture saved is the view's own once it is complete (its offscreen target copied, no
//! point or ray drawn again for the picture). When Ctrl+S or the button comes while the view is
//! still filling in (progressive points or volume bands), moving, or waiting for a surface, the
//! save waits here, frame after frame, and takes the view's picture the first frame it holds
//! it complete; the window goes on drawing meanwhile and the status says so.
//!
//! A camera move (or a setting changed) during the wait restarts it: the view then fills in the
//! new scene and that is what is saved, the picture the user sees. Keeping the camera of the
//! click would mean drawing a picture the view no longer shows, the whole heavy draw that the
//! wait is there to avoid. A view that stays at rest and complete without giving its picture
//! for [`STILL_FRAMES`] frames (which a view at rest does not do) falls back to rendering the
//! picture, as every save did before, so a save never waits forever on a still view.
//!
//! At a chosen size the view's picture is not the one wanted: the save draws its own picture
//! ([`Sliced`]), at the camera of the click, into a target of its own, a slice of the points
//! (`ui/progressive.rs`) or a band of the volume's rows (`render/volume/progressive.rs`) a
//! frame, as the view fills in, and its read-back is submitted once it is complete
//! (`ui/save_slices.rs`). A camera move meanwhile leaves it as it is: its picture is not on
//! screen.

use std::path::PathBuf;
use std::time::Instant;

use crate::picture::compare::CompareView;
use crate::render::gpu::target::RenderTarget;
use crate::render::scene::RenderSettings;
use crate::render::volume::progressive::ProgressiveVolume;
use crate::ui::bridge::CompareSliced;
use crate::ui::frame_cache::RenderKey;
use crate::ui::progressive::ProgressivePoints;
use crate::view::frame_view::FrameView;

/// A compare save under way (`ui/compare_save.rs`): what it saves, its picture drawn over
/// frames at a chosen size, and what the status last said it waits for.
pub(in crate::ui) struct CompareWait {
    pub(in crate::ui) what: CompareView,
    pub(in crate::ui) sliced: Option<Box<CompareSliced>>,
    /// What the save waits for, as the status says it.
    pub(in crate::ui) told: &'static str,
    /// What the status said last.
    pub(in crate::ui) last_told: &'static str,
}

/// Frames at rest, with nothing filling in, after which a view that still does not give its
/// picture has it rendered instead.
pub(in crate::ui) const STILL_FRAMES: u32 = 3;

/// What a waiting save does this frame when the view did not give its picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum WaitStep {
    /// Wait for the next frame.
    Wait,
    /// Render the picture now (the view stays still without giving it).
    Render,
}

/// A save waiting for the view to fill in: where it goes and what its "saved …" line adds,
/// decided at the click, and the frames waited so far.
pub(in crate::ui) struct SaveWait {
    /// Where it goes (the overwrite rules already applied at the click).
    pub(in crate::ui) path: PathBuf,
    /// What the "saved …" line adds.
    pub(in crate::ui) notes: String,
    /// The cloud shown at the click: another one shown meanwhile ends the wait, nothing saved.
    pub(in crate::ui) cloud: u64,
    /// When the click came.
    pub(in crate::ui) since: Instant,
    /// Frames drawn while waiting (the click's own not counted).
    pub(in crate::ui) frames: u32,
    /// Frames in a row the view was still and complete without giving its picture.
    still: u32,
    /// The picture drawn for the save over frames (a chosen size), instead of the view's.
    pub(in crate::ui) sliced: Option<Box<Sliced>>,
    /// The A/B compare saved instead of the single view (`ui/compare_save.rs`).
    pub(in crate::ui) compare: Option<CompareWait>,
}

/// A picture drawn for a save over several frames, at the camera and settings of the click,
/// into a target of its own.
pub(in crate::ui) struct Sliced {
    /// The picture (the chosen size).
    pub(in crate::ui) target: RenderTarget,
    /// The points a slice a frame, into a points target of its own.
    pub(in crate::ui) points: ProgressivePoints,
    /// The volume coarse first, then a band of rows a frame.
    pub(in crate::ui) volume: ProgressiveVolume<RenderKey>,
    /// The view of the click at the chosen size, at rest.
    pub(in crate::ui) view: FrameView,
    /// The settings of the click (markers included).
    pub(in crate::ui) settings: RenderSettings,
}

impl Sliced {
    pub(in crate::ui) fn new(
        device: &wgpu::Device,
        view: FrameView,
        settings: RenderSettings,
    ) -> Self {
        let mut view = view;
        view.moving = false;
        Self {
            target: RenderTarget::new(device, view.width, view.height),
            points: ProgressivePoints::default(),
            volume: ProgressiveVolume::default(),
            view,
            settings,
        }
    }
}

impl SaveWait {
    pub(in crate::ui) fn new(path: PathBuf, notes: String, cloud: u64) -> Self {
        Self {
            path,
            notes,
            cloud,
            since: Instant::now(),
            frames: 0,
            still: 0,
            sliced: None,
            compare: None,
        }
    }

    /// A frame after the click's, drawn while waiting.
    pub(in crate::ui) fn frame_drawn(&mut self) {
        self.frames += 1;
    }

    /// One frame in which the view did not give its picture: `settling` when it is filling
    /// in, moving or waiting for a surface (then the wait goes on, however long).
    pub(in crate::ui) fn step(&mut self, settling: bool) -> WaitStep {
        if settling {
            self.still = 0;
            return WaitStep::Wait;
        }
        self.still += 1;
        if self.still > STILL_FRAMES {
            WaitStep::Render
        } else {
            WaitStep::Wait
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait() -> SaveWait {
        SaveWait::new("x.png".into(), String::new(), 1)
    }

    /// A view filling in is waited for as long as it fills in; the frames drawn meanwhile are
    /// counted.
    #[test]
    fn a_view_filling_in_is_waited_for() {
        let mut save = wait();
        for _ in 0..100 {
            save.frame_drawn();
            assert_eq!(save.step(true), WaitStep::Wait);
        }
        assert_eq!(save.frames, 100);
    }

    /// A view still and complete that does not give its picture has it rendered after a few
    /// frames, not waited for forever.
    #[test]
    fn a_still_view_that_gives_nothing_is_rendered() {
        let mut save = wait();
        for _ in 0..STILL_FRAMES {
            assert_eq!(save.step(false), WaitStep::Wait);
        }
        assert_eq!(save.step(false), WaitStep::Render);
    }

    /// A frame or two at rest between moving and filling in (the frame the refinement starts)
    /// does not end the wait: the still frames count again from zero after each settling one.
    #[test]
    fn settling_again_restarts_the_still_count() {
        let mut save = wait();
        for _ in 0..10 {
            for _ in 0..STILL_FRAMES {
                assert_eq!(save.step(false), WaitStep::Wait);
            }
            assert_eq!(save.step(true), WaitStep::Wait);
        }
    }
}
