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
use crate::render::grid::difference::{
    DifferenceError, DifferenceGrids, DifferenceMeasure, signed_range,
};
use crate::render::grid::voxelize::{VoxelSettings, VoxelizeError, VoxelizeRequest};
use crate::render::grid::voxelize_cpu::grid_box;
use crate::render::scene::{Renderer, SceneData};

#[derive(Debug, Error)]
pub enum CompareBuildError {
    #[error("{file}: voxelizing: {source}")]
    Voxelize { file: String, source: VoxelizeError },
    #[error(transparent)]
    Difference(#[from] DifferenceError),
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
        let data_a = SceneData::new(device, renderer, &a);
        let data_b = SceneData::new(device, renderer, &b);
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
        let (min_a, max_a) = grid_box(&self.a.points);
        let (min_b, max_b) = grid_box(&self.b.points);
        (min_a.min(min_b), max_a.max(max_b))
    }

    /// Builds both grids in the shared box, their difference and the shown grid, unless they
    /// exist for `settings`. Waits for the GPU (the statistics and the ranges are read back).
    /// Returns whether anything was built.
    pub fn ensure_grids(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        settings: &VoxelSettings,
    ) -> Result<bool, CompareBuildError> {
        let resolution = settings.resolution_for(self.a.meta.mode);
        let key = (resolution, settings.smoothing_sigma.to_bits());
        if self.grids.as_ref().is_some_and(|g| g.key == key) {
            return Ok(false);
        }
        let measure = self.grids.as_ref().map(|g| g.measure).unwrap_or_default();
        self.grids = None;
        let shared_box = self.shared_box();
        let voxelize = |cloud: &PointCloud| {
            renderer
                .voxelize
                .voxelize(
                    device,
                    queue,
                    &VoxelizeRequest::new(&cloud.points, resolution, settings.smoothing_sigma)
                        .in_box(Some(shared_box)),
                )
                .map_err(|source| CompareBuildError::Voxelize {
                    file: cloud.path.display().to_string(),
                    source,
                })
        };
        let (grid_a, stats_a) = voxelize(&self.a)?;
        let (grid_b, stats_b) = voxelize(&self.b)?;
        let grids =
            renderer
                .difference
                .build(device, queue, (&grid_a, &stats_a), (&grid_b, &stats_b))?;
        let difference = grids
            .read_difference(device, queue)
            .map_err(DifferenceError::from)?;
        let columns = grids
            .read_columns(device, queue)
            .map_err(DifferenceError::from)?;
        let ranges = [signed_range(&difference), signed_range(&columns)];
        let scaled = |grid: &crate::render::grid::VoxelGrid| crate::render::grid::VoxelGrid {
            dims: grid.dims,
            box_min: grid.box_min,
            box_max: grid.box_max,
            density: grid.density.clone(),
            hp_mean: grid.hp_mean.clone(),
        };
        self.data_a.set_grid(
            device,
            renderer,
            scaled(&grids.scaled_a),
            Some(stats_a),
            resolution,
            settings,
        );
        self.data_b.set_grid(
            device,
            renderer,
            scaled(&grids.scaled_b),
            Some(stats_b),
            resolution,
            settings,
        );
        let mut data = SceneData::new(device, renderer, &self.a);
        data.set_grid(
            device,
            renderer,
            scaled(&grids.shown),
            None,
            resolution,
            settings,
        );
        let mut built = CompareGrids {
            grids,
            data,
            measure,
            ranges,
            difference_cpu: difference,
            columns_cpu: columns,
            key,
        };
        renderer
            .difference
            .shade(device, queue, &built.grids, measure, built.range());
        built.measure = measure;
        self.grids = Some(built);
        Ok(true)
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
