// Voxelization: points -> per-voxel sums -> normalized loudness density and mean hp.
// Entry points, in the order src/render/grid/voxelize.rs dispatches them:
//   accumulate  one thread per point: adds scalar, hp and 1 to the point's voxel's sums and count
//   resolve     one thread per voxel: density = loudness sum (as f32), hp mean = hp sum / count
//   smooth_axis one thread per voxel: one axis of a separable Gaussian on the sums (optional)
//   histogram   grid-stride over voxels: log2 histogram of the positive (smoothed) sums
//   percentile  one thread: the reference sum (the 99th percentile of the positive sums)
//   normalize_density  one thread per voxel: density = min(sum / reference, 1)
// Keep VoxelParams and SmoothParams in sync with src/render/grid/voxelize.rs.

struct VoxelParams {
    // Grid size in voxels (w unused).
    dims: vec4<u32>,
    // Grid box minimum in data space (w unused).
    box_min: vec4<f32>,
    // dims / (box_max - box_min): voxel coordinates per data unit (w unused).
    voxels_per_unit: vec4<f32>,
    // x: points in this chunk, y: unused, z: percentile in parts per million, w: unused.
    counts: vec4<u32>,
    // x: scalar fixed-point scale, y: log2 of the histogram's lowest bin edge, z: bins per octave,
    // w: hp fixed-point scale.
    scales: vec4<f32>,
    // The frequency axis of the view (shaders/utils/freq_axis.wgsl); z: the chunk's first point.
    freq: FreqParams,
};

struct SmoothParams {
    // Grid size in voxels (w unused).
    dims: vec4<u32>,
    // x: axis (0, 1, 2), y: kernel radius in voxels.
    axis: vec4<u32>,
    // Kernel weights for offsets 0..radius (normalized together with their mirror images).
    weights: array<vec4<f32>, 8>,
};

// Histogram: HISTOGRAM_BINS bins, log-spaced, BINS_PER_OCTAVE per doubling of the sum.
const HISTOGRAM_BINS: u32 = 1024u;
// Layout of `stats`: [0] non-empty voxels, [1] reference sum (f32 bits), [2] voxels over the
// reference (clamped to 1), [3] the largest sum (f32 bits; positive floats order as u32), then
// the histogram.
const STATS_HISTOGRAM: u32 = 4u;

@group(1) @binding(0) var<uniform> params: VoxelParams;
// The cloud chunk as a flat array, five f32 per point (x, y, z, scalar, hp), the PLY record.
@group(1) @binding(1) var<storage, read> cloud: array<f32>;
// Two 64-bit fixed-point numbers per voxel, each two u32 words (low, high) with manual carries,
// in two buffers of 8 bytes per voxel (so a 224^3 grid fits a 128 MiB binding), and a count:
//   loudness_sums: the loudness sum, scale 2^20
//   hp_sums:       the hp sum, scale 2^16
//   point_counts:  the points in the voxel, one u32 (4 bytes per voxel): exact up to 2^32 - 1
//                  points, more than any cloud a GPU buffer holds at 20 bytes a point
@group(1) @binding(2) var<storage, read_write> loudness_sums: array<atomic<u32>>;
@group(1) @binding(3) var<storage, read_write> hp_sums: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read_write> stats: array<atomic<u32>>;
// Four voxels per element (the buffer is padded to a multiple of 16 bytes with zeros).
@group(1) @binding(5) var<storage, read_write> density: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> hp_mean: array<f32>;
// [0] the reference sum, written by `percentile` for `normalize_density` to read without atomics.
@group(1) @binding(7) var<storage, read_write> reference_sum: array<f32>;
@group(1) @binding(8) var<storage, read_write> point_counts: array<atomic<u32>>;
// Per STFT bin: the view's z range its points are spread over (shaders/utils/freq_axis.wgsl).
@group(1) @binding(9) var<storage, read> freq_table: array<vec2<f32>>;

// The smoothing pass binds only group 2 (group 1 holds the density it would read and write).
@group(2) @binding(0) var<uniform> smooth_params: SmoothParams;
@group(2) @binding(1) var<storage, read> smooth_in: array<f32>;
@group(2) @binding(2) var<storage, read_write> smooth_out: array<f32>;

// The resolving pass reads the sums without atomics (much faster on CPU adapters), so it binds
// them read-only in a group of its own and leaves out group 1, where they are atomic.
@group(3) @binding(0) var<uniform> resolve_params: VoxelParams;
// Two voxels per element (low, high word each).
@group(3) @binding(1) var<storage, read> loudness_words: array<vec4<u32>>;
@group(3) @binding(2) var<storage, read> hp_words: array<vec4<u32>>;
// Four voxels per element.
@group(3) @binding(3) var<storage, read_write> resolved_density: array<vec4<f32>>;
@group(3) @binding(4) var<storage, read_write> resolved_hp_mean: array<vec4<f32>>;
@group(3) @binding(5) var<storage, read> count_words: array<vec4<u32>>;

// Linear invocation index over a 2D dispatch (x up to 65535 workgroups, then rows of y).
fn linear_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 256u;
}

fn voxel_total() -> u32 {
    return params.dims.x * params.dims.y * params.dims.z;
}

// The voxel holding data-space point `p`: floor((p - box_min) * voxels_per_unit), clamped.
// Keep in sync with voxel_of in src/render/grid/voxelize_cpu.rs (the CPU reference).
fn voxel_of(p: vec3<f32>) -> u32 {
    let u = (p - params.box_min.xyz) * params.voxels_per_unit.xyz;
    let top = vec3<i32>(params.dims.xyz) - vec3<i32>(1);
    let ijk = vec3<u32>(clamp(vec3<i32>(floor(u)), vec3<i32>(0), top));
    return ijk.x + params.dims.x * (ijk.y + params.dims.y * ijk.z);
}

@compute @workgroup_size(256)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = linear_index(id, groups);
    if (index >= params.counts.x) {
        return;
    }
    let base = index * 5u;
    let p = vec3<f32>(cloud[base], cloud[base + 1u], freq_view_z(cloud[base + 2u], index));
    // NaN coordinates would land anywhere: skip them (the loader rejects them; this is a guard).
    // Points the frequency axis leaves out (z = FREQ_HIDDEN) are skipped too.
    if (any(p != p) || p.z > 2.0) {
        return;
    }
    let voxel = voxel_of(p);
    let word = 2u * voxel;
    let scalar = u32(round(clamp(cloud[base + 3u], 0.0, 1.0) * params.scales.x));
    let hp = u32(round(clamp(cloud[base + 4u], 0.0, 1.0) * params.scales.w));
    // Add to the low words; carry one into the high word where the low word wrapped.
    let old_scalar = atomicAdd(&loudness_sums[word], scalar);
    if (old_scalar > 0xffffffffu - scalar) {
        atomicAdd(&loudness_sums[word + 1u], 1u);
    }
    let old_hp = atomicAdd(&hp_sums[word], hp);
    if (old_hp > 0xffffffffu - hp) {
        atomicAdd(&hp_sums[word + 1u], 1u);
    }
    atomicAdd(&point_counts[voxel], 1u);
}

// The histogram bin of a non-empty voxel's sum. Keep in sync with histogram_bin in
// src/render/grid/voxelize_cpu.rs.
// `scales` is VoxelParams.scales (y: log2 of the lowest edge, z: bins per octave).
fn histogram_bin(sum: f32, scales: vec4<f32>) -> u32 {
    if (sum <= 0.0) {
        return 0u;
    }
    let t = (log2(sum) - scales.y) * scales.z;
    return u32(clamp(floor(t), 0.0, f32(HISTOGRAM_BINS - 1u)));
}

var<workgroup> local_histogram: array<atomic<u32>, HISTOGRAM_BINS>;
var<workgroup> local_max: atomic<u32>;

fn clear_local_histogram(local: u32) {
    for (var b = local; b < HISTOGRAM_BINS; b += 256u) {
        atomicStore(&local_histogram[b], 0u);
    }
    if (local == 0u) {
        atomicStore(&local_max, 0u);
    }
}

fn bin_locally(sum: f32, scales: vec4<f32>) {
    if (sum > 0.0) {
        atomicAdd(&local_histogram[histogram_bin(sum, scales)], 1u);
    }
}

fn resolve_one(loudness: vec2<u32>, hp_sum: vec2<u32>, count: u32) -> vec2<f32> {
    if (count == 0u) {
        return vec2<f32>(0.0, 0.5);
    }
    let scalar = (f32(loudness.y) * 4294967296.0 + f32(loudness.x)) / resolve_params.scales.x;
    let hp = (f32(hp_sum.y) * 4294967296.0 + f32(hp_sum.x)) / resolve_params.scales.w;
    return vec2<f32>(scalar, clamp(hp / f32(count), 0.0, 1.0));
}

// Four voxels per thread (whole 16-byte loads and stores; buffers are padded to groups of four).
@compute @workgroup_size(256)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let group4 = linear_index(id, groups);
    if (group4 >= arrayLength(&resolved_density)) {
        return;
    }
    let l01 = loudness_words[2u * group4];
    let l23 = loudness_words[2u * group4 + 1u];
    let h01 = hp_words[2u * group4];
    let h23 = hp_words[2u * group4 + 1u];
    let n = count_words[group4];
    let v0 = resolve_one(l01.xy, h01.xy, n.x);
    let v1 = resolve_one(l01.zw, h01.zw, n.y);
    let v2 = resolve_one(l23.xy, h23.xy, n.z);
    let v3 = resolve_one(l23.zw, h23.zw, n.w);
    resolved_density[group4] = vec4<f32>(v0.x, v1.x, v2.x, v3.x);
    resolved_hp_mean[group4] = vec4<f32>(v0.y, v1.y, v2.y, v3.y);
}

// Grid-stride: a bounded number of workgroups each bins many voxels, so clearing and merging
// the workgroup histogram is paid a few hundred times, not once per 256 voxels.
@compute @workgroup_size(256)
fn histogram(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    clear_local_histogram(local);
    workgroupBarrier();
    let stride = groups.x * groups.y * 256u;
    // Four voxels per element; the padding is zero and so not counted.
    let group4_count = arrayLength(&density);
    var largest = vec4<f32>(0.0);
    for (var group4 = linear_index(id, groups); group4 < group4_count; group4 += stride) {
        let sums = density[group4];
        largest = max(largest, sums);
        bin_locally(sums.x, params.scales);
        bin_locally(sums.y, params.scales);
        bin_locally(sums.z, params.scales);
        bin_locally(sums.w, params.scales);
    }
    // Positive floats order as their bits do.
    atomicMax(&local_max, bitcast<u32>(max(max(largest.x, largest.y), max(largest.z, largest.w))));
    workgroupBarrier();
    for (var b = local; b < HISTOGRAM_BINS; b += 256u) {
        let n = atomicLoad(&local_histogram[b]);
        if (n > 0u) {
            atomicAdd(&stats[STATS_HISTOGRAM + b], n);
        }
    }
    if (local == 0u) {
        atomicMax(&stats[3], atomicLoad(&local_max));
    }
}

// The reference sum: the upper edge of the bin holding the percentile's rank among the
// voxels with a positive sum (rank ceil(p * n), 1-based), so at most 1 - p of them exceed it;
// capped at the largest sum (so a lone voxel, or a field of equal voxels, reaches exactly 1).
// Keep in sync with reference_sum in src/render/grid/voxelize_cpu.rs.
@compute @workgroup_size(1)
fn percentile() {
    var nonempty = 0u;
    for (var b = 0u; b < HISTOGRAM_BINS; b += 1u) {
        nonempty += atomicLoad(&stats[STATS_HISTOGRAM + b]);
    }
    atomicStore(&stats[0], nonempty);
    var reference = 1.0;
    if (nonempty > 0u) {
        let p = f32(params.counts.z) / 1000000.0;
        let rank = max(1u, u32(ceil(p * f32(nonempty))));
        var seen = 0u;
        var bin = HISTOGRAM_BINS - 1u;
        for (var b = 0u; b < HISTOGRAM_BINS; b += 1u) {
            seen += atomicLoad(&stats[STATS_HISTOGRAM + b]);
            if (seen >= rank) {
                bin = b;
                break;
            }
        }
        let largest = bitcast<f32>(atomicLoad(&stats[3]));
        reference = min(exp2(params.scales.y + f32(bin + 1u) / params.scales.z), largest);
    }
    atomicStore(&stats[1], bitcast<u32>(reference));
    reference_sum[0] = reference;
}

@compute @workgroup_size(256)
fn normalize_density(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Four voxels per thread.
    let group4 = linear_index(id, groups);
    if (group4 >= arrayLength(&density)) {
        return;
    }
    let value = density[group4] / reference_sum[0];
    let over = dot(vec4<u32>(value > vec4<f32>(1.0)), vec4<u32>(1u));
    if (over > 0u) {
        atomicAdd(&stats[2], over);
    }
    density[group4] = min(value, vec4<f32>(1.0));
}

@compute @workgroup_size(256)
fn smooth_axis(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let voxel = linear_index(id, groups);
    let dims = smooth_params.dims.xyz;
    if (voxel >= dims.x * dims.y * dims.z) {
        return;
    }
    let ijk = vec3<i32>(
        i32(voxel % dims.x),
        i32((voxel / dims.x) % dims.y),
        i32(voxel / (dims.x * dims.y)),
    );
    let axis = smooth_params.axis.x;
    let radius = i32(smooth_params.axis.y);
    var step = vec3<i32>(0);
    step[axis] = 1;
    let extent = i32(dims[axis]);
    let here = ijk[axis];
    var total = 0.0;
    var weight_sum = 0.0;
    for (var o = -radius; o <= radius; o += 1) {
        let at = here + o;
        // Outside the grid counts as missing, not as zero: weights renormalize at the edges.
        if (at < 0 || at >= extent) {
            continue;
        }
        let w = smooth_params.weights[u32(abs(o)) / 4u][u32(abs(o)) % 4u];
        let q = vec3<u32>(ijk + step * o);
        total += w * smooth_in[q.x + dims.x * (q.y + dims.y * q.z)];
        weight_sum += w;
    }
    smooth_out[voxel] = total / max(weight_sum, 1e-12);
}
