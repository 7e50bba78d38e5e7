//! The A/B compare's side of the bridge: [`CompareResources`] sits in egui_wgpu's callback
//! resources beside the window's [`ViewResources`] (whose renderer it borrows) and holds the
//! [`CompareScene`] and one offscreen target per half; [`CompareCallback`] renders a half into
//! its target only when what it shows changed and composites it into its viewport: a job of the
//! bridge's one paint callback, as the 3D view's is (the same [`Offscreen`] target and
//! [`FrameCache`]).

use eframe::egui_wgpu::{self, CallbackResources};

mod save;
pub(in crate::ui) use save::CompareSliced;

use super::{Offscreen, OffscreenJob, Prepare, ViewResources};
use crate::data::cloud::PointCloud;
use crate::render::compare::{BuiltGrids, CompareScene};
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::grid::voxelize::VoxelSettings;
use crate::render::points::PointBuffers;
use crate::render::scene::{RenderSettings, ViewKind};
use crate::render::surface::SurfaceSettings;
use crate::render::surface::state::ExtractionStatus;
use crate::ui::compare_refine::{CompareRefine, Refined};
use crate::ui::frame_cache::{FrameCache, RenderKey};
use crate::view::frame_view::FrameView;

/// One half's offscreen target and what it holds.
struct Half {
    offscreen: Offscreen,
    cache: FrameCache,
}

/// The compare's GPU state, in egui_wgpu's callback resources.
pub struct CompareResources {
    pub(in crate::ui) scene: Option<CompareScene>,
    /// A, B and the difference.
    halves: [Half; 3],
    /// Bumped when the scene or its grids change.
    revision: u64,
    /// The halves' points at rest, a slice a frame within one shared budget
    /// (`ui/compare_refine.rs`).
    refine: CompareRefine,
}

impl CompareResources {
    /// Runs `f` with the compare's resources (made on first use) and the window's, under one
    /// write lock of egui_wgpu's renderer. None before the window's are installed.
    pub(in crate::ui) fn write<T>(
        render_state: &egui_wgpu::RenderState,
        f: impl FnOnce(&mut CompareResources, &ViewResources) -> T,
    ) -> Option<T> {
        let mut renderer = render_state.renderer.write();
        let resources = &mut renderer.callback_resources;
        if resources.get::<CompareResources>().is_none() {
            let half = || Half {
                offscreen: Offscreen::new(&render_state.device, render_state.target_format),
                cache: FrameCache::default(),
            };
            resources.insert(CompareResources {
                scene: None,
                halves: [half(), half(), half()],
                revision: 0,
                refine: CompareRefine::default(),
            });
        }
        let mut compare = resources.remove::<CompareResources>()?;
        let result = resources
            .get::<ViewResources>()
            .map(|view| f(&mut compare, view));
        resources.insert(compare);
        result
    }

    /// Makes A and B (already on their union axes, their point buffers filled on a thread)
    /// the compare's scene; returns the scene it replaces, for the caller to drop where it
    /// costs the window nothing.
    pub(in crate::ui) fn build(
        &mut self,
        view: &ViewResources,
        a: PointCloud,
        b: PointCloud,
        buffers: [PointBuffers; 2],
    ) -> Option<CompareScene> {
        let scene = CompareScene::from_buffers(&view.device, &view.renderer, a, b, buffers);
        self.revision += 1;
        self.scene.replace(scene)
    }

    pub(in crate::ui) fn clear(&mut self) {
        self.scene = None;
        self.revision += 1;
    }

    /// Whether the scene's grids are built with `voxels` (or there is no scene to build for).
    pub(in crate::ui) fn grids_match(&self, voxels: &VoxelSettings) -> bool {
        self.scene
            .as_ref()
            .is_none_or(|scene| scene.grids_built_for(voxels))
    }

    /// The measure the Difference view shows, which a build of the grids on a thread needs
    /// (None without a scene).
    pub(in crate::ui) fn measure(&self) -> Option<DifferenceMeasure> {
        self.scene.as_ref().map(|scene| scene.measure())
    }

    /// Installs grids built on a thread (`render::compare::build_grids`) in the scene.
    pub(in crate::ui) fn install_grids(&mut self, view: &ViewResources, built: BuiltGrids) {
        if let Some(scene) = self.scene.as_mut() {
            scene.install_grids(&view.device, &view.renderer, built);
            self.revision += 1;
        }
    }

    /// The surfaces of the two halves in the Surface view with `settings`: their status as
    /// one (extracting while either is; the larger mesh's counts, so "no surface" only when
    /// neither has one) and each half's triangles once the mesh on screen is the one
    /// `settings` ask of its grid. None without grids.
    pub(in crate::ui) fn surface_status(
        &self,
        settings: &SurfaceSettings,
    ) -> Option<CompareSurfaces> {
        let scene = self.scene.as_ref()?;
        let halves = [&scene.data_a, &scene.data_b];
        let statuses = halves.map(|data| data.surface.status());
        let shown = halves.map(|data| {
            let grid = data.grid.as_ref()?;
            data.surface
                .shows(grid, settings)
                .then(|| data.surface.counts().map(|c| c.triangles()))
                .flatten()
        });
        if halves.iter().any(|d| d.grid.is_none()) {
            return None;
        }
        let [a, b] = statuses;
        let larger =
            if b.counts.map_or(0, |c| c.triangles()) > a.counts.map_or(0, |c| c.triangles()) {
                &b
            } else {
                &a
            };
        Some(CompareSurfaces {
            status: ExtractionStatus {
                counts: larger.counts,
                error: a.error.clone().or(b.error.clone()),
                extracting: a.extracting || b.extracting,
            },
            triangles: shown,
        })
    }

    /// The fraction of the halves' points drawn while they fill in (None when complete).
    pub(in crate::ui) fn refining(&self) -> Option<f32> {
        self.refine.progress()
    }

    /// The halves' last refinement, once complete.
    pub(in crate::ui) fn refine_finished(&mut self) -> Option<Refined> {
        self.refine.take_finished()
    }

    /// Moves the Difference view to `measure` (once its grids are built).
    pub(in crate::ui) fn set_measure(&mut self, view: &ViewResources, measure: DifferenceMeasure) {
        if let Some(scene) = self.scene.as_mut()
            && scene.grids.as_ref().is_some_and(|g| g.measure != measure)
        {
            scene.set_measure(&view.device, &view.queue, &view.renderer, measure);
            self.revision += 1;
        }
    }
}

/// The compare's surfaces as the window reads them once a frame.
pub(in crate::ui) struct CompareSurfaces {
    pub(in crate::ui) status: ExtractionStatus,
    /// A's and B's triangles when each shows the surface asked for.
    pub(in crate::ui) triangles: [Option<u32>; 2],
}

/// One half of the compare (0 A, 1 B) or the difference (2).
pub struct CompareCallback {
    pub side: usize,
    pub view: FrameView,
    pub settings: RenderSettings,
}

impl OffscreenJob for CompareCallback {
    fn render(&self, gpu: Prepare<'_>, resources: &mut CallbackResources) {
        let Some(mut compare) = resources.remove::<CompareResources>() else {
            return;
        };
        if let Some(view_resources) = resources.get::<ViewResources>() {
            let CompareResources {
                scene,
                halves,
                revision,
                refine,
            } = &mut compare;
            let half = &mut halves[self.side];
            if half
                .offscreen
                .ensure_size(gpu.device, self.view.width, self.view.height)
            {
                half.cache.invalidate();
            }
            // Both halves' keys: they share one view and settings, and the budget.
            let keys = [0, 1, 2]
                .map(|side| RenderKey::new(&self.view, &self.settings, Some(side), *revision));
            let key = keys[self.side].clone();
            let data = scene.as_ref().and_then(|s| match self.side {
                0 => Some(&s.data_a),
                1 => Some(&s.data_b),
                _ => s.grids.as_ref().map(|g| &g.data),
            });
            let totals = scene
                .as_ref()
                .map(|s| [s.data_a.points.total, s.data_b.points.total]);
            if let Some(target) = half.offscreen.target()
                && half.cache.begin(&key)
            {
                let progressive = if let (Some(data), Some(totals)) = (data, totals)
                    && self.side < 2
                    && !self.view.moving
                    && crate::render::scene::draws_points_at_rest(&self.settings, data)
                    && refine.wants(self.side, totals)
                {
                    // At rest, each half's points a slice a frame, the two within one frame's
                    // budget; the window asks for the next frame until both are complete.
                    let complete = refine.frame(
                        self.side,
                        (gpu.device, gpu.queue, gpu.encoder, &view_resources.renderer),
                        target,
                        data,
                        [&keys[0], &keys[1]],
                        totals,
                        &self.view,
                        &self.settings,
                    );
                    half.cache.finish(key.clone(), complete);
                    if !complete && let Some(ctx) = &view_resources.repaint {
                        ctx.request_repaint();
                    }
                    true
                } else {
                    false
                };
                if !progressive {
                    // Moving, a surface or a volume, or clouds small enough for one frame: the
                    // half drawn whole, and a refinement left unfinished forgotten.
                    if self.side < 2 {
                        refine.set_aside(self.side);
                    }
                    view_resources.renderer.render(
                        gpu.queue,
                        gpu.encoder,
                        target,
                        data,
                        &self.view,
                        &self.settings,
                    );
                    let pending = data.is_some_and(|d| {
                        self.settings.view == ViewKind::Surface && d.surface.needs_another_frame()
                    });
                    half.cache.finish(key, !pending);
                }
            }
        }
        resources.insert(compare);
    }

    fn offscreen<'a>(&self, resources: &'a CallbackResources) -> Option<&'a Offscreen> {
        resources
            .get::<CompareResources>()
            .map(|compare| &compare.halves[self.side].offscreen)
    }
}
