// Points view without storage buffers (WebGL2, the web page's fallback): the discs of
// points.wgsl, three vertices a point (not instanced, as points.wgsl), each vertex reading its
// point's record (x, y, z, scalar, hp, the PLY record as is, stored three times) as vertex
// attributes. z is drawn as stored: the
// frequency axis's per-bin table is a storage buffer, which this variant has not.
// Keep PointStyleParams in sync with src/render/points_attributes.rs; the disc itself is
// shaders/utils/point_disc.wgsl, shared with points.wgsl.

struct PointStyleParams {
    // Disc diameter in pixels.
    size_px: f32,
    // Points with scalar below this are not drawn.
    min_scalar: f32,
    _pad: vec2<f32>,
};

@group(1) @binding(0) var<uniform> params: PointStyleParams;

@vertex
fn vs_main(
    @builtin(vertex_index) vertex_index: u32,
    @location(0) position: vec3<f32>,
    // scalar, hp
    @location(1) values: vec2<f32>,
) -> DiscVertex {
    let hidden = values.x < params.min_scalar;
    return disc_vertex(position, vertex_index % 3u, params.size_px, hp_palette(values.y), hidden);
}

@fragment
fn fs_main(in: DiscVertex) -> @location(0) vec4<f32> {
    if (!disc_inside(in.corner)) {
        discard;
    }
    return disc_colour(in.corner, in.color);
}
