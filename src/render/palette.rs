//! Colour maps shared by the passes and the legends.

/// The five-stop harmonic-percussive palette (paper 3.4): red, orange, white, light blue,
/// deep blue, from percussive (hp = 0) to harmonic (hp = 1), gamma-encoded RGB.
/// Keep in sync with `hp_palette` in shaders/utils/palette.wgsl.
pub const HP_PALETTE: [[f32; 3]; 5] = [
    [0.843, 0.188, 0.153],
    [0.992, 0.553, 0.235],
    [0.969, 0.969, 0.969],
    [0.569, 0.749, 0.859],
    [0.129, 0.400, 0.675],
];

/// The palette at `hp` in [0, 1], the same interpolation as the shader.
pub fn hp_color(hp: f32) -> [f32; 3] {
    let t = hp.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f32;
    let (a, b) = (HP_PALETTE[i], HP_PALETTE[i + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// Gamma-encoded 8-bit RGB for the palette at `hp`.
pub fn hp_color_u8(hp: f32) -> [u8; 3] {
    hp_color(hp).map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8)
}
