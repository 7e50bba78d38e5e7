// Shared by the isosurface extraction passes (marching_tets.wgsl, dual_contour.wgsl): the grid
// they read, the mesh they write, and sampling helpers.
// Keep IsoParams, MeshVertex and the binding numbers in sync with src/render/mesh.rs.
//
// Grid coordinates: sample (voxel centre) p = (i, j, k) sits at box_min + (p + 0.5) * voxel_size
// in data space. Samples outside [0, dims) read as density 0 (hp 0.5), so every surface closes at
// the grid's border instead of leaving holes; cells therefore run from -1 to dims - 1 on each
// axis ((dims + 1)^3 cells). A sample is inside the surface when its density is > iso_value.

struct IsoParams {
    dims: vec3<u32>,
    vertex_capacity: u32,
    box_min: vec3<f32>,
    iso_value: f32,
    voxel_size: vec3<f32>,
    index_capacity: u32,
};

// One mesh vertex: data-space position, hp colour scalar, unit normal (toward lower density).
struct MeshVertex {
    position: vec3<f32>,
    hp: f32,
    normal: vec3<f32>,
    pad: f32,
};

// Counts written by atomic append; they keep counting past capacity so the CPU learns the size a
// surface needs.
struct Counters {
    vertices: atomic<u32>,
    indices: atomic<u32>,
};

@group(1) @binding(0) var<uniform> params: IsoParams;
@group(1) @binding(1) var<storage, read> density: array<f32>;
@group(1) @binding(2) var<storage, read> hp_mean: array<f32>;
@group(1) @binding(3) var<storage, read_write> vertices: array<MeshVertex>;
@group(1) @binding(4) var<storage, read_write> counters: Counters;
// [0..4]: DrawIndirectArgs, [4..9]: DrawIndexedIndirectArgs (wgpu::util layouts).
@group(1) @binding(5) var<storage, read_write> indirect: array<u32, 12>;

const INVALID: u32 = 0xffffffffu;

fn in_grid(p: vec3<i32>) -> bool {
    return all(p >= vec3<i32>(0)) && all(p < vec3<i32>(params.dims));
}

fn voxel_index(p: vec3<i32>) -> u32 {
    let q = vec3<u32>(p);
    return q.x + params.dims.x * (q.y + params.dims.y * q.z);
}

fn sample_density(p: vec3<i32>) -> f32 {
    if (!in_grid(p)) {
        return 0.0;
    }
    return density[voxel_index(p)];
}

fn sample_hp(p: vec3<i32>) -> f32 {
    if (!in_grid(p)) {
        return 0.5;
    }
    return hp_mean[voxel_index(p)];
}

// Central-difference gradient of the density at a sample, in grid units.
fn sample_gradient(p: vec3<i32>) -> vec3<f32> {
    let x = vec3<i32>(1, 0, 0);
    let y = vec3<i32>(0, 1, 0);
    let z = vec3<i32>(0, 0, 1);
    return 0.5 * vec3<f32>(
        sample_density(p + x) - sample_density(p - x),
        sample_density(p + y) - sample_density(p - y),
        sample_density(p + z) - sample_density(p - z),
    );
}

fn data_position(grid: vec3<f32>) -> vec3<f32> {
    return params.box_min + (grid + 0.5) * params.voxel_size;
}

// Unit normal in data space pointing toward lower density, from a grid-unit gradient; zero when
// the gradient vanishes.
fn outward_normal(grid_gradient: vec3<f32>) -> vec3<f32> {
    let g = grid_gradient / params.voxel_size;
    let len = length(g);
    if (len < 1e-20) {
        return vec3<f32>(0.0);
    }
    return -g / len;
}

// Cube corner k (bit 0: x, bit 1: y, bit 2: z) as an offset from the cell's lowest sample.
fn corner_offset(k: u32) -> vec3<i32> {
    return vec3<i32>(i32(k & 1u), i32((k >> 1u) & 1u), i32((k >> 2u) & 1u));
}

// The hp of a set of samples, weighted by their density (empty voxels carry no colour).
fn weighted_hp(sum_weighted: f32, sum_weights: f32) -> f32 {
    if (sum_weights <= 1e-12) {
        return 0.5;
    }
    return clamp(sum_weighted / sum_weights, 0.0, 1.0);
}
