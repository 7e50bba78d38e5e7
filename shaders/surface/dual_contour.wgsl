// Dual contouring (paper 3.2). Prepended: surface/extraction.wgsl (bindings, sampling, the
// active-cell list).
// Reads the density and hp grids. `inside_bits_pass` and `classify` (32 cells per thread, from
// surface/extraction.wgsl) append the cells whose corners straddle the isovalue to the active
// list (the active index is the cell's vertex index) and reserve six indices (two triangles) for
// each crossing edge from the cell's corner 0 along +x, +y, +z whose four surrounding cells
// exist; `dispatch_active`; `cell_vertices` (per active
// cell) places the vertex; `quads` (per active cell) joins the four cells around each of its
// crossing edges through `cell_map`; `finalize` writes the vertex count and the indexed
// indirect draw.
// The vertex minimises a QEF of the edge crossings' tangent planes (normals from the field's
// central-difference gradient, interpolated along each edge), biased toward the crossings' mass
// point and clamped into its cell (Schaefer and Warren); its normal is the corner gradients
// interpolated trilinearly at the vertex, negated so it points toward lower density (the flip
// the paper makes), and quads are wound to face the same way.

// The pull toward the mass point, relative to one unit-normal plane.
const QEF_BIAS: f32 = 0.5;

// The lower corner of cube edge e (0..11): edges 4a .. 4a + 3 run along axis a, from the four
// corners whose bit a is clear (computed, not read from a constant array, which llvmpipe
// copies into every invocation when it is indexed dynamically).
fn cube_edge_start(e: u32) -> u32 {
    let j = e & 3u;
    switch (e >> 2u) {
        case 0u: {
            return j << 1u;
        }
        case 1u: {
            return (j & 1u) | ((j & 2u) << 1u);
        }
        default: {
            return j;
        }
    }
}

// Bit a (0..2) set when the edge from the cell's corner 0 along axis a crosses the isovalue and
// the four cells around it exist (the cell's lowest sample is >= 0 on the other two axes).
fn quad_edges(base: vec3<i32>, mask: u32) -> u32 {
    var edges = 0u;
    for (var axis = 0u; axis < 3u; axis++) {
        let b = (axis + 1u) % 3u;
        let c = (axis + 2u) % 3u;
        if (base[b] < 0 || base[c] < 0) {
            continue;
        }
        if (((mask >> (1u << axis)) & 1u) != (mask & 1u)) {
            edges |= 1u << axis;
        }
    }
    return edges;
}

// The cell map holds the cell's active index, which is its vertex.
fn cell_map_entry(i: u32, mask: u32, first_vertex: u32) -> u32 {
    return i;
}

// Indices of a cell: six per quad it owns (its vertex is its active index, counted apart).
fn cell_output(base: vec3<i32>, mask: u32) -> vec2<u32> {
    return vec2<u32>(0u, 6u * countOneBits(quad_edges(base, mask)));
}

@compute @workgroup_size(64)
fn cell_vertices(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = active_thread(group, groups, lane);
    if (i >= active_count() || i >= params.vertex_capacity) {
        return;
    }
    let entry = active_list[i];
    let base = slot_cell(entry.x);
    let mask = entry.y;
    let c0 = cell_corners(base, 0u);
    let c1 = cell_corners(base, 4u);
    // Central-difference gradients at the corners (24 loads beyond the corners' eight).
    var gradients: array<vec3<f32>, 8>;
    for (var k = 0u; k < 8u; k++) {
        gradients[k] = corner_gradient(base, c0, c1, k);
    }
    // The QEF sum (n.(x - p))^2 over the edge crossings p with unit normals n (the corner
    // gradients interpolated along the edge), accumulated as A = sum n n^T and b = sum n (n.p), with the
    // crossings' mass point; cell-local coordinates, [0, 1]^3.
    var count = 0u;
    var mass = vec3<f32>(0.0);
    var normal_sum = vec3<f32>(0.0);
    var a00 = 0.0;
    var a01 = 0.0;
    var a02 = 0.0;
    var a11 = 0.0;
    var a12 = 0.0;
    var a22 = 0.0;
    var b = vec3<f32>(0.0);
    // The crossed edges first, then only those: SIMD lanes loop as often as the busiest lane
    // has crossings instead of twelve times (the sums run in the same order, edge by edge).
    var crossed = 0u;
    for (var e = 0u; e < 12u; e++) {
        let ka = cube_edge_start(e);
        let kb = ka | (1u << (e >> 2u));
        if (((mask >> ka) & 1u) != ((mask >> kb) & 1u)) {
            crossed |= 1u << e;
        }
    }
    while (crossed != 0u) {
        let e = firstTrailingBit(crossed);
        crossed &= crossed - 1u;
        let ka = cube_edge_start(e);
        let kb = ka | (1u << (e >> 2u));
        let va = corner_value(c0, c1, ka);
        let vb = corner_value(c0, c1, kb);
        let t = clamp((params.iso_value - va) / (vb - va), 0.0, 1.0);
        let pa = vec3<f32>(corner_offset(ka));
        let p = pa + (vec3<f32>(corner_offset(kb)) - pa) * t;
        let g = gradients[ka] + (gradients[kb] - gradients[ka]) * t;
        var n = vec3<f32>(0.0);
        if (length(g) > 1e-20) {
            n = normalize(g);
        }
        a00 += n.x * n.x;
        a01 += n.x * n.y;
        a02 += n.x * n.z;
        a11 += n.y * n.y;
        a12 += n.y * n.z;
        a22 += n.z * n.z;
        b += n * dot(n, p);
        mass += p;
        normal_sum += n;
        count += 1u;
    }
    mass /= f32(max(count, 1u));
    // Minimise sum (n.(x - p))^2 + bias |x - mass|^2: (A + bias I) y = b - A mass, with
    // y = x - mass; A + bias I is symmetric positive definite, solved by its adjugate.
    let rhs = b - vec3<f32>(
        a00 * mass.x + a01 * mass.y + a02 * mass.z,
        a01 * mass.x + a11 * mass.y + a12 * mass.z,
        a02 * mass.x + a12 * mass.y + a22 * mass.z,
    );
    a00 += QEF_BIAS;
    a11 += QEF_BIAS;
    a22 += QEF_BIAS;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    var local = mass;
    if (abs(det) > 1e-12) {
        let y = vec3<f32>(
            c00 * rhs.x + c01 * rhs.y + c02 * rhs.z,
            c01 * rhs.x + c11 * rhs.y + c12 * rhs.z,
            c02 * rhs.x + c12 * rhs.y + c22 * rhs.z,
        ) / det;
        local = mass + y;
    }
    local = clamp(local, vec3<f32>(0.0), vec3<f32>(1.0));

    var gradient = vec3<f32>(0.0);
    var hp_sum = 0.0;
    var weight_sum = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let c = vec3<f32>(corner_offset(k));
        let weights = c * local + (vec3<f32>(1.0) - c) * (vec3<f32>(1.0) - local);
        gradient += weights.x * weights.y * weights.z * gradients[k];
        let w = max(corner_value(c0, c1, k), 0.0);
        hp_sum += w * sample_hp(base + corner_offset(k));
        weight_sum += w;
    }
    var normal = outward_normal(gradient);
    if (all(normal == vec3<f32>(0.0))) {
        normal = outward_normal(normal_sum);
    }
    // Member by member, the padding left as the buffer holds it (zero: nothing writes another
    // value there): one store fewer per vertex.
    vertices[i].position = data_position(vec3<f32>(base) + local);
    vertices[i].hp = weighted_hp(hp_sum, weight_sum);
    vertices[i].normal = normal;
}

// The vertex of the cell in slot `slot`; INVALID when it was not written.
fn slot_vertex(slot: u32) -> u32 {
    let j = cell_map[slot];
    if (j >= params.active_capacity || j >= params.vertex_capacity) {
        return INVALID;
    }
    return j;
}

// Writes quad q (vertices counter-clockwise seen from +axis when corner 0 is inside, else
// wound the other way) as two triangles at index `first` when it fits, and returns the next
// quad's first index.
fn write_quad(first: u32, q_in: vec4<u32>, inside0: bool, capacity: u32) -> u32 {
    if (first + 6u <= capacity) {
        // Inside beyond the edge: the surface faces -axis.
        var q = select(q_in.xwzy, q_in, inside0);
        if (any(q == vec4<u32>(INVALID))) {
            // A cell's vertex did not fit (the CPU grows the buffers): a degenerate pair
            // keeps the drawn range clean (index 0 is inside the vertex buffer).
            q = vec4<u32>(0u);
        }
        indices[first] = q.x;
        indices[first + 1u] = q.y;
        indices[first + 2u] = q.z;
        indices[first + 3u] = q.x;
        indices[first + 4u] = q.z;
        indices[first + 5u] = q.w;
    }
    return first + 6u;
}

@compute @workgroup_size(64)
fn quads(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = active_thread(group, groups, lane);
    if (i >= active_count()) {
        return;
    }
    let entry = active_list[i];
    // Sample s, the cell's lowest; the edges from s along +x, +y, +z. The quad around the edge
    // along a joins the cells s - eb - ec, s - ec, s and s - eb (b x c = a): six neighbours in
    // all, each loaded once and only when a crossed edge needs it; the cell's own vertex is its
    // active index (no load).
    let s = slot_cell(entry.x);
    let edges = quad_edges(s, entry.y);
    let inside0 = (entry.y & 1u) != 0u;
    let own = select(i, INVALID, i >= params.vertex_capacity);
    let strides = slot_strides();
    let sy = strides.x;
    let sz = strides.y;
    var vx = INVALID;
    var vy = INVALID;
    var vz = INVALID;
    if ((edges & 6u) != 0u) {
        vx = slot_vertex(entry.x - 1u);
    }
    if ((edges & 5u) != 0u) {
        vy = slot_vertex(entry.x - sy);
    }
    if ((edges & 3u) != 0u) {
        vz = slot_vertex(entry.x - sz);
    }
    // Whole quads only: with reservations of six, a capacity rounded down to six is never split.
    let capacity = params.index_capacity - params.index_capacity % 6u;
    var first = entry.w;
    if ((edges & 1u) != 0u) {
        let q = vec4<u32>(slot_vertex(entry.x - sy - sz), vz, own, vy);
        first = write_quad(first, q, inside0, capacity);
    }
    if ((edges & 2u) != 0u) {
        let q = vec4<u32>(slot_vertex(entry.x - sz - 1u), vx, own, vz);
        first = write_quad(first, q, inside0, capacity);
    }
    if ((edges & 4u) != 0u) {
        let q = vec4<u32>(slot_vertex(entry.x - 1u - sy), vy, own, vx);
        first = write_quad(first, q, inside0, capacity);
    }
}

@compute @workgroup_size(1)
fn finalize() {
    // One vertex per active cell.
    atomicStore(&counters.vertices, atomicLoad(&counters.active_cells));
    let capacity = params.index_capacity - params.index_capacity % 6u;
    write_indexed_draw(atomicLoad(&counters.indices), capacity);
}
