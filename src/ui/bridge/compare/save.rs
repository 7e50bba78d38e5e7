//! Save PNG of the A/B compare without drawing it whole in the frame of the click
//! (`ui/compare_save.rs` decides when): at the view's size, the halves the view holds complete
//! copied into one picture ([`CompareResources::shown_picture`]); at a chosen size, both halves
//! drawn for the save over frames into targets of their own, each half's points a slice a
//! frame within one shared budget as the view draws them (`ui/compare_refine.rs`), and the
//! picture composed once both are complete ([`CompareResources::draw_save_next`]). Either way
//! the labels, titles and colour keys are those of every compare picture
//! (`picture::compare::compose`) and the read-back goes to the save's thread.

use eframe::egui_wgpu;

use super::CompareResources;
use crate::picture::PendingPicture;
use crate::picture::compare::{CompareView, GAP, compose, difference_settings, half_width};
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{RenderSettings, ViewKind, draws_points_at_rest};
use crate::ui::compare_refine::CompareRefine;
use crate::ui::frame_cache::RenderKey;
use crate::view::frame_view::FrameView;

/// The compare picture drawn for a save over frames, at the camera and settings of the click.
pub(in crate::ui) struct CompareSliced {
    what: CompareView,
    /// A's and B's pictures (the difference's in the first).
    targets: [RenderTarget; 2],
    /// Each half's points a slice a frame, the two within one budget.
    refine: CompareRefine,
    /// A half's view (the whole picture's in the Difference view), at rest.
    view: FrameView,
    /// The picture's size.
    size: (u32, u32),
    /// The settings of the click.
    settings: RenderSettings,
    /// The halves complete so far.
    done: [bool; 2],
    /// What the last frame could not draw for want of it (the grids, the surfaces), if any.
    pub(in crate::ui) missing: Option<&'static str>,
}

impl CompareSliced {
    /// A picture of `size` of `what` from the camera of `view`; why not when two halves do not
    /// fit its width.
    pub(in crate::ui) fn new(
        device: &wgpu::Device,
        what: CompareView,
        view: &FrameView,
        size: (u32, u32),
        settings: RenderSettings,
    ) -> Result<Self, String> {
        let width = match what {
            CompareView::SideBySide(_) => half_width(size.0).map_err(|e| e.to_string())?,
            CompareView::Difference(_) => size.0,
        };
        let mut view = FrameView::at_rest(view.camera, view.world_from_data, width, size.1);
        view.frame_index = 0;
        let target = || RenderTarget::new(device, view.width, view.height);
        // The Difference view draws one picture.
        let done = [false, matches!(what, CompareView::Difference(_))];
        Ok(Self {
            what,
            targets: [target(), target()],
            refine: CompareRefine::default(),
            view,
            size,
            settings,
            done,
            missing: None,
        })
    }
}

fn gpu_of(render_state: &egui_wgpu::RenderState) -> GpuContext {
    GpuContext {
        adapter: render_state.adapter.clone(),
        device: render_state.device.clone(),
        queue: render_state.queue.clone(),
    }
}

/// What a half (or the difference) is drawn with in a picture of `what`.
fn drawn_settings(what: CompareView, base: &RenderSettings) -> RenderSettings {
    match what {
        CompareView::SideBySide(view) => RenderSettings {
            view,
            ..base.clone()
        },
        CompareView::Difference(_) => difference_settings(base),
    }
}

impl CompareResources {
    /// The picture of `what` the view shows, when its halves (the difference) hold it
    /// complete at `view` (a half's, as the window drew it) and `settings`: their copies
    /// submitted with the compare picture's labels. None while they fill in, wait for their
    /// grids or surfaces, or show something else.
    pub(in crate::ui) fn shown_picture(
        &self,
        render_state: &egui_wgpu::RenderState,
        what: CompareView,
        view: &FrameView,
        settings: &RenderSettings,
    ) -> Option<Result<PendingPicture, String>> {
        let scene = self.scene.as_ref()?;
        let mut at_rest = *view;
        at_rest.moving = false;
        let drawn = drawn_settings(what, settings);
        let sides: &[usize] = match what {
            CompareView::SideBySide(_) => &[0, 1],
            CompareView::Difference(measure) => {
                if scene.grids.as_ref()?.measure != measure {
                    return None;
                }
                &[2]
            }
        };
        for &side in sides {
            let half = &self.halves[side];
            let held = half.cache.holds()?;
            let mut wanted = RenderKey::new(&at_rest, &drawn, Some(side as u64), self.revision);
            // What only a moving frame or the playhead changes.
            wanted.settings.points.max_points_moving = held.settings.points.max_points_moving;
            wanted.settings.markers = held.settings.markers.clone();
            wanted.settings.surface_detail = held.settings.surface_detail;
            if *held != wanted {
                return None;
            }
            let target = half.offscreen.target()?;
            if (target.width, target.height) != (view.width, view.height) {
                return None;
            }
        }
        let targets = match what {
            CompareView::SideBySide(_) => [0, 1].map(|s| self.halves[s].offscreen.target()),
            CompareView::Difference(_) => [2, 2].map(|s| self.halves[s].offscreen.target()),
        };
        let [Some(first), Some(second)] = targets else {
            return None;
        };
        let size = match what {
            CompareView::SideBySide(_) => (2 * view.width + GAP, view.height),
            CompareView::Difference(_) => (view.width, view.height),
        };
        let gpu = gpu_of(render_state);
        let picture = compose(
            &gpu,
            scene,
            what,
            [first, second],
            &at_rest,
            size,
            settings,
            settings.show_box,
            None,
        );
        Some(picture.map_err(|e| format!("{e:#}")))
    }

    /// Draws the next part of `sliced`'s picture. `Some` once it is complete (its copies
    /// submitted with the labels), or why nothing can be saved; `None`: draw again next frame
    /// (its points still coming, or the grids or surfaces it needs not there yet: the window
    /// builds them in the background, never this).
    pub(in crate::ui) fn draw_save_next(
        &mut self,
        render_state: &egui_wgpu::RenderState,
        renderer: &crate::render::scene::Renderer,
        sliced: &mut CompareSliced,
    ) -> Option<Result<PendingPicture, String>> {
        let Some(scene) = self.scene.as_ref() else {
            return Some(Err("the compare is no longer shown".into()));
        };
        let settings = drawn_settings(sliced.what, &sliced.settings);
        let datas = match sliced.what {
            CompareView::SideBySide(_) => [&scene.data_a, &scene.data_b],
            CompareView::Difference(measure) => {
                let grids = scene.grids.as_ref().filter(|g| g.measure == measure);
                sliced.missing = grids.is_none().then_some("the difference grid");
                let grids = grids?;
                [&grids.data, &grids.data]
            }
        };
        sliced.missing = if settings.view == ViewKind::Points {
            None
        } else if datas.iter().any(|d| d.grid.is_none()) {
            Some("the grids")
        } else if settings.view == ViewKind::Surface
            && datas.iter().any(|d| {
                d.grid
                    .as_ref()
                    .is_some_and(|grid| !d.surface.shows(grid, &settings.surface))
            })
        {
            Some("the surfaces")
        } else {
            None
        };
        if sliced.missing.is_some() {
            return None;
        }
        let device = &render_state.device;
        let queue = &render_state.queue;
        let totals = [scene.data_a.points.total, scene.data_b.points.total];
        sliced.view.frame_index += 1;
        let keys = [0, 1].map(|side| RenderKey::new(&sliced.view, &settings, Some(side), 0));
        for (side, data) in datas.into_iter().enumerate() {
            if sliced.done[side] {
                continue;
            }
            let target = &sliced.targets[side];
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("save_png::compare_slice"),
            });
            let sides_points = matches!(sliced.what, CompareView::SideBySide(_))
                && draws_points_at_rest(&settings, data)
                && sliced.refine.wants(side, totals);
            sliced.done[side] = if sides_points {
                sliced.refine.frame(
                    side,
                    (device, queue, &mut encoder, renderer),
                    target,
                    data,
                    [&keys[0], &keys[1]],
                    totals,
                    &sliced.view,
                    &settings,
                )
            } else {
                renderer.render(
                    queue,
                    &mut encoder,
                    target,
                    Some(data),
                    &sliced.view,
                    &settings,
                );
                true
            };
            queue.submit([encoder.finish()]);
        }
        if !sliced.done.iter().all(|d| *d) {
            return None;
        }
        let gpu = gpu_of(render_state);
        let [first, second] = &sliced.targets;
        let second = match sliced.what {
            CompareView::SideBySide(_) => second,
            CompareView::Difference(_) => first,
        };
        let picture = compose(
            &gpu,
            scene,
            sliced.what,
            [first, second],
            &sliced.view,
            sliced.size,
            &sliced.settings,
            sliced.settings.show_box,
            None,
        );
        Some(picture.map_err(|e| format!("{e:#}")))
    }
}
