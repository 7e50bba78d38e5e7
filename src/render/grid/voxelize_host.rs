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
    // accumulate: exact 64-bit fixed-point sums and a count per voxel.
    let mut loudness = vec![0u64; voxels];
    let mut hp_sums = vec![0u64; voxels];
    let mut counts = vec![0u32; voxels];
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
        let i = (v.x + dims.x * (v.y + dims.y * v.z)) as usize;
        loudness[i] += fixed(point.scalar, FIXED_POINT_SCALE);
        hp_sums[i] += fixed(point.hp, HP_FIXED_POINT_SCALE);
        counts[i] += 1;
    }
    // resolve: the sums as f32 (the high word times 2^32 plus the low word, as the shader
    // converts them) and the mean hp (0.5 where a voxel holds no point).
    let as_f32 = |sum: u64, scale: u32| {
        ((sum >> 32) as u32 as f32 * 4_294_967_296.0 + sum as u32 as f32) / scale as f32
    };
    let mut density: Vec<f32> = loudness
        .iter()
        .zip(&counts)
        .map(|(&sum, &n)| {
            if n == 0 {
                0.0
            } else {
                as_f32(sum, FIXED_POINT_SCALE)
            }
        })
        .collect();
    let hp_mean: Vec<f32> = hp_sums
        .iter()
        .zip(&counts)
        .map(|(&sum, &n)| {
            if n == 0 {
                0.5
            } else {
                (as_f32(sum, HP_FIXED_POINT_SCALE) / n as f32).clamp(0.0, 1.0)
            }
        })
        .collect();
    drop((loudness, hp_sums, counts));
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

/// A value in [0, 1] as fixed-point units of `scale`, rounded half to even as WGSL's `round`.
fn fixed(value: f32, scale: u32) -> u64 {
    (value.clamp(0.0, 1.0) * scale as f32).round_ties_even() as u64
}

/// One axis of the separable Gaussian, as `smooth_axis` in the shader: the weights of the
/// offsets inside the grid, renormalized at its edges, summed in f32 from the lowest offset up.
/// The slabs of constant z are shared among the cores.
fn smooth_axis(input: &[f32], output: &mut [f32], dims: UVec3, axis: usize, weights: &[f32]) {
    let radius = weights.len() as i64 - 1;
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let extent = [dims.x, dims.y, dims.z][axis] as i64;
    let stride = [1, nx, nx * ny][axis] as i64;
    let slab = nx * ny;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slabs_per_thread = (dims.z as usize).div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for (part, out) in output.chunks_mut(slabs_per_thread * slab).enumerate() {
            scope.spawn(move || {
                let first = part * slabs_per_thread * slab;
                for (offset, value) in out.iter_mut().enumerate() {
                    let voxel = first + offset;
                    let here = [voxel % nx, (voxel / nx) % ny, voxel / slab][axis] as i64;
                    let mut total = 0.0f32;
                    let mut weight_sum = 0.0f32;
                    for o in -radius..=radius {
                        let at = here + o;
                        if at < 0 || at >= extent {
                            continue;
                        }
                        let w = weights[o.unsigned_abs() as usize];
                        total += w * input[(voxel as i64 + o * stride) as usize];
                        weight_sum += w;
                    }
                    *value = total / weight_sum.max(1e-12);
                }
            });
        }
    });
}
