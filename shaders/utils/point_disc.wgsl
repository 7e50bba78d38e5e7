// A point drawn as a screen-aligned disc: one triangle around the unit disc (three vertices a
// point, not six: vertex work dominates on software rasterizers), a fixed size in pixels, a
// little shading toward the rim so dense clouds keep their depth. Shared by points.wgsl
// (storage buffers) and points_attributes.wgsl (vertex attributes, WebGL2), so both draw the
// same discs. Needs frame.wgsl (the frame uniform).

struct DiscVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) corner: vec2<f32>,
    @location(1) color: vec3<f32>,
};

// Vertex `vertex` (0, 1 or 2) of the disc of `size_px` pixels around `position` (data space),
// coloured `color`; a hidden point goes behind the far plane.
fn disc_vertex(position: vec3<f32>, vertex: u32, size_px: f32, color: vec3<f32>, hidden: bool) -> DiscVertex {
    let corners = array<vec2<f32>, 3>(
        vec2<f32>(0.0, 2.0), vec2<f32>(-1.7320508, -1.0), vec2<f32>(1.7320508, -1.0),
    );
    let corner = corners[vertex];
    var clip = frame.clip_from_data * vec4<f32>(position, 1.0);
    // Offset in pixels, scaled back into clip space so the disc keeps its pixel size.
    let half_size = 0.5 * size_px * frame.viewport.zw * 2.0;
    clip = vec4<f32>(clip.xy + corner * half_size * clip.w, clip.zw);
    if (hidden) {
        clip = vec4<f32>(0.0, 0.0, -2.0, 1.0);
    }
    var out: DiscVertex;
    out.clip = clip;
    out.corner = corner;
    out.color = color;
    return out;
}

// The disc's colour at `corner`, shaded toward the rim; the caller discards where
// `disc_inside` is false.
fn disc_inside(corner: vec2<f32>) -> bool {
    return dot(corner, corner) <= 1.0;
}

fn disc_colour(corner: vec2<f32>, color: vec3<f32>) -> vec4<f32> {
    let shade = 1.0 - 0.25 * dot(corner, corner);
    return vec4<f32>(color * shade, 1.0);
}
