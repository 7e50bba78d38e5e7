// The volume view's derived grids, built once per voxel grid by src/render/volume_grids.rs:
// - `gradients`: the density's central differences at every voxel centre (one voxel apart on each
//   side, clamped to the grid) and the density itself into an rgba16float 3D texture, which the
//   ray march samples with linear filtering: one sample a step instead of eight loads, and for
//   the gradient instead of six more trilinear samples (filtering the differences is the same as
//   differencing two filtered samples one voxel apart).
// - `brick_maxima`: the largest density of each brick of `bricks.w` voxels a side, over every
//   voxel a trilinear sample inside the brick can read (the brick and a one-voxel apron), so
//   where that maximum gives no opacity the march skips the brick without changing a sample.
// Reads the density buffer (layout of src/render/grid/mod.rs). Keep GridParams in sync with
// src/render/volume_grids.rs and BRICK_WORKGROUP there.

struct GridParams {
    // Grid size in voxels (w unused).
    dims: vec4<u32>,
    // Bricks per axis; w: brick size in voxels.
    bricks: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: GridParams;
@group(0) @binding(1) var<storage, read> density: array<f32>;
@group(0) @binding(2) var gradient: texture_storage_3d<rgba16float, write>;
@group(0) @binding(3) var<storage, read_write> brick_max: array<f32>;

fn voxel_density(ijk: vec3<i32>) -> f32 {
    let top = vec3<i32>(params.dims.xyz) - vec3<i32>(1);
    let c = vec3<u32>(clamp(ijk, vec3<i32>(0), top));
    return density[c.x + params.dims.x * (c.y + params.dims.y * c.z)];
}

@compute @workgroup_size(4, 4, 4)
fn gradients(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id >= params.dims.xyz)) {
        return;
    }
    let ijk = vec3<i32>(id);
    let g = vec3<f32>(
        voxel_density(ijk + vec3<i32>(1, 0, 0)) - voxel_density(ijk - vec3<i32>(1, 0, 0)),
        voxel_density(ijk + vec3<i32>(0, 1, 0)) - voxel_density(ijk - vec3<i32>(0, 1, 0)),
        voxel_density(ijk + vec3<i32>(0, 0, 1)) - voxel_density(ijk - vec3<i32>(0, 0, 1)),
    );
    textureStore(gradient, id, vec4<f32>(g, voxel_density(ijk)));
}

@compute @workgroup_size(4, 4, 4)
fn brick_maxima(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id >= params.bricks.xyz)) {
        return;
    }
    let size = i32(params.bricks.w);
    let top = vec3<i32>(params.dims.xyz) - vec3<i32>(1);
    // A sample at voxel-space u reads voxels floor(u - 0.5) and the next, so a brick covering
    // [b * size, (b + 1) * size] reads voxels b * size - 1 through (b + 1) * size.
    let lo = max(vec3<i32>(id) * size - vec3<i32>(1), vec3<i32>(0));
    let hi = min((vec3<i32>(id) + vec3<i32>(1)) * size, top);
    var most = voxel_density(lo);
    for (var z = lo.z; z <= hi.z; z += 1) {
        for (var y = lo.y; y <= hi.y; y += 1) {
            let row = u32(lo.x) + params.dims.x * (u32(y) + params.dims.y * u32(z));
            for (var x = 0; x <= hi.x - lo.x; x += 1) {
                most = max(most, density[row + u32(x)]);
            }
        }
    }
    brick_max[id.x + params.bricks.x * (id.y + params.bricks.y * id.z)] = most;
}
