// Downsample of a voxel grid by 2 on each axis (src/render/grid/downsample.rs), the coarse grid
// of the Surface view's level of detail.
//
// Reads: a grid (layout of src/render/grid/mod.rs). Writes: a grid of ceil(dims / 2) voxels in
// the same box, whose voxel (i, j, k) stands for the fine block 2 (i, j, k) + {0, 1}^3 (cut at
// the far border where a fine dimension is odd: only the voxels that exist count).
//   density: the mean of the block's densities.
//   hp_mean: the density-weighted mean of the block's hp; where the block has no density, the
//            plain mean of its hp (0.5 where no voxel held a point).
// Keep the arithmetic (the order of the sums included) in sync with `reference_downsample` in
// downsample.rs.

struct DownsampleParams {
    // xyz: the fine grid's dims.
    fine: vec4<u32>,
    // xyz: the coarse grid's dims.
    coarse: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: DownsampleParams;
@group(0) @binding(1) var<storage, read> fine_density: array<f32>;
@group(0) @binding(2) var<storage, read> fine_hp: array<f32>;
@group(0) @binding(3) var<storage, read_write> coarse_density: array<f32>;
@group(0) @binding(4) var<storage, read_write> coarse_hp: array<f32>;

@compute @workgroup_size(256)
fn downsample(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let voxel = id.x + id.y * groups.x * 256u;
    let fine = params.fine.xyz;
    let coarse = params.coarse.xyz;
    if (voxel >= coarse.x * coarse.y * coarse.z) {
        return;
    }
    let i = voxel % coarse.x;
    let j = (voxel / coarse.x) % coarse.y;
    let k = voxel / (coarse.x * coarse.y);
    let base = 2u * vec3<u32>(i, j, k);
    var count = 0u;
    var density_sum = 0.0;
    var weighted_hp = 0.0;
    var hp_sum = 0.0;
    for (var dz = 0u; dz < 2u; dz = dz + 1u) {
        for (var dy = 0u; dy < 2u; dy = dy + 1u) {
            for (var dx = 0u; dx < 2u; dx = dx + 1u) {
                let q = base + vec3<u32>(dx, dy, dz);
                if (any(q >= fine)) {
                    continue;
                }
                let index = q.x + fine.x * (q.y + fine.y * q.z);
                let d = fine_density[index];
                let h = fine_hp[index];
                count = count + 1u;
                density_sum = density_sum + d;
                weighted_hp = weighted_hp + d * h;
                hp_sum = hp_sum + h;
            }
        }
    }
    let n = f32(count);
    coarse_density[voxel] = density_sum / n;
    let hp = select(hp_sum / n, weighted_hp / density_sum, density_sum > 0.0);
    coarse_hp[voxel] = clamp(hp, 0.0, 1.0);
}
