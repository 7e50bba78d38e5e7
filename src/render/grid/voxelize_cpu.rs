//! The CPU side of shaders/grid/voxelize.wgsl's arithmetic: the grid box, the voxel a point
//! falls in, the histogram of the sums and its percentile, the Gaussian weights. The pass
//! ([`voxelize`](super::voxelize)) fills its uniforms from these; the f64
//! [`ReferenceGrid`](super::reference::ReferenceGrid) and the tests rebuild the grid with them,
//! so the CPU puts every point in the voxel the GPU does.

use glam::{UVec3, Vec3};

use crate::data::cloud::Point;
use crate::data::freq_axis::FreqMapping;

/// Fixed-point units per 1.0 of scalar or hp. One point adds at most 2^20 to a 64-bit sum, so no
/// cloud that fits a GPU buffer can overflow it; the rounding error is at most 2^-21 per point.
pub const FIXED_POINT_SCALE: u32 = 1 << 20;
/// Fixed-point units per 1.0 of hp, in a 64-bit sum of its own (the count has its own u32).
pub const HP_FIXED_POINT_SCALE: u32 = 1 << 16;

/// What the normalization found, read back after a build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelStats {
    /// Voxels with a positive (smoothed) loudness sum.
    pub nonempty: u32,
    /// The loudness sum that maps to density 1 (the 99th-percentile histogram bin's upper edge,
    /// capped at the largest sum).
    pub reference_sum: f32,
    /// Voxels whose sum exceeded the reference and were clamped to 1.
    pub clamped: u32,
}

/// The shared scale of two grids compared: each grid's factor onto the larger reference sum,
/// `(scale_a, scale_b)` (the difference pass on the GPU, the page's compare grids on the CPU).
pub fn shared_scales(stats_a: &VoxelStats, stats_b: &VoxelStats) -> (f32, f32) {
    let shared = stats_a.reference_sum.max(stats_b.reference_sum);
    if shared.is_nan() || shared <= 0.0 {
        return (1.0, 1.0);
    }
    (
        stats_a.reference_sum / shared,
        stats_b.reference_sum / shared,
    )
}

/// The density is normalized by this percentile of the voxels with a positive loudness sum.
pub const PERCENTILE: f64 = 0.99;
pub const HISTOGRAM_BINS: u32 = 1024;
/// log2 of the lowest histogram bin edge: one point of scalar 2^-20 (one fixed-point unit).
pub const HISTOGRAM_LOG2_MIN: f32 = -20.0;
/// Bins per doubling of the sum: bins are 2.9 % wide; 1024 bins reach sums of 2^22.6.
pub const HISTOGRAM_BINS_PER_OCTAVE: f32 = 24.0;
/// Largest Gaussian kernel radius, in voxels (the smoothing uniform holds 32 weights).
const MAX_KERNEL_RADIUS: usize = 31;

/// The grid box for a cloud: its bounding box, each side grown by 1 % so that no point lies on
/// the box's faces, and at least 5 % of the largest side (or 0.02 data units) thick, so a flat
/// cloud or a single point still gets a box with volume. An empty cloud gets the data cube.
pub fn grid_box(points: &[Point]) -> (Vec3, Vec3) {
    let (min, max) = finite_bounds(points.iter().map(|p| Vec3::from(p.position)));
    grid_box_of_bounds(min, max)
}

/// [`grid_box`] from the points' bounding box `[min, max]` (not finite: no points).
pub fn grid_box_of_bounds(min: Vec3, max: Vec3) -> (Vec3, Vec3) {
    if !min.is_finite() || !max.is_finite() {
        return (Vec3::splat(-1.0), Vec3::splat(1.0));
    }
    let centre = (min + max) * 0.5;
    let extent = max - min;
    let thinnest = (extent.max_element() * 0.05).max(0.02);
    let extent = extent.max(Vec3::splat(thinnest)) * 1.02;
    (centre - extent * 0.5, centre + extent * 0.5)
}

/// The grid box of the points as the frequency axis `mapping` shows them (z remapped, points it
/// leaves out ignored): [`grid_box`] of [`FreqMapping::view_points`], without the copy.
pub fn grid_box_mapped(points: &[Point], mapping: Option<&FreqMapping>) -> (Vec3, Vec3) {
    let Some(mapping) = mapping.filter(|m| !m.is_identity()) else {
        return grid_box(points);
    };
    let shown = points.iter().enumerate().filter_map(|(i, p)| {
        let z = mapping.view_z(p.position[2], i as u32)?;
        Some(Vec3::new(p.position[0], p.position[1], z))
    });
    let (min, max) = finite_bounds(shown);
    grid_box_of_bounds(min, max)
}

/// The bounding box of the finite positions (infinite and inverted when there are none).
fn finite_bounds(positions: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    positions.filter(|q| q.is_finite()).fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(min, max), q| (min.min(q), max.max(q)),
    )
}

/// Voxel coordinates per data unit along each axis.
pub fn voxels_per_unit(dims: UVec3, box_min: Vec3, box_max: Vec3) -> Vec3 {
    dims.as_vec3() / (box_max - box_min)
}

/// The voxel (i, j, k) holding `p`. Keep in sync with `voxel_of` in shaders/grid/voxelize.wgsl: the
/// same f32 operations, so the CPU reference puts points on voxel faces where the GPU does.
pub fn voxel_of(p: Vec3, box_min: Vec3, per_unit: Vec3, dims: UVec3) -> UVec3 {
    let u = ((p - box_min) * per_unit).floor();
    let top = dims.as_vec3() - Vec3::ONE;
    u.clamp(Vec3::ZERO, top).as_uvec3()
}

/// The histogram bin of a positive sum. Keep in sync with `histogram_bin` in voxelize.wgsl.
pub fn histogram_bin(sum: f32) -> u32 {
    if sum <= 0.0 {
        return 0;
    }
    let t = (sum.log2() - HISTOGRAM_LOG2_MIN) * HISTOGRAM_BINS_PER_OCTAVE;
    t.floor().clamp(0.0, (HISTOGRAM_BINS - 1) as f32) as u32
}

/// The upper edge of a histogram bin.
pub fn bin_upper_edge(bin: u32) -> f32 {
    (HISTOGRAM_LOG2_MIN + (bin + 1) as f32 / HISTOGRAM_BINS_PER_OCTAVE).exp2()
}

/// The reference sum for normalization, as the GPU computes it: the upper edge of the histogram
/// bin holding rank ceil(0.99 n) of the n positive sums, capped at the largest sum (1 when there
/// are none).
/// Keep in sync with `percentile` in voxelize.wgsl.
pub fn reference_sum(sums: impl IntoIterator<Item = f32>) -> f32 {
    let mut histogram = vec![0u32; HISTOGRAM_BINS as usize];
    let mut n = 0u32;
    let mut largest = 0.0f32;
    for s in sums {
        if s > 0.0 {
            histogram[histogram_bin(s) as usize] += 1;
            n += 1;
            largest = largest.max(s);
        }
    }
    if n == 0 {
        return 1.0;
    }
    let p = (PERCENTILE * 1e6).round() as f32 / 1e6;
    let rank = ((p * n as f32).ceil() as u32).max(1);
    let mut seen = 0;
    for (bin, count) in histogram.iter().enumerate() {
        seen += count;
        if seen >= rank {
            return bin_upper_edge(bin as u32).min(largest);
        }
    }
    largest
}

/// Normalized Gaussian weights for offsets 0..=radius (radius = ceil(3 sigma), at most 31).
pub fn gaussian_weights(sigma: f32) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let radius = ((3.0 * sigma).ceil() as usize).clamp(1, MAX_KERNEL_RADIUS);
    (0..=radius)
        .map(|o| (-(o as f32).powi(2) / (2.0 * sigma * sigma)).exp())
        .collect()
}
