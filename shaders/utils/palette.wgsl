// Colour maps, read from the palette uniform (bind group 0, binding 1), which
// src/render/colormap.rs fills from the user's choice (PaletteUniforms there; keep in sync).
// Three maps of evenly spaced stops, interpolated linearly in the gamma-encoded space of the
// render target: 0 the points' hp map (also the volume's hp tint), 1 the surface's hp map, 2 the
// volume's density ramp (already reversed on the light background). The Classic hp map is the
// paper's five-stop palette (section 3.4), red percussive (hp = 0) through white to deep blue
// harmonic (hp = 1); the others are matplotlib's (colormap_data.rs).

const PALETTE_STOPS: u32 = 256u;

struct Palette {
    // x, y, z: stops in maps 0, 1, 2; w: 1 on the light background.
    counts: vec4<u32>,
    stops: array<vec4<f32>, 768>,
};

@group(0) @binding(1) var<uniform> palette: Palette;

// Map `which` at `t` in [0, 1]: the same arithmetic as Ramp::sample in src/render/colormap.rs.
fn palette_lookup(which: u32, t: f32) -> vec3<f32> {
    let n = max(palette.counts[which], 2u);
    let x = clamp(t, 0.0, 1.0) * f32(n - 1u);
    let i = min(u32(floor(x)), n - 2u);
    let base = which * PALETTE_STOPS + i;
    return mix(palette.stops[base].rgb, palette.stops[base + 1u].rgb, x - f32(i));
}

fn hp_palette(hp: f32) -> vec3<f32> {
    return palette_lookup(0u, hp);
}

fn surface_palette(hp: f32) -> vec3<f32> {
    return palette_lookup(1u, hp);
}

fn density_palette(t: f32) -> vec3<f32> {
    return palette_lookup(2u, t);
}

fn light_background() -> bool {
    return palette.counts.w != 0u;
}

// Line ink: the colour as given on the dark background; on the light one its lightness turned
// over (hue kept), so grey-blue box lines become slate ink.
fn line_ink(c: vec3<f32>) -> vec3<f32> {
    if (!light_background()) {
        return c;
    }
    let l = max(dot(c, vec3<f32>(0.299, 0.587, 0.114)), 1e-3);
    return clamp(c * ((1.0 - l) / l) * 0.8, vec3<f32>(0.0), vec3<f32>(1.0));
}
