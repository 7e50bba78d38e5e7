//! An A/B compare on the GPU: two clouds on one set of axes (`data::compare`), each with its
//! own [`SceneData`], their grids built in one box and put on one scale, and the difference
//! grid the Difference view draws (`grid::difference`).
//!
//! Both grids use the union of the two clouds' grid boxes, so voxel (i, j, k) is the same
//! place in both; both are then scaled onto the larger of the two reference sums, so a density
//! means the same loudness sum in A as in B and equal loudness looks equal. The grids are built
//! when a view needs them and rebuilt only when the voxel settings change.

use glam::Vec3;
use thiserror::Error;

use crate::data::cloud::PointCloud;
use crate::data::compare::{CompareError, on_union_axes};
use crate::render::gpu::frame::FrameBinding;
use crate::render::grid::VoxelGrid;
use crate::render::grid::difference::DifferencePass;
use crate::render::grid::difference::{
    DifferenceError, DifferenceGrids, DifferenceMeasure, signed_range,
};
use crate::render::grid::voxelize::{
    VoxelSettings, VoxelStats, VoxelizeError, VoxelizePass, VoxelizeRequest,
};
use crate::render::grid::voxelize_cpu::grid_box;
use crate::render::points::{PointBuffers, PointsGpu};
use crate::render::scene::{Renderer, SceneData};
use crate::render::surface::driver::wait_polling;

#[derive(Debug, Error)]
pub enum CompareBuildError {
    #[error("{file}: voxelizing: {source}")]
    Voxelize { file: String, source: VoxelizeError },
    #[error(transparent)]
    Difference(#[from] DifferenceError),
    #[error("waiting for the compare grids: {0}")]
    Wait(String),
}

/// The difference of the two grids, ready to draw.
pub struct CompareGrids {
    pub grids: DifferenceGrids,
    /// The Difference view's scene: A's points and box (the union axes) with the shown grid.
    pub data: SceneData,
    pub measure: DifferenceMeasure,
    /// The signed range of each measure ([`signed_range`] of its values), by
    /// [`DifferenceMeasure::ALL`] order.
    pub ranges: [f32; 2],
    /// The differences read back (for read-outs): B - A per voxel, and per column.
    pub difference_cpu: Vec<f32>,
    pub columns_cpu: Vec<f32>,
    key: (u32, u32),
}

impl CompareGrids {
    /// The signed range the shown grid uses now.
    pub fn range(&self) -> f32 {
        self.ranges[self.measure.index() as usize]
    }
}

/// Two clouds compared.
pub struct CompareScene {
    /// A and B, moved onto the union of their axes.
    pub a: PointCloud,
    pub b: PointCloud,
    pub data_a: SceneData,
    pub data_b: SceneData,
    pub grids: Option<CompareGrids>,
}

impl CompareScene {
    /// Puts both clouds on one set of axes and uploads them (no grid yet).
    pub fn new(
        device: &wgpu::Device,
        renderer: &Renderer,
        a: &PointCloud,
        b: &PointCloud,
    ) -> Result<Self, CompareError> {
        let (a, b) = on_union_axes(a, b)?;
        Ok(Self::from_union(device, renderer, a, b))
    }

    /// As [`CompareScene::new`] for clouds already on one set of axes.
    pub fn from_union(
        device: &wgpu::Device,
        renderer: &Renderer,
        a: PointCloud,
        b: PointCloud,
    ) -> Self {
        let buffers = [&a, &b]
            .map(|cloud| PointsGpu::buffers(device, &cloud.points, PointsGpu::chunk_limit(device)));
        Self::from_buffers(device, renderer, a, b, buffers)
    }

    /// As [`CompareScene::from_union`], A's and B's point buffers made beforehand
    /// (`PointsGpu::buffers` with `PointsGpu::chunk_limit`, on a thread beside the window).
    pub fn from_buffers(
        device: &wgpu::Device,
        renderer: &Renderer,
        a: PointCloud,
        b: PointCloud,
        buffers: [PointBuffers; 2],
    ) -> Self {
        let [buffers_a, buffers_b] = buffers;
        let data_a = SceneData::from_buffers(device, renderer, &a, buffers_a);
        let data_b = SceneData::from_buffers(device, renderer, &b, buffers_b);
        Self {
            a,
            b,
            data_a,
            data_b,
            grids: None,
        }
    }

    /// The one grid box of both: the union of their own grid boxes.
    pub fn shared_box(&self) -> (Vec3, Vec3) {
        shared_box(&self.a, &self.b)
    }

    /// The key of the grids `settings` build: (resolution, smoothing bits).
    fn grids_key(&self, settings: &VoxelSettings) -> (u32, u32) {
        (
            settings.resolution_for(self.a.meta.mode),
            settings.smoothing_for(self.a.meta.mode).to_bits(),
        )
    }

    /// Whether the grids are built for `settings`.
    pub fn grids_built_for(&self, settings: &VoxelSettings) -> bool {
        let key = self.grids_key(settings);
        self.grids.as_ref().is_some_and(|g| g.key == key)
    }

    /// The measure the Difference view shows (the default before any grid).
    pub fn measure(&self) -> DifferenceMeasure {
        self.grids.as_ref().map(|g| g.measure).unwrap_or_default()
    }

    /// Builds both grids in the shared box, their difference and the shown grid, unless they
    /// exist for `settings`. Waits for the GPU (the statistics and the ranges are read back).
    /// Returns whether anything was built. The window builds them on a thread instead
    /// ([`build_grids`] with passes of its own, then [`CompareScene::install_grids`]).
    pub fn ensure_grids(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        settings: &VoxelSettings,
    ) -> Result<bool, CompareBuildError> {
        if self.grids_built_for(settings) {
            return Ok(false);
        }
        let measure = self.measure();
        self.grids = None;
        let passes = GridPasses {
            voxelize: &renderer.voxelize,
            difference: &renderer.difference,
            poll_waits: false,
        };
        let built = build_grids(device, queue, &passes, &self.a, &self.b, settings, measure)?;
        self.install_grids(device, renderer, built);
        Ok(true)
    }

    /// Installs grids built by [`build_grids`] for this scene's clouds: A's and B's on one
    /// scale (what the Surface and Volume halves draw; their old surfaces are dropped) and the
    /// Difference view's scene.
    pub fn install_grids(&mut self, device: &wgpu::Device, renderer: &Renderer, built: BuiltGrids) {
        let BuiltGrids {
            grids,
            stats,
            settings,
            measure,
            ranges,
            difference_cpu,
            columns_cpu,
        } = built;
        let [stats_a, stats_b] = stats;
        self.data_a.set_grid(
            device,
            renderer,
            share(&grids.scaled_a),
            Some(stats_a),
            self.a.meta.mode,
            &settings,
        );
        self.data_b.set_grid(
            device,
            renderer,
            share(&grids.scaled_b),
            Some(stats_b),
            self.a.meta.mode,
            &settings,
        );
        let mut data = SceneData::new(device, renderer, &self.a);
        data.set_grid(
            device,
            renderer,
            share(&grids.shown),
            None,
            self.a.meta.mode,
            &settings,
        );
        self.grids = Some(CompareGrids {
            grids,
            data,
            measure,
            ranges,
            difference_cpu,
            columns_cpu,
            key: self.grids_key(&settings),
        });
    }

    /// Shows `measure` in the Difference view (no rebuild: one pass over the grid).
    pub fn set_measure(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        measure: DifferenceMeasure,
    ) {
        if let Some(grids) = &mut self.grids
            && grids.measure != measure
        {
            grids.measure = measure;
            renderer
                .difference
                .shade(device, queue, &grids.grids, measure, grids.range());
        }
    }
}

/// A second handle on a grid's buffers (shared, not copied).
fn share(grid: &VoxelGrid) -> VoxelGrid {
    VoxelGrid {
        dims: grid.dims,
        box_min: grid.box_min,
        box_max: grid.box_max,
        density: grid.density.clone(),
        hp_mean: grid.hp_mean.clone(),
    }
}

/// The passes a grid build runs: the renderer's, or a thread's own ([`OwnGridPasses`]).
pub struct GridPasses<'p> {
    pub voxelize: &'p VoxelizePass,
    pub difference: &'p DifferencePass,
    /// Wait for the GPU by polling (a thread beside the window: a blocking wait holds the
    /// device, and every frame's submission waits behind it); otherwise by blocking.
    pub poll_waits: bool,
}

/// Passes built for one thread (their pipelines are compiled there, off the window's thread).
pub struct OwnGridPasses {
    _frame: FrameBinding,
    voxelize: VoxelizePass,
    difference: DifferencePass,
}

impl OwnGridPasses {
    pub fn new(device: &wgpu::Device) -> Self {
        let frame = FrameBinding::new(device);
        Self {
            voxelize: VoxelizePass::new(device, &frame),
            difference: DifferencePass::new(device),
            _frame: frame,
        }
    }

    /// Its passes, waiting by polling.
    pub fn passes(&self) -> GridPasses<'_> {
        GridPasses {
            voxelize: &self.voxelize,
            difference: &self.difference,
            poll_waits: true,
        }
    }
}

/// Both grids of a compare, their difference shaded with a measure and read back, ready for
/// [`CompareScene::install_grids`]. Only buffers and numbers: it can be built on one thread and
/// installed on another.
pub struct BuiltGrids {
    pub grids: DifferenceGrids,
    /// A's and B's statistics.
    pub stats: [VoxelStats; 2],
    /// The voxel settings they were built with.
    pub settings: VoxelSettings,
    pub measure: DifferenceMeasure,
    pub ranges: [f32; 2],
    pub difference_cpu: Vec<f32>,
    pub columns_cpu: Vec<f32>,
}

/// The union of the grid boxes of `a` and `b` (clouds on one set of axes).
pub fn shared_box(a: &PointCloud, b: &PointCloud) -> (Vec3, Vec3) {
    let (min_a, max_a) = grid_box(&a.points);
    let (min_b, max_b) = grid_box(&b.points);
    (min_a.min(min_b), max_a.max(max_b))
}

/// Builds both grids of `a` and `b` (already on one set of axes) in their shared box, their
/// difference, and shades the shown grid with `measure`. Waits for the GPU (the statistics and
/// the differences are read back): the window runs it on a thread of its own.
pub fn build_grids(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    passes: &GridPasses<'_>,
    a: &PointCloud,
    b: &PointCloud,
    settings: &VoxelSettings,
    measure: DifferenceMeasure,
) -> Result<BuiltGrids, CompareBuildError> {
    let resolution = settings.resolution_for(a.meta.mode);
    let shared_box = shared_box(a, b);
    // Waits for the GPU's work before each read-back, by polling where asked (the read then
    // finds it done instead of blocking the device for all of it).
    let wait = || -> Result<(), CompareBuildError> {
        if passes.poll_waits {
            wait_polling(device, queue).map_err(|e| CompareBuildError::Wait(e.to_string()))?;
        }
        Ok(())
    };
    let voxelize = |cloud: &PointCloud| -> Result<(VoxelGrid, VoxelStats), CompareBuildError> {
        let failed = |source| CompareBuildError::Voxelize {
            file: cloud.path.display().to_string(),
            source,
        };
        let request = VoxelizeRequest::new(
            &cloud.points,
            resolution,
            settings.smoothing_for(a.meta.mode),
        )
        .in_box(Some(shared_box));
        if passes.voxelize.on_cpu() {
            // Built on the CPU's cores and uploaded (voxelize_host.rs): nothing to wait for.
            return passes
                .voxelize
                .voxelize(device, queue, &request)
                .map_err(failed);
        }
        let job = passes.voxelize.prepare(device, &request).map_err(failed)?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("compare::voxelize"),
        });
        passes.voxelize.encode(&mut encoder, &job, None);
        queue.submit([encoder.finish()]);
        wait()?;
        let stats = passes
            .voxelize
            .read_stats(device, queue, &job)
            .map_err(failed)?;
        Ok((VoxelizePass::finish(job), stats))
    };
    let (grid_a, stats_a) = voxelize(a)?;
    let (grid_b, stats_b) = voxelize(b)?;
    let grids = passes
        .difference
        .build(device, queue, (&grid_a, &stats_a), (&grid_b, &stats_b))?;
    wait()?;
    let difference_cpu = grids
        .read_difference(device, queue)
        .map_err(DifferenceError::from)?;
    let columns_cpu = grids
        .read_columns(device, queue)
        .map_err(DifferenceError::from)?;
    let ranges = [signed_range(&difference_cpu), signed_range(&columns_cpu)];
    passes.difference.shade(
        device,
        queue,
        &grids,
        measure,
        ranges[measure.index() as usize],
    );
    Ok(BuiltGrids {
        grids,
        stats: [stats_a, stats_b],
        settings: *settings,
        measure,
        ranges,
        difference_cpu,
        columns_cpu,
    })
}
