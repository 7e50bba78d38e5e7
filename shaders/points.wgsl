// Points view: every point of the cloud as a screen-aligned disc, coloured by hp.
// Reads the cloud as a flat array of f32, five per point (x, y, z, scalar, hp), the PLY record.
// Keep PointParams in sync with src/render/points.rs.

struct PointParams {
    // Draw points first, first + stride, first + 2 stride, ... (stride > 1 while moving).
    stride: u32,
    count: u32,
    // Disc diameter in pixels.
    size_px: f32,
    // Points with scalar below this are not drawn.
    min_scalar: f32,
    // The frequency axis of the view (shaders/utils/freq_axis.wgsl).
    freq: FreqParams,
};

@group(1) @binding(0) var<storage, read> cloud: array<f32>;
@group(1) @binding(1) var<uniform> params: PointParams;
// Per STFT bin: the view's z range its points are spread over (shaders/utils/freq_axis.wgsl).
@group(1) @binding(2) var<storage, read> freq_table: array<vec2<f32>>;

@vertex
fn vs_main(@builtin(vertex_index) vertex_index: u32) -> DiscVertex {
    // Three vertices per point, not instanced: software rasterizers shade vertices in batches
    // of 8 or 16 within a draw, but a three-vertex instance fills one batch with three.
    let instance = vertex_index / 3u;
    let vertex = vertex_index % 3u;
    let index = instance * params.stride;
    let base = index * 5u;
    let position = vec3<f32>(cloud[base], cloud[base + 1u], freq_view_z(cloud[base + 2u], index));
    let scalar = cloud[base + 3u];
    let hp = cloud[base + 4u];
    let hidden = scalar < params.min_scalar || index >= params.count || position.z > 2.0;
    return disc_vertex(position, vertex, params.size_px, hp_palette(hp), hidden);
}

@fragment
fn fs_main(in: DiscVertex) -> @location(0) vec4<f32> {
    if (!disc_inside(in.corner)) {
        discard;
    }
    return disc_colour(in.corner, in.color);
}
