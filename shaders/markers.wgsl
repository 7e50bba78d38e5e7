// Markers: translucent boxes and planes over the data (the playhead, a loop range, the hovered
// timeline song), one instance per box, with their edges. Keep `MarkerInstance` in sync with
// `MarkerBox` in src/render/markers.rs.

struct MarkerInstance {
    @location(0) box_min: vec4<f32>,
    @location(1) box_max: vec4<f32>,
    @location(2) fill: vec4<f32>,
    @location(3) edge: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

fn corner_position(corner: u32, box_min: vec3<f32>, box_max: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        select(box_min.x, box_max.x, (corner & 1u) != 0u),
        select(box_min.y, box_max.y, (corner & 2u) != 0u),
        select(box_min.z, box_max.z, (corner & 4u) != 0u),
    );
}

// Two triangles per face; faces -x, +x, -y, +y, -z, +z (corner bits: 1 x, 2 y, 4 z).
@vertex
fn vs_fill(@builtin(vertex_index) vertex: u32, box: MarkerInstance) -> VertexOut {
    var corners = array<u32, 36>(
        0u, 4u, 6u, 0u, 6u, 2u,
        1u, 3u, 7u, 1u, 7u, 5u,
        0u, 1u, 5u, 0u, 5u, 4u,
        2u, 6u, 7u, 2u, 7u, 3u,
        0u, 2u, 3u, 0u, 3u, 1u,
        4u, 5u, 7u, 4u, 7u, 6u,
    );
    let face = vertex / 6u;
    let axis = face / 2u;
    let size = box.box_max.xyz - box.box_min.xyz;
    // A flat box is a plane: draw its two coinciding faces once.
    let flat = size[axis] <= 1e-6;
    var corner = corners[vertex];
    if (flat && face % 2u == 1u) {
        corner = 0u;
    }
    var out: VertexOut;
    let p = corner_position(corner, box.box_min.xyz, box.box_max.xyz);
    out.clip = frame.clip_from_data * vec4<f32>(p, 1.0);
    out.color = box.fill;
    return out;
}

// The twelve edges, two vertices each.
@vertex
fn vs_edge(@builtin(vertex_index) vertex: u32, box: MarkerInstance) -> VertexOut {
    var corners = array<u32, 24>(
        0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u,
        0u, 2u, 1u, 3u, 4u, 6u, 5u, 7u,
        0u, 4u, 1u, 5u, 2u, 6u, 3u, 7u,
    );
    var out: VertexOut;
    let p = corner_position(corners[vertex], box.box_min.xyz, box.box_max.xyz);
    out.clip = frame.clip_from_data * vec4<f32>(p, 1.0);
    out.color = box.edge;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return in.color;
}
