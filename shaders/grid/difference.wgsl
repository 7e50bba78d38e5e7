// Difference of two density grids built in one box (src/render/grid/difference.rs).
//
// Reads: the density grids of A and B (layout of src/render/grid/mod.rs, same dims and box).
// Writes: A and B on one scale (`scaled_a`, `scaled_b`: density times the grid's reference sum
// over the shared one), their signed difference B - A per voxel (`difference`), the
// level-weighted difference per time-frequency column (`columns`, element i + dims.x * k), and
// the shown grid: |t| as density and 0.5 - t / 2 as hp (the diverging palette), where t is the
// chosen measure over the signed range, clamped to [-1, 1].
// Keep the arithmetic in sync with the CPU mirror in difference.rs (`reference_*`).

struct DifferenceParams {
    dims: vec4<u32>,
    // x: scale of A, y: scale of B, z: signed range shown, w: presence threshold.
    scales: vec4<f32>,
    // x: measure (0 density, 1 level).
    options: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: DifferenceParams;
@group(0) @binding(1) var<storage, read> density_a: array<f32>;
@group(0) @binding(2) var<storage, read> density_b: array<f32>;
@group(0) @binding(3) var<storage, read_write> scaled_a: array<f32>;
@group(0) @binding(4) var<storage, read_write> scaled_b: array<f32>;
@group(0) @binding(5) var<storage, read_write> difference: array<f32>;
@group(0) @binding(6) var<storage, read_write> columns: array<f32>;
@group(0) @binding(7) var<storage, read_write> shown_density: array<f32>;
@group(0) @binding(8) var<storage, read_write> shown_hp: array<f32>;

fn linear_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 256u;
}

fn voxel_total() -> u32 {
    return params.dims.x * params.dims.y * params.dims.z;
}

// Both grids on the shared scale: one multiplication each, never fused with anything.
@compute @workgroup_size(256)
fn rescale(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let voxel = linear_index(id, groups);
    if (voxel >= voxel_total()) {
        return;
    }
    scaled_a[voxel] = density_a[voxel] * params.scales.x;
    scaled_b[voxel] = density_b[voxel] * params.scales.y;
}

// B - A per voxel: a plain subtraction, so a grid against itself gives exactly zero.
@compute @workgroup_size(256)
fn density_difference(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let voxel = linear_index(id, groups);
    if (voxel >= voxel_total()) {
        return;
    }
    difference[voxel] = scaled_b[voxel] - scaled_a[voxel];
}

// The level of voxel row j: its centre's height in the box, 0 at the floor, 1 at the top.
fn level_weight(j: u32) -> f32 {
    return (f32(j) + 0.5) / f32(params.dims.y);
}

// Per column (time x frequency): sum over the level axis of level weight times B - A.
@compute @workgroup_size(256)
fn level_columns(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let column = linear_index(id, groups);
    let dims = params.dims.xyz;
    if (column >= dims.x * dims.z) {
        return;
    }
    let i = column % dims.x;
    let k = column / dims.x;
    var total = 0.0;
    for (var j = 0u; j < dims.y; j = j + 1u) {
        let voxel = i + dims.x * (j + dims.y * k);
        total = total + level_weight(j) * difference[voxel];
    }
    columns[column] = total;
}

// The grid the volume view draws: |t| as density, 0.5 - t / 2 as hp.
@compute @workgroup_size(256)
fn shade(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let voxel = linear_index(id, groups);
    let dims = params.dims.xyz;
    if (voxel >= voxel_total()) {
        return;
    }
    var value = difference[voxel];
    if (params.options.x == 1u) {
        let i = voxel % dims.x;
        let k = voxel / (dims.x * dims.y);
        let present = max(scaled_a[voxel], scaled_b[voxel]) > params.scales.w;
        value = select(0.0, columns[i + dims.x * k], present);
    }
    let t = clamp(value / params.scales.z, -1.0, 1.0);
    shown_density[voxel] = abs(t);
    shown_hp[voxel] = 0.5 - 0.5 * t;
}
