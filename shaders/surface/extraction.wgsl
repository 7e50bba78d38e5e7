// Shared by the isosurface extraction passes (marching_tets.wgsl, dual_contour.wgsl): the grid they
// read, the mesh they write, the active-cell list, and sampling helpers. Keep IsoParams,
// MeshVertex, Counters and the binding numbers in sync with src/render/surface/buffers.rs.
//
// Every extraction runs in the same shape: `word_range_pass` (once per grid, kept for the next
// isovalue) finds each 32-sample word's lowest and highest density; `inside_bits_pass` packs
// which samples are inside into bits (one load per sample, only in the words whose range
// straddles the isovalue: the others are all in or all out); `classify` finds, 32 cells per
// thread, the cells whose corners straddle the isovalue and appends only those to
// `active_list`, reserving their output with atomics; `dispatch_active` turns the count into indirect dispatch arguments; the
// expensive passes then run one thread per active cell (a few % of the grid), so SIMD lanes are
// not spent on empty cells.
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
    // Entries of `active`.
    active_capacity: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
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
    // Cells whose corners straddle the isovalue.
    active_cells: atomic<u32>,
    pad: u32,
};

@group(1) @binding(0) var<uniform> params: IsoParams;
@group(1) @binding(1) var<storage, read> density: array<f32>;
@group(1) @binding(2) var<storage, read> hp_mean: array<f32>;
@group(1) @binding(3) var<storage, read_write> vertices: array<MeshVertex>;
@group(1) @binding(4) var<storage, read_write> counters: Counters;
// [0..4]: DrawIndirectArgs, [4..9]: DrawIndexedIndirectArgs, [9..12]: DispatchIndirectArgs
// over the active cells (wgpu::util layouts).
@group(1) @binding(5) var<storage, read_write> indirect: array<u32, 12>;
@group(1) @binding(6) var<storage, read_write> indices: array<u32>;
// One entry per cell ((dims + 1)^3, cell c at cell_slot(c)): what the method's `cell_map_entry`
// makes of an active cell, or INVALID when it did not fit in the active list. Written only for
// active cells, and only read for cells known to be active.
@group(1) @binding(7) var<storage, read_write> cell_map: array<u32>;
// One entry per active cell: (cell_slot, inside mask of its eight corners, first vertex, first
// index) as reserved by `classify`.
@group(1) @binding(8) var<storage, read_write> active_list: array<vec4<u32>>;
// Whether each sample is inside, 32 to a word (see bit_words); after the bits, from
// `range_start()`, the lowest and highest density of each word's 32 samples (samples outside
// the grid count as 0; two f32 by their bits), written by `word_range_pass` once per grid and
// kept for the next isovalue, so `inside_bits_pass` loads only the words whose range straddles
// the isovalue.
@group(1) @binding(9) var<storage, read_write> inside_bits: array<u32>;

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

// The densities at corners first .. first + 3 of the cell whose lowest sample is `base`
// (first 0: corners 0..3, first 4: corners 4..7).
fn cell_corners(base: vec3<i32>, first: u32) -> vec4<f32> {
    return vec4<f32>(
        sample_density(base + corner_offset(first)),
        sample_density(base + corner_offset(first + 1u)),
        sample_density(base + corner_offset(first + 2u)),
        sample_density(base + corner_offset(first + 3u)),
    );
}

// The value at corner k of a cell whose corner values are c0 (corners 0..3) and c1 (4..7).
fn corner_value(c0: vec4<f32>, c1: vec4<f32>, k: u32) -> f32 {
    return select(c0, c1, k >= 4u)[k & 3u];
}

// The central-difference gradient (grid units) at corner k of the cell whose lowest sample is
// `base`, from the cell's corner values c0 (corners 0..3) and c1 (4..7) and the three samples
// beyond the cell next to the corner (three loads instead of six).
fn corner_gradient(base: vec3<i32>, c0: vec4<f32>, c1: vec4<f32>, k: u32) -> vec3<f32> {
    let offset = corner_offset(k);
    let p = base + offset;
    // Along each axis the neighbour inside the cell is the corner with that bit flipped; the
    // one outside lies one sample further out.
    let inside = vec3<f32>(
        corner_value(c0, c1, k ^ 1u),
        corner_value(c0, c1, k ^ 2u),
        corner_value(c0, c1, k ^ 4u),
    );
    let step = vec3<i32>(1) - 2 * offset;
    let outside = vec3<f32>(
        sample_density(p - vec3<i32>(step.x, 0, 0)),
        sample_density(p - vec3<i32>(0, step.y, 0)),
        sample_density(p - vec3<i32>(0, 0, step.z)),
    );
    // Toward +axis: (value at +1) - (value at -1); the inside neighbour sits at +step.
    return 0.5 * (inside - outside) * vec3<f32>(step);
}

// The hp of a set of samples, weighted by their density (empty voxels carry no colour).
fn weighted_hp(sum_weighted: f32, sum_weights: f32) -> f32 {
    if (sum_weights <= 1e-12) {
        return 0.5;
    }
    return clamp(sum_weighted / sum_weights, 0.0, 1.0);
}

// The steps between neighbouring slots of `cell_map` along y and z (along x: 1).
fn slot_strides() -> vec2<u32> {
    let sy = params.dims.x + 1u;
    return vec2<u32>(sy, sy * (params.dims.y + 1u));
}

// The cell's slot in `cell_map`: cells run from -1 to dims - 1 on each axis.
fn cell_slot(cell: vec3<i32>) -> u32 {
    let q = vec3<u32>(cell + vec3<i32>(1));
    let strides = slot_strides();
    return q.x + strides.x * q.y + strides.y * q.z;
}

// The cell (its lowest sample) of a slot.
fn slot_cell(slot: u32) -> vec3<i32> {
    // Two divisions (llvmpipe runs vector integer division lane by lane).
    let side = params.dims + vec3<u32>(1u);
    let layer = side.x * side.y;
    let z = slot / layer;
    let in_layer = slot - z * layer;
    let y = in_layer / side.x;
    return vec3<i32>(vec3<u32>(in_layer - y * side.x, y, z)) - vec3<i32>(1);
}

// Records active cell i (INVALID in `cell_map` when the list is full).
fn store_active(i: u32, base: vec3<i32>, mask: u32, first_vertex: u32, first_index: u32) {
    let slot = cell_slot(base);
    if (i < params.active_capacity) {
        active_list[i] = vec4<u32>(slot, mask, first_vertex, first_index);
        cell_map[slot] = cell_map_entry(i, mask, first_vertex);
    } else {
        cell_map[slot] = INVALID;
    }
}

// Threads of the one-dimensional passes: 64 per workgroup, workgroups in x then y (keep in sync
// with FLAT_WORKGROUP and FLAT_ROW in src/render/surface/buffers.rs).
const ACTIVE_WORKGROUP: u32 = 64u;
const ACTIVE_ROW: u32 = 32768u;

fn active_count() -> u32 {
    return min(atomicLoad(&counters.active_cells), params.active_capacity);
}

fn active_thread(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (group.x + group.y * groups.x) * ACTIVE_WORKGROUP + local;
}

// Inside bits: the samples padded by one on each side ((dims + 2)^3, sample p at p + 1), 32
// along x per word; row (y, z) of the padded samples starts at word
// bit_words() * (y + (dims.y + 2) * z).
fn bit_words() -> u32 {
    return (params.dims.x + 2u + 31u) / 32u;
}

fn bit_word(w: u32, y: u32, z: u32) -> u32 {
    return inside_bits[w + bit_words() * (y + (params.dims.y + 2u) * z)];
}

// Where the word ranges start in `inside_bits`: after the bits.
fn range_start() -> u32 {
    return bit_words() * (params.dims.y + 2u) * (params.dims.z + 2u);
}

// The word of inside bits thread t packs: its word along x and its padded row's y and z (-1 ..
// dims), or None past the last word.
fn bit_word_of(t: u32) -> vec4<i32> {
    let words = bit_words();
    let side = params.dims + vec3<u32>(2u);
    let w = t % words;
    let row = t / words;
    let valid = i32(t < words * side.y * side.z);
    return vec4<i32>(i32(w), i32(row % side.y) - 1, i32(row / side.y) - 1, valid);
}

// Whether padded row (y, z) lies in the grid (else all of its samples read as density 0).
fn row_in_grid(y: i32, z: i32) -> bool {
    return y >= 0 && y < i32(params.dims.y) && z >= 0 && z < i32(params.dims.z);
}

// The samples of word `word` (see bit_word_of; its row in the grid): the density index of its
// bit 0 (sample x = 32 w - 1, which may lie before the row) and the bits [first, end) that lie
// in the row, as (index, first, end).
fn word_samples(word: vec4<i32>) -> vec3<i32> {
    let x0 = word.x * 32 - 1;
    let row_start = i32(params.dims.x * (u32(word.y) + params.dims.y * u32(word.z)));
    return vec3<i32>(row_start + x0, max(-x0, 0), clamp(i32(params.dims.x) - x0, 0, 32));
}

// Where the density range of thread t's word lies in `inside_bits`: its lowest, then its highest.
fn range_slot(t: u32) -> u32 {
    return range_start() + 2u * t;
}

// Whether `v` is NaN (by its bits, which no fast-math assumption folds away).
fn is_nan(v: f32) -> bool {
    return (bitcast<u32>(v) & 0x7fffffffu) > 0x7f800000u;
}

// One thread per word of inside bits, once per grid: the lowest and highest density of the
// word's 32 samples. A NaN sample, which is never inside, makes the lowest NaN (so the word is
// never taken as all inside) and is passed over for the highest.
@compute @workgroup_size(64)
fn word_range_pass(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = active_thread(group, groups, lane);
    let word = bit_word_of(t);
    if (word.w == 0) {
        return;
    }
    var lo = 0.0;
    var hi = 0.0;
    if (row_in_grid(word.y, word.z)) {
        let samples = word_samples(word);
        // A word reaching past the row holds samples of density 0; a whole one starts from its
        // first sample.
        if (samples.y == 0 && samples.z == 32) {
            lo = density[u32(samples.x)];
            hi = select(lo, 0.0, is_nan(lo));
        }
        for (var b = samples.y; b < samples.z; b++) {
            let v = density[u32(samples.x + b)];
            lo = select(select(lo, v, v < lo || is_nan(v)), lo, is_nan(lo));
            hi = select(hi, v, v > hi);
        }
    }
    inside_bits[range_slot(t)] = bitcast<u32>(lo);
    inside_bits[range_slot(t) + 1u] = bitcast<u32>(hi);
}

// One thread per word of inside bits: 32 loads and compares and one store where the word's
// density range straddles the isovalue; elsewhere one load of the range and the store.
@compute @workgroup_size(64)
fn inside_bits_pass(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = active_thread(group, groups, lane);
    let word = bit_word_of(t);
    if (word.w == 0) {
        return;
    }
    let range = vec2<f32>(
        bitcast<f32>(inside_bits[range_slot(t)]),
        bitcast<f32>(inside_bits[range_slot(t) + 1u]),
    );
    // Samples outside the grid read as density 0.
    var bits = select(0u, 0xffffffffu, 0.0 > params.iso_value);
    if (!(range.y > params.iso_value)) {
        // No sample above the isovalue.
        bits = 0u;
    } else if (range.x > params.iso_value) {
        // Every sample above it.
        bits = 0xffffffffu;
    } else if (row_in_grid(word.y, word.z)) {
        let samples = word_samples(word);
        for (var b = samples.y; b < samples.z; b++) {
            let inside = density[u32(samples.x + b)] > params.iso_value;
            bits = (bits & ~(1u << u32(b))) | (u32(inside) << u32(b));
        }
    }
    inside_bits[t] = bits;
}

// The bits of words r (x) and r shifted to x + 1 (`next`: the following word of the row).
fn shifted(r: u32, next: u32) -> u32 {
    return (r >> 1u) | (next << 31u);
}

// One thread per 32 cells along x: finds the cells whose eight corners straddle the isovalue
// from the inside bits of four rows, asks the method how much output each needs
// (`cell_output`: vertices, indices), reserves it for all 32 with one atomic add per counter
// and appends the cells to the active list.
@compute @workgroup_size(64)
fn classify(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = active_thread(group, groups, lane);
    let words = bit_words();
    let cells = params.dims + vec3<u32>(1u);
    if (t >= words * cells.y * cells.z) {
        return;
    }
    let w = t % words;
    let row = t / words;
    let y = row % cells.y;
    let z = row / cells.y;
    var r: array<u32, 8>;
    for (var k = 0u; k < 4u; k++) {
        let ry = y + (k & 1u);
        let rz = z + (k >> 1u);
        let word = bit_word(w, ry, rz);
        var next = 0u;
        if (w + 1u < words) {
            next = bit_word(w + 1u, ry, rz);
        }
        // Corner 2k: x, corner 2k + 1: x + 1.
        r[2u * k] = word;
        r[2u * k + 1u] = shifted(word, next);
    }
    var all_in = r[0];
    var any_in = r[0];
    for (var k = 1u; k < 8u; k++) {
        all_in &= r[k];
        any_in |= r[k];
    }
    // Cells 32w + b exist for 32w + b <= dims.x.
    let count = params.dims.x + 1u - min(w * 32u, params.dims.x + 1u);
    var valid = 0xffffffffu;
    if (count < 32u) {
        valid = (1u << count) - 1u;
    }
    let todo = any_in & ~all_in & valid;
    if (todo == 0u) {
        return;
    }
    var total = vec2<u32>(0u);
    var bits = todo;
    while (bits != 0u) {
        let b = firstTrailingBit(bits);
        bits &= bits - 1u;
        total += cell_output(vec3<i32>(vec3<u32>(w * 32u + b, y, z)) - vec3<i32>(1), corner_bits(r, b));
    }
    var i = atomicAdd(&counters.active_cells, countOneBits(todo));
    var first_vertex = 0u;
    if (total.x > 0u) {
        first_vertex = atomicAdd(&counters.vertices, total.x);
    }
    var first_index = 0u;
    if (total.y > 0u) {
        first_index = atomicAdd(&counters.indices, total.y);
    }
    bits = todo;
    while (bits != 0u) {
        let b = firstTrailingBit(bits);
        bits &= bits - 1u;
        let base = vec3<i32>(vec3<u32>(w * 32u + b, y, z)) - vec3<i32>(1);
        let mask = corner_bits(r, b);
        store_active(i, base, mask, first_vertex, first_index);
        let out = cell_output(base, mask);
        first_vertex += out.x;
        first_index += out.y;
        i += 1u;
    }
}

// The inside mask of cell b of the eight corner words (bit k: corner k).
fn corner_bits(r: array<u32, 8>, b: u32) -> u32 {
    var mask = 0u;
    for (var k = 0u; k < 8u; k++) {
        mask |= ((r[k] >> b) & 1u) << k;
    }
    return mask;
}

// The indirect dispatch over the active cells.
@compute @workgroup_size(1)
fn dispatch_active() {
    let groups = (active_count() + ACTIVE_WORKGROUP - 1u) / ACTIVE_WORKGROUP;
    let x = min(groups, ACTIVE_ROW);
    indirect[9] = x;
    indirect[10] = (groups + ACTIVE_ROW - 1u) / ACTIVE_ROW;
    indirect[11] = 1u;
}

// The indexed indirect draw of the first `count` indices (at most `capacity`).
fn write_indexed_draw(count: u32, capacity: u32) {
    indirect[0] = 0u;
    indirect[1] = 1u;
    indirect[2] = 0u;
    indirect[3] = 0u;
    indirect[4] = min(count, capacity);
    indirect[5] = 1u;
    indirect[6] = 0u;
    indirect[7] = 0u;
    indirect[8] = 0u;
}
