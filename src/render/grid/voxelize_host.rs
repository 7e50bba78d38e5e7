//! The whole voxelization on the CPU's cores, for devices that are themselves the CPU.
//!
//! On a software adapter (lavapipe, WARP, SwiftShader: `wgpu::DeviceType::Cpu`) the compute
//! passes of shaders/grid/voxelize.wgsl run on the same cores native code would, but every
//! atomic add of `accumulate` and every gathered load of `resolve` and `smooth_axis` becomes a
//! loop over the SIMD lanes: a song's 128^3 grid with its default smoothing took about 2 s there
//! (3.5 M points; `loudscape bench --only volume`), most of the wait between clicking Surface or
//! Volume and seeing it. So on such a device [`VoxelizePass::voxelize`] builds the grid here
//! instead, with the shader's own arithmetic step by step (the same 64-bit fixed-point sums, the
//! same f32 resolve, Gaussian, histogram, percentile and clamp), and uploads the two fields: the
//! same grid and statistics, to float rounding in the smoothing's sums
//! (`tests/it/voxelize.rs` compares the two engines). A real GPU keeps the compute passes.
//!
//! [`VoxelizePass::voxelize`]: super::voxelize::VoxelizePass::voxelize

use glam::{UVec3, Vec3};

use crate::data::cloud::Point;
use crate::data::freq_axis::FreqMapping;
use crate::render::grid::voxelize_cpu::{
    FIXED_POINT_SCALE, HP_FIXED_POINT_SCALE, VoxelStats, gaussian_weights, reference_sum, voxel_of,
    voxels_per_unit,
};

/// A grid built on the CPU: the normalized density and mean hp per voxel (the grid's layout,
/// `src/render/grid/mod.rs`) and what the normalization found.
pub struct HostGrid {
    pub density: Vec<f32>,
    pub hp_mean: Vec<f32>,
    pub stats: VoxelStats,
}

/// Builds the grid of `points` (on the frequency axis `mapping`, `None`: as stored) with `dims`
/// voxels in the box `box_min`..`box_max`, smoothed by a Gaussian of `sigma` voxels (0: not),
/// as the compute passes do.
pub fn build(
    points: &[Point],
    mapping: Option<&FreqMapping>,
    dims: UVec3,
    (box_min, box_max): (Vec3, Vec3),
    sigma: f32,
) -> HostGrid {
    let voxels = (dims.x * dims.y * dims.z) as usize;
    let per_unit = voxels_per_unit(dims, box_min, box_max);
    // accumulate: exact 64-bit fixed-point sums and a count per voxel, side by side so that a
    // point touches one place in memory, not three.
    let mut sums = vec![Sums::default(); voxels];
    for (index, point) in points.iter().enumerate() {
        let [x, y, z] = point.position;
        let z = match mapping {
            Some(mapping) => match mapping.view_z(z, index as u32) {
                Some(z) => z,
                None => continue,
            },
            None => z,
        };
        let p = Vec3::new(x, y, z);
        // As the shader: NaN coordinates and points past the view's z are skipped.
        if p.is_nan() || p.z > 2.0 {
            continue;
        }
        let v = voxel_of(p, box_min, per_unit, dims);
        let voxel = &mut sums[(v.x + dims.x * (v.y + dims.y * v.z)) as usize];
        voxel.loudness += fixed(point.scalar, FIXED_POINT_SCALE);
        voxel.hp += fixed(point.hp, HP_FIXED_POINT_SCALE);
        voxel.count += 1;
    }
    // resolve: the sums as f32 (the high word times 2^32 plus the low word, as the shader
    // converts them) and the mean hp (0.5 where a voxel holds no point).
    let as_f32 = |sum: u64, scale: u32| {
        ((sum >> 32) as u32 as f32 * 4_294_967_296.0 + sum as u32 as f32) / scale as f32
    };
    let (mut density, hp_mean): (Vec<f32>, Vec<f32>) = sums
        .iter()
        .map(|s| match s.count {
            0 => (0.0, 0.5),
            n => (
                as_f32(s.loudness, FIXED_POINT_SCALE),
                (as_f32(s.hp, HP_FIXED_POINT_SCALE) / n as f32).clamp(0.0, 1.0),
            ),
        })
        .unzip();
    drop(sums);
    if sigma > 0.0 {
        let weights = gaussian_weights(sigma);
        let mut scratch = vec![0.0f32; voxels];
        smooth_axis(&density, &mut scratch, dims, 0, &weights);
        smooth_axis(&scratch, &mut density, dims, 1, &weights);
        smooth_axis(&density, &mut scratch, dims, 2, &weights);
        density = scratch;
    }
    // histogram and percentile: the reference sum; normalize_density: divide and clamp.
    let nonempty = density.iter().filter(|&&s| s > 0.0).count() as u32;
    let reference = reference_sum(density.iter().copied());
    let mut clamped = 0u32;
    for value in &mut density {
        let v = *value / reference;
        clamped += u32::from(v > 1.0);
        *value = v.min(1.0);
    }
    HostGrid {
        density,
        hp_mean,
        stats: VoxelStats {
            nonempty,
            reference_sum: reference,
            clamped,
        },
    }
}

/// The grids of an A/B compare's two clouds (`a` and `b`, already on one set of axes), as
/// [`build`] makes each, in one box (the union of their grid boxes, as the window's compare:
/// voxel (i, j, k) is the same place in both) and on one scale (each density times its
/// [`shared_scales`] factor onto the larger reference sum, the CPU mirror of the difference
/// pass's `rescale`: a density means the same loudness sum in A as in B). Returns the grids and
/// their box.
///
/// [`shared_scales`]: super::voxelize_cpu::shared_scales
pub fn build_on_one_scale(
    a: &[Point],
    b: &[Point],
    dims: UVec3,
    sigma: f32,
) -> ([HostGrid; 2], (Vec3, Vec3)) {
    let (min_a, max_a) = super::voxelize_cpu::grid_box(a);
    let (min_b, max_b) = super::voxelize_cpu::grid_box(b);
    let grid_box = (min_a.min(min_b), max_a.max(max_b));
    let mut grids = [a, b].map(|points| build(points, None, dims, grid_box, sigma));
    let (scale_a, scale_b) = super::voxelize_cpu::shared_scales(&grids[0].stats, &grids[1].stats);
    for (grid, scale) in grids.iter_mut().zip([scale_a, scale_b]) {
        if scale != 1.0 {
            grid.density.iter_mut().for_each(|d| *d *= scale);
        }
    }
    (grids, grid_box)
}

/// One voxel's sums as `accumulate` keeps them: loudness and hp in fixed point, and the count.
#[derive(Clone, Copy, Default)]
struct Sums {
    loudness: u64,
    hp: u64,
    count: u32,
}

/// A value in [0, 1] as fixed-point units of `scale`, rounded half to even as WGSL's `round`.
fn fixed(value: f32, scale: u32) -> u64 {
    (value.clamp(0.0, 1.0) * scale as f32).round_ties_even() as u64
}

/// One axis of the separable Gaussian, as `smooth_axis` in the shader: the weights of the
/// offsets inside the grid, renormalized at its edges, each voxel's sum taken in f32 from the
/// lowest offset up (here a row of voxels at a time, the same operations per voxel in the same
/// order). The slabs of constant z are shared among the cores.
fn smooth_axis(input: &[f32], output: &mut [f32], dims: UVec3, axis: usize, weights: &[f32]) {
    let radius = weights.len() as i64 - 1;
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let extent = [dims.x, dims.y, dims.z][axis] as i64;
    let stride = [1, nx, nx * ny][axis] as i64;
    let slab = nx * ny;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slabs_per_thread = (dims.z as usize).div_ceil(threads).max(1);
    let smooth_part = move |part: usize, out: &mut [f32]| {
        let first_row = part * slabs_per_thread * ny;
        for (r, row) in out.chunks_mut(nx).enumerate() {
            let row_index = first_row + r;
            let start = (row_index * nx) as i64;
            if axis == 0 {
                for (i, value) in row.iter_mut().enumerate() {
                    let (mut total, mut weight_sum) = (0.0f32, 0.0f32);
                    for o in -radius..=radius {
                        let at = i as i64 + o;
                        if at < 0 || at >= extent {
                            continue;
                        }
                        let w = weights[o.unsigned_abs() as usize];
                        total += w * input[(start + at) as usize];
                        weight_sum += w;
                    }
                    *value = total / weight_sum.max(1e-12);
                }
                continue;
            }
            // Along y or z every voxel of the row has the same offsets inside the grid.
            let here = if axis == 1 {
                row_index % ny
            } else {
                row_index / ny
            } as i64;
            row.fill(0.0);
            let mut weight_sum = 0.0f32;
            for o in -radius..=radius {
                let at = here + o;
                if at < 0 || at >= extent {
                    continue;
                }
                let w = weights[o.unsigned_abs() as usize];
                let from = (start + o * stride) as usize;
                for (value, x) in row.iter_mut().zip(&input[from..from + nx]) {
                    *value += w * x;
                }
                weight_sum += w;
            }
            let weight_sum = weight_sum.max(1e-12);
            for value in row.iter_mut() {
                *value /= weight_sum;
            }
        }
    };
    if threads == 1 {
        // One core (or none to spawn on, as in a web page): no thread.
        smooth_part(0, output);
        return;
    }
    std::thread::scope(|scope| {
        for (part, out) in output.chunks_mut(slabs_per_thread * slab).enumerate() {
            scope.spawn(move || smooth_part(part, out));
        }
    });
}
