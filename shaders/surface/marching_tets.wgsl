// Marching tetrahedra (paper 3.2). Prepended: surface/extraction.wgsl (bindings, sampling, the
// active-cell list). Reads the density and hp grids; writes an indexed mesh with one vertex per
// grid edge that crosses the isovalue, shared by every triangle that uses it. Every cell is split
// into six tetrahedra around its main diagonal (corner 0 to corner 7); the split of each cube face
// is then the same seen from either side, so the surface is watertight. Every tetrahedron edge runs
// from a corner to one with a superset of its offset bits, so each edge is owned by its lower end:
// the cell whose corner 0 that is, which owns the seven edges from its corner 0 to corners 1..7 (x,
// y, xy, z, xz, yz, xyz). A crossed edge's owner holds both of its ends, so it straddles the
// isovalue and is an active cell. Passes: `inside_bits_pass` packs which samples are inside into
// bits and `classify` (32 cells per thread, both in surface/extraction.wgsl) appends the active
// cells and reserves their vertices (one per crossed owned edge) and indices (three per triangle of
// their tetrahedra); `dispatch_active`; `edge_vertices` (per active cell) places the vertices;
// `triangles` (per active cell) looks the vertices of its triangles up through `cell_map` and
// writes the indices; `finalize` writes the indexed indirect draw.

// Per cell inside mask m (bit k: corner k inside), built on the CPU from the six tetrahedra of the
// split (0-1-3-7, 0-1-5-7, 0-2-3-7, 0-2-6-7, 0-4-5-7, 0-4-6-7) and their 16-entry case table
// (src/render/surface/marching_tets.rs, case_table): word 13m holds the triangle count (at most 12)
// in its low byte and from bit 8 the corners that are the lower end of some triangle's edge (corner
// 7 never is), words 13m + 1.. one triangle each, three edges of six bits wound to face away from
// the inside corners. An edge is (lower corner ka) | (direction d) << 3: it runs from corner ka to
// corner ka + d, whose offset bits are a superset of ka's.
@group(1) @binding(10) var<storage, read> cases: array<u32>;

const CASE_STRIDE: u32 = 13u;

// Bit k (1..7) set when the owned edge from corner 0 to corner k crosses the isovalue.
fn owned_edges(mask: u32) -> u32 {
    let flip = select(0u, 0xffu, (mask & 1u) != 0u);
    return (mask ^ flip) & 0xfeu;
}

// The triangles of a tetrahedron with `inside` of its four corners inside: one when one or
// three are, two when two are.
fn tet_triangles(inside: u32) -> u32 {
    return select(inside & 1u, 2u, inside == 2u);
}

// The triangle count of cell mask `mask` (the low byte of its `cases` header), from the inside
// corners of its six tetrahedra (0-1-3-7, 0-1-5-7, 0-2-3-7, 0-2-6-7, 0-4-5-7, 0-4-6-7) without
// a load.
fn cell_triangles(mask: u32) -> u32 {
    return tet_triangles(countOneBits(mask & 0x8bu)) + tet_triangles(countOneBits(mask & 0xa3u))
        + tet_triangles(countOneBits(mask & 0x8du)) + tet_triangles(countOneBits(mask & 0xc5u))
        + tet_triangles(countOneBits(mask & 0xb1u)) + tet_triangles(countOneBits(mask & 0xd1u));
}

// Vertices (one per crossed owned edge) and indices (three per triangle) of a cell.
fn cell_output(base: vec3<i32>, mask: u32) -> vec2<u32> {
    return vec2<u32>(countOneBits(owned_edges(mask)), 3u * cell_triangles(mask));
}

// The cell map holds an active cell's first vertex and its owned crossing edges (bits 1..7 of
// owned_edges, shifted down by one); vertex indices from 2^25 on do not fit (the CPU never
// grows the vertex buffer that far).
const MAX_MAPPED_VERTICES: u32 = 0x2000000u;

fn cell_map_entry(i: u32, mask: u32, first_vertex: u32) -> u32 {
    if (first_vertex >= MAX_MAPPED_VERTICES) {
        return INVALID;
    }
    return (first_vertex << 7u) | (owned_edges(mask) >> 1u);
}

@compute @workgroup_size(64)
fn edge_vertices(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = active_thread(group, groups, lane);
    if (i >= active_count()) {
        return;
    }
    let entry = active_list[i];
    let owned = owned_edges(entry.y);
    if (owned == 0u || entry.z >= params.vertex_capacity) {
        return;
    }
    let base = slot_cell(entry.x);
    // The cell's eight corner values, loaded once: every owned edge lies in the cell, so they
    // hold each vertex's far end and half of the central differences at both ends.
    let c0 = cell_corners(base, 0u);
    let c1 = cell_corners(base, 4u);
    let v0 = c0.x;
    let g0 = corner_gradient(base, c0, c1, 0u);
    let h0 = sample_hp(base);
    let w0 = max(v0, 0.0);
    let inside0 = (entry.y & 1u) != 0u;
    var out = entry.z;
    // Only the crossed edges: SIMD lanes loop as often as the busiest lane has crossings.
    var todo = owned;
    while (todo != 0u && out < params.vertex_capacity) {
        let k = firstTrailingBit(todo);
        todo &= todo - 1u;
        let offset = corner_offset(k);
        let vk = corner_value(c0, c1, k);
        let hk = sample_hp(base + offset);
        let t = clamp((params.iso_value - v0) / (vk - v0), 0.0, 1.0);
        let gk = corner_gradient(base, c0, c1, k);
        var normal = outward_normal(g0 + (gk - g0) * t);
        if (all(normal == vec3<f32>(0.0))) {
            // No gradient: the edge's own direction, from its inside end to its outside end.
            let along = normalize(vec3<f32>(offset) * params.voxel_size);
            normal = select(-along, along, inside0);
        }
        let wk = max(vk, 0.0);
        // Member by member, the padding left as the buffer holds it (zero: nothing writes
        // another value there): one store fewer per vertex.
        vertices[out].position = data_position(vec3<f32>(base) + vec3<f32>(offset) * t);
        vertices[out].hp = weighted_hp(w0 * h0 + wk * hk, w0 + wk);
        vertices[out].normal = normal;
        out += 1u;
    }
}

// The vertex on edge code `edge` (see `cases`), given the cell-map entries of the cells whose
// corner 0 is the cell's corner c (entries: corners 0..3, entries_hi: corners 4..6), the
// owners of the edges starting there; INVALID when it was not written.
fn edge_vertex(edge: u32, entries: vec4<u32>, entries_hi: vec4<u32>) -> u32 {
    let lower = edge & 7u;
    let entry = select(entries, entries_hi, lower >= 4u)[lower & 3u];
    if (entry == INVALID) {
        return INVALID;
    }
    let owned = (entry & 0x7fu) << 1u;
    let index = (entry >> 7u) + countOneBits(owned & ((1u << (edge >> 3u)) - 1u));
    if (index >= params.vertex_capacity) {
        return INVALID;
    }
    return index;
}

@compute @workgroup_size(64)
fn triangles(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = active_thread(group, groups, lane);
    if (i >= active_count()) {
        return;
    }
    let entry = active_list[i];
    let row = entry.y * CASE_STRIDE;
    let header = cases[row];
    let count = header & 0xffu;
    // The owners' cell-map entries (the cells whose corner 0 is this cell's corner c), each
    // loaded once, by strides with no division back to cell coordinates; the cell's own entry
    // needs no load.
    let needed = header >> 8u;
    let strides = slot_strides();
    var entries = vec4<u32>(cell_map_entry(i, entry.y, entry.z), INVALID, INVALID, INVALID);
    var entries_hi = vec4<u32>(INVALID);
    for (var c = 1u; c < 7u; c++) {
        if (((needed >> c) & 1u) == 0u) {
            continue;
        }
        let step = (c & 1u) + strides.x * ((c >> 1u) & 1u) + strides.y * (c >> 2u);
        let owner = cell_map[entry.x + step];
        if (c < 4u) {
            entries[c] = owner;
        } else {
            entries_hi[c - 4u] = owner;
        }
    }
    // Whole triangles only, so every index below the drawn count is written.
    let capacity = params.index_capacity - params.index_capacity % 3u;
    var out = entry.w;
    for (var tri = 0u; tri < count; tri++) {
        if (out + 3u > capacity) {
            break;
        }
        let code = cases[row + 1u + tri];
        var a = edge_vertex(code & 0x3fu, entries, entries_hi);
        var b = edge_vertex((code >> 6u) & 0x3fu, entries, entries_hi);
        var c = edge_vertex((code >> 12u) & 0x3fu, entries, entries_hi);
        if (a == INVALID || b == INVALID || c == INVALID) {
            // A vertex did not fit (the CPU grows the buffers): a degenerate triangle keeps the
            // drawn range clean (index 0 is inside the vertex buffer).
            a = 0u;
            b = 0u;
            c = 0u;
        }
        indices[out] = a;
        indices[out + 1u] = b;
        indices[out + 2u] = c;
        out += 3u;
    }
}

@compute @workgroup_size(1)
fn finalize() {
    let capacity = params.index_capacity - params.index_capacity % 3u;
    write_indexed_draw(atomicLoad(&counters.indices), capacity);
}
