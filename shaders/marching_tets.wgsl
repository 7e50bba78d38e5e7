// Marching tetrahedra (paper 3.2). Prepended: utils/iso_grid.wgsl (bindings, sampling, the
// active-cell list).
// Reads the density and hp grids; writes an indexed mesh with one vertex per grid edge that
// crosses the isovalue, shared by every triangle that uses it.
// Every cell is split into six tetrahedra around its main diagonal (corner 0 to corner 7); the
// split of each cube face is then the same seen from either side, so the surface is watertight.
// Every tetrahedron edge runs from a corner to one with a superset of its offset bits, so each
// edge is owned by its lower end: the cell whose corner 0 that is, which owns the seven edges
// from its corner 0 to corners 1..7 (x, y, xy, z, xz, yz, xyz). A crossed edge's owner holds
// both of its ends, so it straddles the isovalue and is an active cell.
// Passes: `classify` (every cell) appends the active cells and reserves their vertices (one per
// crossed owned edge) and indices (three per triangle of their tetrahedra); `dispatch_active`;
// `edge_vertices` (per active cell) places the vertices; `triangles` (per active cell) looks the
// vertices of its triangles up through `cell_map` and writes the indices; `finalize` writes the
// indexed indirect draw.

// The six tetrahedra of a cell as cube-corner indices, each a chain 0 -> 0+a -> 0+a+b -> 7, so
// within a tetrahedron a lower corner index is also the lower point on every axis.
const TETS = array<vec4<u32>, 6>(
    vec4<u32>(0u, 1u, 3u, 7u),
    vec4<u32>(0u, 1u, 5u, 7u),
    vec4<u32>(0u, 2u, 3u, 7u),
    vec4<u32>(0u, 2u, 6u, 7u),
    vec4<u32>(0u, 4u, 5u, 7u),
    vec4<u32>(0u, 4u, 6u, 7u),
);

// Tetrahedron edges as vertex pairs: e0 = 01, e1 = 02, e2 = 03, e3 = 12, e4 = 13, e5 = 23.
const EDGE_A = array<u32, 6>(0u, 0u, 0u, 1u, 1u, 2u);
const EDGE_B = array<u32, 6>(1u, 2u, 3u, 2u, 3u, 3u);

// Case table, indexed by the inside mask of the four vertices (bit v: vertex v inside): bits
// 24.. hold the triangle count (0 to 2), bits 4i..4i+3 the i-th edge of the triangles. Winding is
// fixed afterwards so every triangle faces away from the inside vertices.
const TET_CASES = array<u32, 16>(
    0x00000000u, 0x01000210u, 0x01000430u, 0x02241431u, 0x01000531u, 0x02250530u, 0x02450510u,
    0x01000542u, 0x01000542u, 0x02150540u, 0x02350520u, 0x01000531u, 0x02341421u, 0x01000430u,
    0x01000210u, 0x00000000u,
);

fn tet_mask(tet: vec4<u32>, cell_mask: u32) -> u32 {
    return ((cell_mask >> tet.x) & 1u) | (((cell_mask >> tet.y) & 1u) << 1u)
        | (((cell_mask >> tet.z) & 1u) << 2u) | (((cell_mask >> tet.w) & 1u) << 3u);
}

// Bit k (1..7) set when the owned edge from corner 0 to corner k crosses the isovalue.
fn owned_edges(mask: u32) -> u32 {
    let flip = select(0u, 0xffu, (mask & 1u) != 0u);
    return (mask ^ flip) & 0xfeu;
}

fn cell_triangles(mask: u32) -> u32 {
    var triangles = 0u;
    for (var t = 0u; t < 6u; t++) {
        triangles += TET_CASES[tet_mask(TETS[t], mask)] >> 24u;
    }
    return triangles;
}

// Vertices (one per crossed owned edge) and indices (three per triangle) of a cell.
fn cell_output(base: vec3<i32>, mask: u32) -> vec2<u32> {
    return vec2<u32>(countOneBits(owned_edges(mask)), 3u * cell_triangles(mask));
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
    let v0 = sample_density(base);
    let g0 = sample_gradient(base);
    let h0 = sample_hp(base);
    let w0 = max(v0, 0.0);
    let inside0 = (entry.y & 1u) != 0u;
    var out = entry.z;
    for (var k = 1u; k < 8u; k++) {
        if (((owned >> k) & 1u) == 0u) {
            continue;
        }
        if (out >= params.vertex_capacity) {
            break;
        }
        let offset = corner_offset(k);
        let pk = base + offset;
        let vk = sample_density(pk);
        let gk = sample_gradient(pk);
        let hk = sample_hp(pk);
        let t = clamp((params.iso_value - v0) / (vk - v0), 0.0, 1.0);
        let grid = vec3<f32>(base) + vec3<f32>(offset) * t;
        var normal = outward_normal(g0 + (gk - g0) * t);
        if (all(normal == vec3<f32>(0.0))) {
            // No gradient: the edge's own direction, from its inside end to its outside end.
            let along = normalize(vec3<f32>(offset) * params.voxel_size);
            normal = select(-along, along, inside0);
        }
        let wk = max(vk, 0.0);
        var vertex: MeshVertex;
        vertex.position = data_position(grid);
        vertex.hp = weighted_hp(w0 * h0 + wk * hk, w0 + wk);
        vertex.normal = normal;
        vertex.pad = 0.0;
        vertices[out] = vertex;
        out += 1u;
    }
}

// The vertex on the edge from `lower` to lower + corner_offset(direction), owned by the cell
// whose lowest sample is `lower`; INVALID when it was not written.
fn edge_vertex(lower: vec3<i32>, direction: u32) -> u32 {
    let j = cell_map[cell_slot(lower)];
    if (j >= params.active_capacity) {
        return INVALID;
    }
    let owner = active_list[j];
    let index = owner.z + countOneBits(owned_edges(owner.y) & ((1u << direction) - 1u));
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
    let base = slot_cell(entry.x);
    let mask = entry.y;
    // Whole triangles only, so every index below the drawn count is written.
    let capacity = params.index_capacity - params.index_capacity % 3u;
    var out = entry.w;
    for (var t = 0u; t < 6u; t++) {
        let tet = TETS[t];
        let case_bits = TET_CASES[tet_mask(tet, mask)];
        let count = case_bits >> 24u;
        if (count == 0u) {
            continue;
        }
        let corners = array<u32, 4>(tet.x, tet.y, tet.z, tet.w);
        // From the inside vertices toward the outside ones: the way triangles must face.
        var inside_sum = vec3<f32>(0.0);
        var outside_sum = vec3<f32>(0.0);
        var inside_count = 0.0;
        for (var v = 0u; v < 4u; v++) {
            let p = vec3<f32>(corner_offset(corners[v]));
            if (((mask >> corners[v]) & 1u) != 0u) {
                inside_sum += p;
                inside_count += 1.0;
            } else {
                outside_sum += p;
            }
        }
        let outward = outside_sum / (4.0 - inside_count) - inside_sum / inside_count;
        for (var tri = 0u; tri < count; tri++) {
            if (out + 3u <= capacity) {
                var index: array<u32, 3>;
                var mid: array<vec3<f32>, 3>;
                var valid = true;
                for (var c = 0u; c < 3u; c++) {
                    let edge = (case_bits >> (4u * (tri * 3u + c))) & 0xfu;
                    let ka = corners[EDGE_A[edge]];
                    let kb = corners[EDGE_B[edge]];
                    // The orientation of a triangle on these edges is the same wherever on the
                    // edges its corners lie, so the edge midpoints decide it.
                    mid[c] = 0.5 * vec3<f32>(corner_offset(ka) + corner_offset(kb));
                    index[c] = edge_vertex(base + corner_offset(ka), ka ^ kb);
                    valid = valid && index[c] != INVALID;
                }
                if (dot(cross(mid[1] - mid[0], mid[2] - mid[0]), outward) < 0.0) {
                    let swap = index[1];
                    index[1] = index[2];
                    index[2] = swap;
                }
                if (!valid) {
                    // A vertex did not fit (the CPU grows the buffers): a degenerate triangle
                    // keeps the drawn range clean (index 0 is inside the vertex buffer).
                    index = array<u32, 3>(0u, 0u, 0u);
                }
                indices[out] = index[0];
                indices[out + 1u] = index[1];
                indices[out + 2u] = index[2];
            }
            out += 3u;
        }
    }
}

@compute @workgroup_size(1)
fn finalize() {
    let capacity = params.index_capacity - params.index_capacity % 3u;
    write_indexed_draw(atomicLoad(&counters.indices), capacity);
}
