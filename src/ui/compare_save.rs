//! Save PNG of the A/B compare (side by side, and the Difference view) never draws the whole
//! compare in the frame of the click. At the view's size it waits until both halves (the
//! difference) are complete, their points filled in by the compare's shared refinement
//! (`ui/compare_refine.rs`), and copies the picture the view shows. At a chosen size it draws
//! both halves for the save over frames, each half's points a slice a frame, and composes them
//! (`bridge/compare/save.rs`). The grids or surfaces a picture needs that the view has not
//! built yet are waited for (the view builds them in the background, "saving … (waiting for
//! the grids)"), never built in a frame; ones that do not come end the save with one line.
//! The read-back, labels and PNG then go to the save's thread (`state/picture_save.rs`).

use eframe::egui;

use crate::picture::compare::CompareView;
use crate::render::scene::ViewKind;
use crate::ui::bridge::{CompareResources, CompareSliced};
use crate::ui::state::LoudscapeApp;
use crate::ui::state::picture_save::{COPIED, RENDERED, SLICED};
use crate::ui::state::save_wait::{CompareWait, SaveWait, WaitStep};

/// What a compare save waiting for the view says.
pub(in crate::ui) const WAIT_HALVES: &str = "waiting for both halves to fill in";
/// What a compare save drawn over frames says.
pub(in crate::ui) const WAIT_SLICES: &str = "drawing it a part a frame";
/// What a compare save waiting for the view's grids says.
pub(in crate::ui) const WAIT_GRIDS: &str = "waiting for the grids";
/// What a compare save waiting for the view's surfaces says.
pub(in crate::ui) const WAIT_SURFACES: &str = "waiting for the surfaces";

/// Whether a compare picture `what` can be drawn now, from what the compare holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum Needs {
    Ready,
    /// Wait for what the view builds in the background (the status says which).
    Wait(&'static str),
    /// Grids the picture needs, none built and none coming.
    NoGrids,
}

/// What the picture `what` needs: the grids (every view but Points, and the Difference view)
/// built (`has_grids`) or coming (`grids_coming`), and in Surface the two surfaces, which
/// come while `surfaces_coming`.
pub(in crate::ui) fn needs(
    what: CompareView,
    has_grids: bool,
    grids_coming: bool,
    surfaces_coming: bool,
) -> Needs {
    let grids = match what {
        CompareView::SideBySide(view) => view != ViewKind::Points,
        CompareView::Difference(_) => true,
    };
    if grids && !has_grids {
        return if grids_coming {
            Needs::Wait(WAIT_GRIDS)
        } else {
            Needs::NoGrids
        };
    }
    if what == CompareView::SideBySide(ViewKind::Surface) && surfaces_coming {
        return Needs::Wait(WAIT_SURFACES);
    }
    Needs::Ready
}

impl LoudscapeApp {
    /// The click of Save PNG while the compare is shown as `what`: the save waits for the
    /// view's halves (the view's size) or draws its own over frames (`size`), starting in this
    /// frame; the status says which.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn start_compare_save(
        &mut self,
        ctx: &egui::Context,
        frame: &eframe::Frame,
        mut wait: SaveWait,
        what: CompareView,
        view: &crate::view::frame_view::FrameView,
        size: Option<(u32, u32)>,
        settings: crate::render::scene::RenderSettings,
    ) {
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let sliced = match size {
            Some(size) => {
                match CompareSliced::new(&render_state.device, what, view, size, settings) {
                    Ok(sliced) => Some(Box::new(sliced)),
                    Err(e) => {
                        self.messages.error(format!(
                            "Save PNG: {e}: nothing saved to {}",
                            wait.path.display()
                        ));
                        return;
                    }
                }
            }
            None => None,
        };
        let told = if sliced.is_some() {
            WAIT_SLICES
        } else {
            WAIT_HALVES
        };
        wait.compare = Some(CompareWait {
            what,
            sliced,
            told,
            last_told: told,
        });
        let path = wait.path.clone();
        self.save_shot.waiting = Some(wait);
        self.step_compare_wait(ctx, frame);
        if let Some(wait) = self.save_shot.waiting.as_ref()
            && let Some(compare) = wait.compare.as_ref()
        {
            let shown = std::path::absolute(&path).unwrap_or(path);
            let told = compare.told;
            self.messages
                .info(format!("saving {}… ({told})", shown.display()));
            if let Some(compare) = self
                .save_shot
                .waiting
                .as_mut()
                .and_then(|w| w.compare.as_mut())
            {
                compare.last_told = told;
            }
        }
    }

    /// Once a frame while a compare save waits, and in the frame of the click: the view's
    /// picture copied once both halves hold it complete, or the next part of the save's own
    /// picture drawn; grids or surfaces the picture needs waited for while the view builds
    /// them. The compare shown otherwise meanwhile ends a wait for the view's picture, nothing
    /// saved.
    pub(super) fn step_compare_wait(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let (Some(render_state), Some(view)) = (frame.wgpu_render_state(), self.last_view) else {
            return;
        };
        let shown_as = self.compare_shown_as();
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        let Some(wait) = self.save_shot.waiting.as_mut() else {
            return;
        };
        let Some(compare) = wait.compare.as_mut() else {
            return;
        };
        let what = compare.what;
        let state = self.compare.as_ref();
        let needs = needs(
            what,
            state.is_some_and(|c| c.has_grids),
            state.is_some_and(|c| c.settling()),
            self.surface.busy,
        );
        let settling = self.refining.is_some()
            || view.moving
            || self.surface.busy
            || self.busy.is_some()
            || state.is_some_and(|c| c.settling());
        if compare.sliced.is_none() && shown_as != Some(what) {
            let wait = self.save_shot.waiting.take();
            if let Some(wait) = wait {
                self.messages.error(format!(
                    "Save PNG: the view showed something else before both halves filled in: \
                     nothing saved to {}",
                    wait.path.display()
                ));
            }
            return;
        }
        let taken = match (needs, compare.sliced.as_mut()) {
            (Needs::Ready, Some(sliced)) => CompareResources::write(render_state, |c, v| {
                c.draw_save_next(render_state, &v.renderer, sliced)
            })
            .unwrap_or_else(|| Some(Err("the compare is not ready".into())))
            .map(|r| (r, SLICED)),
            (Needs::Ready, None) => CompareResources::write(render_state, |c, _| {
                c.shown_picture(render_state, what, &view, &settings)
            })
            .flatten()
            .map(|r| (r, COPIED)),
            _ => None,
        };
        if let Some((taken, how)) = taken {
            let path = wait.path.display().to_string();
            self.finish_wait(
                ctx,
                render_state,
                taken.map_err(|e| format!("{path}: {e}")),
                how,
            );
            return;
        }
        // Told from the frame after the click's (the click's own line says what it waits for).
        if let Needs::Wait(reason) = needs
            && compare.told != reason
        {
            compare.told = reason;
        }
        if let Needs::Wait(reason) = needs
            && wait.frames > 0
            && std::mem::replace(&mut compare.last_told, reason) != reason
        {
            let shown = std::path::absolute(&wait.path).unwrap_or(wait.path.clone());
            self.messages
                .info(format!("saving {}… ({reason})", shown.display()));
        }
        // Slices still to draw are progress; a view that stays still without its picture, or
        // grids that never come, end the wait.
        let drawing = needs == Needs::Ready
            && compare
                .sliced
                .as_ref()
                .is_some_and(|sliced| sliced.missing.is_none());
        let missing = compare.sliced.as_ref().and_then(|sliced| sliced.missing);
        let step = wait.step(settling || drawing || matches!(needs, Needs::Wait(_)));
        if step != WaitStep::Render {
            ctx.request_repaint();
            return;
        }
        let Some(wait) = self.save_shot.waiting.take() else {
            return;
        };
        if needs == Needs::NoGrids {
            self.messages.error(format!(
                "Save PNG: the compare's grids are not built (the view has none to show): \
                 nothing saved to {}",
                wait.path.display()
            ));
            return;
        }
        if let Some(missing) = missing {
            self.messages.error(format!(
                "Save PNG: the compare has no {} to draw yet: nothing saved to {}",
                missing.trim_start_matches("the "),
                wait.path.display()
            ));
            return;
        }
        // The view still and complete without giving its picture: rendered, as before.
        let size = match what {
            CompareView::SideBySide(_) => {
                (2 * view.width + crate::picture::compare::GAP, view.height)
            }
            CompareView::Difference(_) => (view.width, view.height),
        };
        let rendered = crate::ui::window_screenshot::compare_screenshot(
            render_state,
            what,
            view.camera,
            size,
            &settings,
        )
        .map_err(|e| format!("{}: {e:#}", wait.path.display()));
        self.save_shot.waiting = Some(wait);
        self.finish_wait(ctx, render_state, rendered, RENDERED);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::grid::difference::DifferenceMeasure;

    /// The Points view side by side needs nothing built; the other views and the Difference
    /// view need the grids, waited for while they come and refused when none come; Surface
    /// waits for its surfaces too.
    #[test]
    fn a_compare_picture_waits_for_what_the_view_builds() {
        let points = CompareView::SideBySide(ViewKind::Points);
        let surface = CompareView::SideBySide(ViewKind::Surface);
        let volume = CompareView::SideBySide(ViewKind::Volume);
        let difference = CompareView::Difference(DifferenceMeasure::ALL[0]);
        assert_eq!(needs(points, false, false, true), Needs::Ready);
        for what in [surface, volume, difference] {
            assert_eq!(needs(what, false, true, false), Needs::Wait(WAIT_GRIDS));
            assert_eq!(needs(what, false, false, false), Needs::NoGrids);
            assert_eq!(needs(what, true, false, false), Needs::Ready);
        }
        assert_eq!(
            needs(surface, true, false, true),
            Needs::Wait(WAIT_SURFACES)
        );
        assert_eq!(needs(volume, true, false, true), Needs::Ready);
        assert_eq!(needs(difference, true, true, true), Needs::Ready);
    }
}
