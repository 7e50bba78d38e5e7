// Surface view: draws an extracted isosurface (marching tetrahedra or dual contouring).
// Prepended: utils/frame.wgsl, utils/palette.wgsl. Reads MeshVertex records as a vertex buffer (position, hp,
// normal; see surface/extraction.wgsl) and SurfaceStyle; writes colour and depth.
// Colour: hp through the palette's surface map (Classic: warm percussive to cool harmonic,
// paper 3.4; src/render/colormap.rs), optionally Phong-lit by the frame's directional light
// from above. Keep SurfaceStyle in sync with src/render/surface/draw.rs.

struct SurfaceStyle {
    // 1: Phong lighting, 0: flat hp colour.
    lit: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(1) @binding(0) var<uniform> style: SurfaceStyle;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) hp: f32,
    @location(2) normal: vec3<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) position: vec3<f32>,
    @location(1) hp: f32,
    @location(2) normal: vec3<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_data * vec4<f32>(in.position, 1.0);
    out.position = in.position;
    out.hp = in.hp;
    out.normal = in.normal;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let albedo = surface_palette(in.hp);
    if (style.lit == 0u) {
        return vec4<f32>(albedo, 1.0);
    }
    // Light in linear space, then back to the gamma-encoded target.
    let linear = pow(albedo, vec3<f32>(2.2));
    var n = in.normal;
    if (dot(n, n) > 1e-12) {
        n = normalize(n);
    }
    let l = normalize(frame.light_direction.xyz);
    let v = normalize(frame.eye_position.xyz - in.position);
    let diffuse = max(dot(n, l), 0.0);
    let r = reflect(-l, n);
    let specular = pow(max(dot(r, v), 0.0), 32.0) * step(0.0, dot(n, l));
    let lit = linear * (0.22 + 0.78 * diffuse) + vec3<f32>(0.18 * specular);
    return vec4<f32>(pow(clamp(lit, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(1.0 / 2.2)), 1.0);
}
