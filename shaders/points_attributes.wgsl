// Points view without storage buffers (WebGL2, the web page's fallback): the discs of
// points.wgsl, three vertices a point (not instanced, as points.wgsl), each vertex reading its
// point's record (x, y, z, scalar, hp, the PLY record as is, stored three times) as vertex
// attributes. z is drawn as stored: the
// frequency axis's per-bin table is a storage buffer, which this variant has not.
// Keep PointStyleParams in sync with src/render/points_attributes.rs, and the disc (corners,
// pixel size, hidden points, shading) in sync with vs_main and fs_main of points.wgsl.

struct PointStyleParams {
    // Disc diameter in pixels.
    size_px: f32,
    // Points with scalar below this are not drawn.
    min_scalar: f32,
    _pad: vec2<f32>,
};

@group(1) @binding(0) var<uniform> params: PointStyleParams;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) corner: vec2<f32>,
    @location(1) color: vec3<f32>,
};

@vertex
fn vs_main(
    @builtin(vertex_index) vertex_index: u32,
    @location(0) position: vec3<f32>,
    // scalar, hp
    @location(1) values: vec2<f32>,
) -> VertexOut {
    var out: VertexOut;
    let corners = array<vec2<f32>, 3>(
        vec2<f32>(0.0, 2.0), vec2<f32>(-1.7320508, -1.0), vec2<f32>(1.7320508, -1.0),
    );
    let corner = corners[vertex_index % 3u];
    var clip = frame.clip_from_data * vec4<f32>(position, 1.0);
    let half_size = 0.5 * params.size_px * frame.viewport.zw * 2.0;
    clip = vec4<f32>(clip.xy + corner * half_size * clip.w, clip.zw);
    if (values.x < params.min_scalar) {
        clip = vec4<f32>(0.0, 0.0, -2.0, 1.0);
    }
    out.clip = clip;
    out.corner = corner;
    out.color = hp_palette(values.y);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.corner, in.corner);
    if (r2 > 1.0) {
        discard;
    }
    let shade = 1.0 - 0.25 * r2;
    return vec4<f32>(in.color * shade, 1.0);
}
