// The harmonic-percussive palette of paper section 3.4, five stops from percussive (hp = 0,
// red) through orange and white to light and deep blue (hp = 1, harmonic). Colours are in the
// gamma-encoded space of the render target. Keep in sync with HP_PALETTE in src/render/palette.rs.
fn hp_palette(hp: f32) -> vec3<f32> {
    let stops = array<vec3<f32>, 5>(
        vec3<f32>(0.843, 0.188, 0.153),
        vec3<f32>(0.992, 0.553, 0.235),
        vec3<f32>(0.969, 0.969, 0.969),
        vec3<f32>(0.569, 0.749, 0.859),
        vec3<f32>(0.129, 0.400, 0.675),
    );
    let t = clamp(hp, 0.0, 1.0) * 4.0;
    let i = min(u32(floor(t)), 3u);
    return mix(stops[i], stops[i + 1u], t - f32(i));
}
