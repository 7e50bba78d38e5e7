// Composite: copies the offscreen scene into the window's frame (egui's render pass).

@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var scene_sampler: sampler;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// One triangle that covers the viewport.
@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    var out: VertexOut;
    let uv = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    out.clip = vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return textureSample(scene, scene_sampler, in.uv);
}

// For sRGB outputs: the scene holds gamma-encoded colour, which the output would encode again.
@fragment
fn fs_decode_srgb(in: VertexOut) -> @location(0) vec4<f32> {
    let c = textureSample(scene, scene_sampler, in.uv);
    let low = c.rgb / 12.92;
    let high = pow((c.rgb + 0.055) / 1.055, vec3<f32>(2.4));
    return vec4<f32>(select(high, low, c.rgb <= vec3<f32>(0.04045)), c.a);
}
