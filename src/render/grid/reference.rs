//! [`ReferenceGrid`]: the whole voxelization in f64 on the CPU, built with the pass's own box
//! and voxel arithmetic (`voxelize_cpu.rs`, which mirrors voxelize.wgsl), that the tests and the
//! benchmarks compare the GPU grid with.

use glam::{UVec3, Vec3};

use crate::data::cloud::Point;
use crate::render::grid::voxelize_cpu::{gaussian_weights, grid_box, voxel_of, voxels_per_unit};

/// A CPU reference of the whole build in f64, for tests: loudness sums, mean hp and counts per
/// voxel, in the grid's layout.
pub struct ReferenceGrid {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub sums: Vec<f64>,
    pub hp_mean: Vec<f64>,
    pub counts: Vec<u32>,
}

impl ReferenceGrid {
    pub fn build(points: &[Point], resolution: u32) -> Self {
        let dims = UVec3::splat(resolution);
        let (box_min, box_max) = grid_box(points);
        let per_unit = voxels_per_unit(dims, box_min, box_max);
        let n = (resolution as usize).pow(3);
        let (mut sums, mut hp_sums, mut counts) = (vec![0.0; n], vec![0.0; n], vec![0u32; n]);
        for p in points {
            let q = Vec3::from(p.position);
            if q.is_nan() {
                continue;
            }
            let v = voxel_of(q, box_min, per_unit, dims);
            let i = (v.x + dims.x * (v.y + dims.y * v.z)) as usize;
            sums[i] += f64::from(p.scalar.clamp(0.0, 1.0));
            hp_sums[i] += f64::from(p.hp.clamp(0.0, 1.0));
            counts[i] += 1;
        }
        let hp_mean = hp_sums
            .iter()
            .zip(&counts)
            .map(|(h, &c)| if c == 0 { 0.5 } else { h / f64::from(c) })
            .collect();
        Self {
            dims,
            box_min,
            box_max,
            sums,
            hp_mean,
            counts,
        }
    }

    /// Smooths the sums as the GPU does: three 1D passes x, y, z, weights renormalized at edges.
    pub fn smooth(&mut self, sigma: f32) {
        if sigma <= 0.0 {
            return;
        }
        let weights = gaussian_weights(sigma);
        let radius = weights.len() as i64 - 1;
        let d = [self.dims.x as i64, self.dims.y as i64, self.dims.z as i64];
        for axis in 0..3 {
            let input = self.sums.clone();
            for k in 0..d[2] {
                for j in 0..d[1] {
                    for i in 0..d[0] {
                        let ijk = [i, j, k];
                        let (mut total, mut wsum) = (0.0, 0.0);
                        for o in -radius..=radius {
                            let mut q = ijk;
                            q[axis] += o;
                            if q[axis] < 0 || q[axis] >= d[axis] {
                                continue;
                            }
                            let w = f64::from(weights[o.unsigned_abs() as usize]);
                            total += w * input[(q[0] + d[0] * (q[1] + d[1] * q[2])) as usize];
                            wsum += w;
                        }
                        self.sums[(i + d[0] * (j + d[1] * k)) as usize] = total / wsum;
                    }
                }
            }
        }
    }

    /// The normalized density, given the reference sum.
    pub fn density(&self, reference: f64) -> Vec<f64> {
        self.sums.iter().map(|s| (s / reference).min(1.0)).collect()
    }
}

impl ReferenceGrid {
    /// [`ReferenceGrid::build`] of the points as the frequency axis `mapping` shows them (the
    /// CPU reference of the voxelizer's remapping, src/data/freq_axis.rs).
    pub fn build_mapped(
        points: &[Point],
        resolution: u32,
        mapping: &crate::data::freq_axis::FreqMapping,
    ) -> Self {
        Self::build(&mapping.view_points(points), resolution)
    }
}
