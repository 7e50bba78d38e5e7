// Volume view: a full-screen triangle whose fragments march their pixel's ray through the voxel
// grid, front to back, mapping density through a transfer function (paper 3.3).
// Reads the grid's density and hp_mean buffers (layout of src/render/grid/mod.rs) with manual
// trilinear filtering, and the derived grids of shaders/volume_grids.wgsl: each brick's largest
// density, to step over bricks the transfer function leaves transparent (landing on the same
// samples the full march takes), and a texture of the density gradient and the density, sampled
// once per step with the sampler's filtering (the full march is kept for the tests). Writes
// premultiplied colour (blended over the cleared background) and the depth where the ray's
// opacity first passes one half, so box lines behind dense volume hide.
// Keep VolumeParams in sync with src/render/volume.rs and `transfer` with src/render/transfer.rs;
// colours come from shaders/utils/palette.wgsl.

// The variant this pipeline runs. src/render/volume.rs (VolumeVariant::source) compiles one
// pipeline per combination by rewriting these three lines, so that each compiled march holds only
// its own work: lavapipe runs both sides of every branch under a lane mask, even a branch no lane
// takes, so a uniform `if` would leave the other variants' loads in every step.
const FULL_MARCH: bool = false;
const SHADING: bool = true;
const HP_TINT: bool = false;

struct VolumeParams {
    // Grid size in voxels (w unused).
    dims: vec4<u32>,
    // Grid box in data space (w unused).
    box_min: vec4<f32>,
    box_max: vec4<f32>,
    // x: preset (0 Classic, 1 Ember, 2 Glacial), y, z unused (the variant's HP_TINT and
    // SHADING), w: most steps per ray.
    options: vec4<u32>,
    // x: density scale, y: opacity scale times the opacity per voxel at alpha 1, z: step in
    // voxels, w: emission gain.
    controls: vec4<f32>,
    // Bricks per axis of brick_max; w: brick size in voxels.
    bricks: vec4<u32>,
    // Unused (the variant's FULL_MARCH).
    modes: vec4<u32>,
    // x: bricks whose largest density is below this are transparent, y: the smallest scaled
    // density a sample must pass to count, z: the smallest opacity per step (w unused).
    skip: vec4<f32>,
};

@group(1) @binding(0) var<uniform> params: VolumeParams;
@group(1) @binding(1) var<storage, read> density: array<f32>;
@group(1) @binding(2) var<storage, read> hp_mean: array<f32>;
@group(1) @binding(3) var<storage, read> brick_max: array<f32>;
@group(1) @binding(4) var gradient_texture: texture_3d<f32>;
@group(1) @binding(5) var gradient_sampler: sampler;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    // One triangle covering the screen: (-1, -1), (3, -1), (-1, 3).
    let uv = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

fn voxel_index(ijk: vec3<u32>) -> u32 {
    return ijk.x + params.dims.x * (ijk.y + params.dims.y * ijk.z);
}

struct Corners {
    i0: vec3<u32>,
    i1: vec3<u32>,
    f: vec3<f32>,
};

// The eight voxels around voxel-space point `u` (voxel centres at ijk + 0.5), clamped to the
// grid, and the interpolation weights.
fn corners(u: vec3<f32>) -> Corners {
    let top = vec3<f32>(params.dims.xyz) - 1.0;
    let q = clamp(u - 0.5, vec3<f32>(0.0), top);
    let base = floor(q);
    var c: Corners;
    c.i0 = vec3<u32>(base);
    c.i1 = vec3<u32>(min(base + 1.0, top));
    c.f = q - base;
    return c;
}

fn trilinear_density(c: Corners) -> f32 {
    let a = mix(density[voxel_index(c.i0)], density[voxel_index(vec3<u32>(c.i1.x, c.i0.y, c.i0.z))], c.f.x);
    let b = mix(density[voxel_index(vec3<u32>(c.i0.x, c.i1.y, c.i0.z))], density[voxel_index(vec3<u32>(c.i1.x, c.i1.y, c.i0.z))], c.f.x);
    let d = mix(density[voxel_index(vec3<u32>(c.i0.x, c.i0.y, c.i1.z))], density[voxel_index(vec3<u32>(c.i1.x, c.i0.y, c.i1.z))], c.f.x);
    let e = mix(density[voxel_index(vec3<u32>(c.i0.x, c.i1.y, c.i1.z))], density[voxel_index(c.i1)], c.f.x);
    return mix(mix(a, b, c.f.y), mix(d, e, c.f.y), c.f.z);
}

// Mean hp around a sample, weighted by density as well as distance, so empty voxels (hp 0.5,
// "neither") do not wash the colour of the loud ones out toward white.
fn weighted_hp(c: Corners) -> f32 {
    var total = 0.0;
    var weight_sum = 0.0;
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let pick = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, corner >> 2u);
        let ijk = select(c.i0, c.i1, pick == vec3<u32>(1u));
        let f = select(1.0 - c.f, c.f, pick == vec3<u32>(1u));
        let index = voxel_index(ijk);
        let w = f.x * f.y * f.z * density[index];
        total += w * hp_mean[index];
        weight_sum += w;
    }
    return select(0.5, total / weight_sum, weight_sum > 1e-6);
}

fn sample_density(u: vec3<f32>) -> f32 {
    return trilinear_density(corners(u));
}

// Density (already scaled) -> colour and opacity per voxel: the preset shapes density to a
// ramp position and an opacity (keep in sync with TransferPreset::shape in
// src/render/transfer.rs); the colour is the palette's density ramp at that position (the
// preset's own ramp or a chosen map, src/render/colormap.rs).
fn transfer(preset: u32, density_value: f32) -> vec4<f32> {
    let s = clamp(density_value, 0.0, 1.0);
    var t = s;
    var alpha = s;
    if (preset == 1u) {
        t = sqrt(s);
        alpha = t;
    } else if (preset == 2u) {
        t = smoothstep(0.2, 1.0, s);
        alpha = min(1.6 * t * t, 1.0);
    }
    return vec4<f32>(density_palette(t), alpha);
}

fn hash(pixel: vec2<u32>, frame_index: u32) -> f32 {
    var h = pixel.x * 1973u + pixel.y * 9277u + frame_index * 26699u;
    h = (h ^ (h >> 16u)) * 0x7feb352du;
    h = (h ^ (h >> 15u)) * 0x846ca68bu;
    h = h ^ (h >> 16u);
    return f32(h >> 8u) / 16777216.0;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    // The pixel's ray in data space, from the near plane to the far plane.
    let ndc = vec2<f32>(
        in.position.x * frame.viewport.z * 2.0 - 1.0,
        1.0 - in.position.y * frame.viewport.w * 2.0,
    );
    let near4 = frame.data_from_clip * vec4<f32>(ndc, 0.0, 1.0);
    let far4 = frame.data_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let near = near4.xyz / near4.w;
    let far = far4.xyz / far4.w;

    // Into voxel space (one unit per voxel), where steps are measured.
    let dims = vec3<f32>(params.dims.xyz);
    let per_unit = dims / (params.box_max.xyz - params.box_min.xyz);
    let origin = (near - params.box_min.xyz) * per_unit;
    let span = (far - near) * per_unit;
    let ray_length = length(span);
    let dir = span / ray_length;

    // Slab intersection with the box [0, dims].
    let inv = 1.0 / dir;
    let t0 = (vec3<f32>(0.0) - origin) * inv;
    let t1 = (dims - origin) * inv;
    let t_enter = max(max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z)), 0.0);
    let t_exit = min(min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z)), ray_length);
    if (t_enter >= t_exit) {
        discard;
    }

    let preset = params.options.x;
    let density_scale = params.controls.x;
    let step = params.controls.z;
    let opacity = params.controls.y;
    let light = normalize(frame.light_direction.xyz);
    let gain = select(params.controls.w, 1.0, light_background());

    // Jittered start: hides the banding of fixed steps (changes every frame while moving).
    var t = t_enter + step * hash(vec2<u32>(in.position.xy), frame.flags.x);
    var color = vec3<f32>(0.0);
    var alpha = 0.0;
    // Where the opacity first passes one half (the depth written), negative until it does.
    var t_half = -1.0;
    let brick_size = f32(params.bricks.w);
    let last_brick = vec3<f32>(params.bricks.xyz) - 1.0;
    let min_value = params.skip.y;
    let min_step_opacity = params.skip.z;
    let unit_step = step == 1.0;
    var t_brick_end = -1.0;
    for (var i = 0u; i < params.options.w && t < t_exit; i += 1u) {
        let u = origin + dir * t;
        // The fast path's one filtered sample: the gradient (xyz) and the density (w).
        var texel = vec4<f32>(0.0);
        // Inside a brick already found to hold opacity, every sample is taken: the look-up is
        // once per brick the ray crosses, not once a step.
        if (!FULL_MARCH && t >= t_brick_end) {
            let brick = clamp(floor(u / brick_size), vec3<f32>(0.0), last_brick);
            let b = vec3<u32>(brick);
            let far_side = select(brick, brick + 1.0, dir > vec3<f32>(0.0)) * brick_size;
            let t_sides = select(vec3<f32>(3.0e38), (far_side - origin) * inv, dir != vec3<f32>(0.0));
            let t_leave = min(min(t_sides.x, t_sides.y), t_sides.z);
            if (brick_max[b.x + params.bricks.x * (b.y + params.bricks.y * b.z)] < params.skip.x) {
                // Every sample in this brick is transparent: step to the first sample past its
                // far side (whole steps, so the samples after it are the full march's).
                let steps = max(ceil((t_leave - t) / step), 1.0);
                let skipped = u32(min(steps, f32(params.options.w)));
                t += f32(skipped) * step;
                i += skipped - 1u;
                continue;
            }
            t_brick_end = t_leave;
        }
        var value: f32;
        if (!FULL_MARCH) {
            texel = textureSampleLevel(gradient_texture, gradient_sampler, u / dims, 0.0);
            value = texel.w * density_scale;
        } else {
            value = sample_density(u) * density_scale;
        }
        if (value > min_value) {
            let sample = transfer(preset, value);
            // Opacity per step from opacity per voxel, so the look does not depend on the step
            // (at rest the step is one voxel, and the power is the identity).
            let kept = 1.0 - clamp(sample.a * opacity, 0.0, 0.999);
            var a = 1.0 - kept;
            if (!unit_step) {
                a = 1.0 - pow(kept, step);
            }
            if (a > min_step_opacity) {
                var rgb = sample.rgb;
                if (HP_TINT) {
                    // The points' palette, brighter where denser.
                    let tinted = hp_palette(weighted_hp(corners(u))) * (0.45 + 0.65 * clamp(value, 0.0, 1.0));
                    rgb = mix(rgb, tinted, 0.85);
                }
                if (SHADING && a > 0.01) {
                    // Central differences in voxel space; the normal in data space. The texture
                    // holds them at the voxel centres, and filtering them is differencing two
                    // filtered samples (the full march's six samples).
                    var gv: vec3<f32>;
                    if (!FULL_MARCH) {
                        gv = texel.xyz;
                    } else {
                        gv = vec3<f32>(
                            sample_density(u + vec3<f32>(1.0, 0.0, 0.0)) - sample_density(u - vec3<f32>(1.0, 0.0, 0.0)),
                            sample_density(u + vec3<f32>(0.0, 1.0, 0.0)) - sample_density(u - vec3<f32>(0.0, 1.0, 0.0)),
                            sample_density(u + vec3<f32>(0.0, 0.0, 1.0)) - sample_density(u - vec3<f32>(0.0, 0.0, 1.0)),
                        );
                    }
                    let g = gv * per_unit;
                    let magnitude = length(g);
                    if (magnitude > 1e-6) {
                        // The normal points down the gradient (out of the dense region); flat
                        // regions (small gradients) stay unshaded.
                        let n = -g / magnitude;
                        let lit = 0.5 + 0.7 * max(dot(n, light), 0.0);
                        let edge = clamp(length(gv) * 4.0, 0.0, 1.0);
                        rgb = rgb * mix(1.0, lit, edge);
                    }
                }
                // Emission outweighs absorption a little, so the field glows on the dark
                // background; on the light one light added over white would wash out, so the
                // colour is laid on as paint (gain 1).
                color += (1.0 - alpha) * a * rgb * gain;
                alpha += (1.0 - alpha) * a;
                if (alpha > 0.5 && t_half < 0.0) {
                    t_half = t;
                }
                if (alpha > 0.99) {
                    break;
                }
            }
        }
        t += step;
    }
    out.color = vec4<f32>(color, alpha);
    out.depth = 1.0;
    if (t_half >= 0.0) {
        let data = params.box_min.xyz + (origin + dir * t_half) / per_unit;
        let clip = frame.clip_from_data * vec4<f32>(data, 1.0);
        out.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    }
    return out;
}
