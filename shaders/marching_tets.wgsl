// Marching tetrahedra (paper 3.2). Prepended: utils/iso_grid.wgsl (bindings, sampling).
// Reads the density and hp grids; appends a triangle soup (three MeshVertex per triangle) to
// `vertices` with one atomic reservation per cell, then `finalize` writes the indirect draw.
// Every cell is split into six tetrahedra around its main diagonal (corner 0 to corner 7); the
// split of each cube face is then the same seen from either side, so the surface is watertight.

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

struct EdgePoint {
    // Grid coordinates of the crossing.
    grid: vec3<f32>,
    vertex: MeshVertex,
};

// The crossing on the edge from sample pa to sample pb (pa the lower on every axis, so both
// cells that share the edge compute exactly the same point).
// Gradients and hp at the ends come from the cell's cache (computed once per corner).
fn edge_point(
    pa: vec3<i32>, pb: vec3<i32>, va: f32, vb: f32, ga: vec3<f32>, gb: vec3<f32>, ha: f32, hb: f32,
) -> EdgePoint {
    let t = clamp((params.iso_value - va) / (vb - va), 0.0, 1.0);
    let a = vec3<f32>(pa);
    let grid = a + (vec3<f32>(pb) - a) * t;
    let gradient = ga + (gb - ga) * t;
    let wa = max(va, 0.0);
    let wb = max(vb, 0.0);
    var out: EdgePoint;
    out.grid = grid;
    out.vertex.position = data_position(grid);
    out.vertex.normal = outward_normal(gradient);
    out.vertex.hp = weighted_hp(wa * ha + wb * hb, wa + wb);
    out.vertex.pad = 0.0;
    return out;
}

fn tet_mask(tet: vec4<u32>, cell_mask: u32) -> u32 {
    return ((cell_mask >> tet.x) & 1u) | (((cell_mask >> tet.y) & 1u) << 1u)
        | (((cell_mask >> tet.z) & 1u) << 2u) | (((cell_mask >> tet.w) & 1u) << 3u);
}

@compute @workgroup_size(16, 4, 1)
fn extract(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id > params.dims)) {
        return;
    }
    let base = vec3<i32>(id) - vec3<i32>(1);
    var values: array<f32, 8>;
    var mask = 0u;
    for (var k = 0u; k < 8u; k++) {
        let v = sample_density(base + corner_offset(k));
        values[k] = v;
        if (v > params.iso_value) {
            mask |= 1u << k;
        }
    }
    if (mask == 0u || mask == 255u) {
        return;
    }
    // Gradient and hp at the eight corners, read once for all of the cell's vertices.
    var gradients: array<vec3<f32>, 8>;
    var hps: array<f32, 8>;
    for (var k = 0u; k < 8u; k++) {
        gradients[k] = sample_gradient(base + corner_offset(k));
        hps[k] = sample_hp(base + corner_offset(k));
    }
    var triangles = 0u;
    for (var t = 0u; t < 6u; t++) {
        triangles += TET_CASES[tet_mask(TETS[t], mask)] >> 24u;
    }
    let first = atomicAdd(&counters.vertices, triangles * 3u);
    var out = first;
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
            if (values[corners[v]] > params.iso_value) {
                inside_sum += p;
                inside_count += 1.0;
            } else {
                outside_sum += p;
            }
        }
        let outward = outside_sum / (4.0 - inside_count) - inside_sum / inside_count;
        for (var tri = 0u; tri < count; tri++) {
            var points: array<EdgePoint, 3>;
            for (var c = 0u; c < 3u; c++) {
                let edge = (case_bits >> (4u * (tri * 3u + c))) & 0xfu;
                let ka = corners[EDGE_A[edge]];
                let kb = corners[EDGE_B[edge]];
                points[c] = edge_point(
                    base + corner_offset(ka),
                    base + corner_offset(kb),
                    values[ka],
                    values[kb],
                    gradients[ka],
                    gradients[kb],
                    hps[ka],
                    hps[kb],
                );
            }
            var face = cross(points[1].grid - points[0].grid, points[2].grid - points[0].grid);
            if (dot(face, outward) < 0.0) {
                let swap = points[1];
                points[1] = points[2];
                points[2] = swap;
                face = -face;
            }
            // A triangle is written only when all of it fits; the count still grows, so the CPU
            // learns how much room the surface needs.
            if (out + 3u <= params.vertex_capacity) {
                // The face normal in data space (a cross product scales by the cofactors).
                let data_face = face * params.voxel_size.yzx * params.voxel_size.zxy;
                var face_normal = vec3<f32>(0.0);
                if (length(data_face) > 1e-30) {
                    face_normal = normalize(data_face);
                }
                for (var c = 0u; c < 3u; c++) {
                    var vertex = points[c].vertex;
                    if (all(vertex.normal == vec3<f32>(0.0))) {
                        vertex.normal = face_normal;
                    }
                    vertices[out + c] = vertex;
                }
            }
            out += 3u;
        }
    }
}

@compute @workgroup_size(1)
fn finalize() {
    let written = min(atomicLoad(&counters.vertices), params.vertex_capacity);
    indirect[0] = written - written % 3u;
    indirect[1] = 1u;
    indirect[2] = 0u;
    indirect[3] = 0u;
    indirect[4] = 0u;
    indirect[5] = 1u;
    indirect[6] = 0u;
    indirect[7] = 0u;
    indirect[8] = 0u;
}
