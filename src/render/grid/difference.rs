//! The difference of two density grids built in one box: where B is louder or denser than A
//! (issue 17).
//!
//! Reads: the density grids of A and B (same dims and box, see `VoxelizeRequest::grid_box`)
//! and their normalization statistics. Writes: both grids on one scale, their signed
//! difference per voxel, a level-weighted difference per time-frequency column, and a grid the
//! volume view draws with the diverging palette. How: shaders/grid/difference.wgsl, one
//! compute pass per stage.
//!
//! **One scale.** Each grid is normalized by its own reference sum (the 99th percentile of its
//! loudness sums), so a louder master would look the same as a quiet one. Here both are put on
//! the larger reference: `scaled = density * reference / max(reference_a, reference_b)`, so
//! density means the same loudness sum in both (exactly, below each grid's own clamp at 1; its
//! top 1 % stays clamped).
//!
//! **What "louder" means.** y is level, so a copy 6 dB louder is the same cloud moved up the
//! level axis (and with larger scalars): its density difference is a dipole, negative below and
//! positive above, and says "denser here", not "louder". Two measures therefore:
//! - *density*: `B - A` per voxel on the shared scale: where B's points pile up more.
//! - *level*: per time-frequency column, `sum_j level_j * (B - A)`, with `level_j` the height of
//!   voxel row j in the box (0 at the shared floor, 1 at the top). A column is louder in B when
//!   its loudness sits higher on the level axis or is larger; moving every point up, or making
//!   every scalar larger, makes it positive. The view shows each column's value on every voxel
//!   where A or B has density above [`PRESENCE_THRESHOLD`].
//!
//! **Shown grid.** `t = clamp(value / range, -1, 1)`; the volume draws `|t|` as its density and
//! `0.5 - t / 2` as its hp, so the hp palette (red, orange, white, light blue, deep blue) is the
//! diverging map: warm where B is louder, cool where A is, transparent at zero.

use glam::{UVec3, Vec3};
use thiserror::Error;
use wgpu::util::DeviceExt;

use crate::render::gpu::layouts::{storage_entry, uniform_entry, whole_buffer_entries};
use crate::render::gpu::readback::ReadbackError;
use crate::render::grid::VoxelGrid;
use crate::render::grid::voxelize::VoxelStats;
pub use crate::render::grid::voxelize_cpu::shared_scales;
use crate::render::shaders;

/// A voxel counts as part of a song (for the level measure's view) above this shared-scale
/// density: 1 % of the reference sum.
pub const PRESENCE_THRESHOLD: f32 = 0.01;
/// The signed range shown is this quantile of the non-zero magnitudes.
pub const RANGE_QUANTILE: f64 = 0.99;
const WORKGROUP: u32 = 256;

/// Keep in sync with `DifferenceParams` in shaders/grid/difference.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DifferenceParams {
    dims: [u32; 4],
    /// x: scale of A, y: scale of B, z: signed range, w: presence threshold.
    scales: [f32; 4],
    /// x: measure (0 density, 1 level).
    options: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<DifferenceParams>() == 48);

/// Which difference the view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DifferenceMeasure {
    /// B - A per voxel, on the shared scale.
    #[default]
    Density,
    /// The level-weighted difference of each time-frequency column.
    Level,
}

impl DifferenceMeasure {
    pub const ALL: [DifferenceMeasure; 2] = [DifferenceMeasure::Density, DifferenceMeasure::Level];

    pub fn name(self) -> &'static str {
        match self {
            DifferenceMeasure::Density => "density",
            DifferenceMeasure::Level => "level",
        }
    }

    pub fn parse(text: &str) -> Option<Self> {
        crate::parse_value(text)
    }

    /// What the legend says the value is.
    pub fn describe(self) -> &'static str {
        match self {
            DifferenceMeasure::Density => "density B - A",
            DifferenceMeasure::Level => "level-weighted B - A",
        }
    }

    pub fn index(self) -> u32 {
        match self {
            DifferenceMeasure::Density => 0,
            DifferenceMeasure::Level => 1,
        }
    }
}

command_line_names!(DifferenceMeasure, |measure| measure.name());

#[derive(Debug, Error)]
pub enum DifferenceError {
    #[error(
        "the two grids differ in shape ({a_dims} and {b_dims} voxels) or box; build both in one box"
    )]
    Mismatch { a_dims: String, b_dims: String },
    #[error("difference: {0}")]
    Readback(#[from] ReadbackError),
}

/// The level weight of voxel row `j` of `ny`. Keep in sync with `level_weight` in difference.wgsl.
pub fn level_weight(j: u32, ny: u32) -> f32 {
    (j as f32 + 0.5) / ny as f32
}

/// CPU mirror of `rescale` and `density_difference`: `b * scale_b - a * scale_a`, each product
/// rounded to f32 first, as the shader does.
pub fn reference_difference(a: &[f32], b: &[f32], scale_a: f32, scale_b: f32) -> Vec<f32> {
    a.iter()
        .zip(b)
        .map(|(&a, &b)| {
            let (sa, sb) = (a * scale_a, b * scale_b);
            sb - sa
        })
        .collect()
}

/// CPU mirror of `level_columns` (summed in f64; the shader's f32 sum differs by rounding).
pub fn reference_columns(difference: &[f32], dims: UVec3) -> Vec<f32> {
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let mut columns = vec![0.0f32; nx * nz];
    for k in 0..nz {
        for i in 0..nx {
            let mut total = 0.0f64;
            for j in 0..ny {
                let voxel = i + nx * (j + ny * k);
                total += f64::from(level_weight(j as u32, dims.y)) * f64::from(difference[voxel]);
            }
            columns[i + nx * k] = total as f32;
        }
    }
    columns
}

/// The signed range to show: the [`RANGE_QUANTILE`] of the non-zero magnitudes (a tiny positive
/// value when all are zero, so the legend still reads `±0`).
pub fn signed_range(values: &[f32]) -> f32 {
    let mut magnitudes: Vec<f32> = values
        .iter()
        .map(|v| v.abs())
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    if magnitudes.is_empty() {
        return f32::MIN_POSITIVE;
    }
    let rank =
        ((RANGE_QUANTILE * magnitudes.len() as f64).ceil() as usize).clamp(1, magnitudes.len()) - 1;
    let (_, value, _) = magnitudes.select_nth_unstable_by(rank, f32::total_cmp);
    *value
}

/// Where and how much the shown grid is tinted: `(|t|, 0.5 - t / 2)` for a value. Keep in sync
/// with `shade` in difference.wgsl.
pub fn shade_value(value: f32, range: f32) -> (f32, f32) {
    let t = (value / range).clamp(-1.0, 1.0);
    (t.abs(), 0.5 - 0.5 * t)
}

/// The result of a build: both grids on one scale, the differences and the shown grid.
pub struct DifferenceGrids {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub scale_a: f32,
    pub scale_b: f32,
    /// A and B on the shared scale (their own hp_mean), for the compare views.
    pub scaled_a: VoxelGrid,
    pub scaled_b: VoxelGrid,
    /// `f32` per voxel: B - A on the shared scale.
    pub difference: wgpu::Buffer,
    /// `f32` per column (i + dims.x * k): the level-weighted difference.
    pub columns: wgpu::Buffer,
    /// What the volume view draws (|t| as density, the diverging position as hp).
    pub shown: VoxelGrid,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl DifferenceGrids {
    pub fn column_count(&self) -> u64 {
        u64::from(self.dims.x) * u64::from(self.dims.z)
    }

    /// B - A per voxel (waits for the GPU).
    pub fn read_difference(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<f32>, ReadbackError> {
        self.shown.read_field(device, queue, &self.difference)
    }

    /// The level-weighted difference per column (waits for the GPU).
    pub fn read_columns(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<f32>, ReadbackError> {
        let bytes = crate::render::gpu::readback::read_buffer(
            device,
            queue,
            "difference::columns_readback",
            &self.columns,
            self.column_count() * 4,
        )?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }
}

/// The difference pipelines, built once per device.
pub struct DifferencePass {
    layout: wgpu::BindGroupLayout,
    rescale: wgpu::ComputePipeline,
    density_difference: wgpu::ComputePipeline,
    level_columns: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
}

const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;

fn dispatch_size(invocations: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(WORKGROUP);
    let x = groups.clamp(1, 65535);
    (x, groups.div_ceil(x))
}

impl DifferencePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "difference", &shaders::difference());
        let mut entries = vec![uniform_entry(0, COMPUTE)];
        entries.push(storage_entry(1, COMPUTE, true));
        entries.push(storage_entry(2, COMPUTE, true));
        entries.extend((3..=8).map(|b| storage_entry(b, COMPUTE, false)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("difference::layout"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("difference::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&format!("difference::{entry}")),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            rescale: pipeline("rescale"),
            density_difference: pipeline("density_difference"),
            level_columns: pipeline("level_columns"),
            shade: pipeline("shade"),
            layout,
        }
    }

    /// Puts `a` and `b` on one scale and computes both differences; the shown grid is filled by
    /// [`DifferencePass::shade`]. Submits the work; does not wait.
    pub fn build(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        a: (&VoxelGrid, &VoxelStats),
        b: (&VoxelGrid, &VoxelStats),
    ) -> Result<DifferenceGrids, DifferenceError> {
        let ((grid_a, stats_a), (grid_b, stats_b)) = (a, b);
        if grid_a.dims != grid_b.dims
            || grid_a.box_min != grid_b.box_min
            || grid_a.box_max != grid_b.box_max
        {
            return Err(DifferenceError::Mismatch {
                a_dims: format!("{}x{}x{}", grid_a.dims.x, grid_a.dims.y, grid_a.dims.z),
                b_dims: format!("{}x{}x{}", grid_b.dims.x, grid_b.dims.y, grid_b.dims.z),
            });
        }
        let dims = grid_a.dims;
        let voxels = grid_a.voxel_count();
        let (scale_a, scale_b) = shared_scales(stats_a, stats_b);
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let storage = |label: &str, count: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: count.max(1) * 4,
                usage,
                mapped_at_creation: false,
            })
        };
        let scaled_a = storage("difference::scaled_a", voxels);
        let scaled_b = storage("difference::scaled_b", voxels);
        let difference = storage("difference::difference", voxels);
        let columns = storage("difference::columns", u64::from(dims.x) * u64::from(dims.z));
        let shown_density = storage("difference::shown_density", voxels);
        let shown_hp = storage("difference::shown_hp", voxels);
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("difference::params"),
            contents: bytemuck::bytes_of(&DifferenceParams {
                dims: dims.extend(0).into(),
                scales: [scale_a, scale_b, 1.0, PRESENCE_THRESHOLD],
                options: [0; 4],
            }),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let buffers = [
            &params,
            &grid_a.density,
            &grid_b.density,
            &scaled_a,
            &scaled_b,
            &difference,
            &columns,
            &shown_density,
            &shown_hp,
        ];
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("difference::bind_group"),
            layout: &self.layout,
            entries: &whole_buffer_entries(&buffers),
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("difference::build"),
        });
        let voxel_groups = dispatch_size(voxels as u32);
        let column_groups = dispatch_size(dims.x * dims.z);
        for (label, pipeline, (x, y)) in [
            ("difference::rescale", &self.rescale, voxel_groups),
            (
                "difference::density_difference",
                &self.density_difference,
                voxel_groups,
            ),
            (
                "difference::level_columns",
                &self.level_columns,
                column_groups,
            ),
        ] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        queue.submit([encoder.finish()]);
        let grid = |density: wgpu::Buffer, hp_mean: wgpu::Buffer| VoxelGrid {
            dims,
            box_min: grid_a.box_min,
            box_max: grid_a.box_max,
            density,
            hp_mean,
        };
        Ok(DifferenceGrids {
            dims,
            box_min: grid_a.box_min,
            box_max: grid_a.box_max,
            scale_a,
            scale_b,
            scaled_a: grid(scaled_a, grid_a.hp_mean.clone()),
            scaled_b: grid(scaled_b, grid_b.hp_mean.clone()),
            difference,
            columns,
            shown: grid(shown_density, shown_hp),
            params,
            bind_group,
        })
    }

    /// Fills the shown grid with `measure` over the signed `range` (positive). Submits; does not
    /// wait.
    pub fn shade(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grids: &DifferenceGrids,
        measure: DifferenceMeasure,
        range: f32,
    ) {
        let params = DifferenceParams {
            dims: grids.dims.extend(0).into(),
            scales: [
                grids.scale_a,
                grids.scale_b,
                range.max(f32::MIN_POSITIVE),
                PRESENCE_THRESHOLD,
            ],
            options: [measure.index(), 0, 0, 0],
        };
        queue.write_buffer(&grids.params, 0, bytemuck::bytes_of(&params));
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("difference::shade"),
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("difference::shade"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.shade);
            pass.set_bind_group(0, &grids.bind_group, &[]);
            let (x, y) = dispatch_size(grids.shown.voxel_count() as u32);
            pass.dispatch_workgroups(x, y, 1);
        }
        queue.submit([encoder.finish()]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_against_itself_is_zero_on_the_cpu() {
        let a = [0.0, 0.25, 1.0, 0.3];
        assert!(
            reference_difference(&a, &a, 1.0, 1.0)
                .iter()
                .all(|d| *d == 0.0)
        );
    }

    #[test]
    fn shared_scale_uses_the_larger_reference() {
        let stats = |reference_sum| VoxelStats {
            nonempty: 1,
            reference_sum,
            clamped: 0,
        };
        assert_eq!(shared_scales(&stats(2.0), &stats(4.0)), (0.5, 1.0));
    }

    #[test]
    fn shading_is_diverging() {
        assert_eq!(shade_value(0.0, 1.0), (0.0, 0.5));
        assert_eq!(shade_value(2.0, 1.0), (1.0, 0.0));
        assert_eq!(shade_value(-0.5, 1.0), (0.5, 0.75));
        assert_eq!(signed_range(&[0.0, 0.0]), f32::MIN_POSITIVE);
        assert_eq!(signed_range(&[1.0, -3.0, 0.0]), 3.0);
    }
}
