// Lines: the box around the data and its tick marks, in data space (the playhead and other
// markers are markers.wgsl). Prepended: utils/frame.wgsl, utils/palette.wgsl (line_ink turns
// the lines to dark ink on the light background).

// Keep in sync with `LineVertex` in src/render/lines.rs (28 bytes: vec3 then vec4).
struct LineVertex {
    @location(0) position: vec3<f32>,
    @location(1) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_main(in: LineVertex) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_data * vec4<f32>(in.position, 1.0);
    out.color = in.color;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(line_ink(in.color.rgb), in.color.a);
}
