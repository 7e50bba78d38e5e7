//! The CPU side of shaders/surface/draw.wgsl: the style uniform and the Classic colour gradient.

/// Keep in sync with `SurfaceStyle` in shaders/surface/draw.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct SurfaceStyle {
    pub(crate) lit: u32,
    pub(crate) pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<SurfaceStyle>() == 16);

/// The surface's Classic colours: warm (hp = 0, percussive), a light neutral (0.5), cool (hp = 1,
/// harmonic), gamma-encoded, interpolated linearly (src/render/colormap.rs uploads them to
/// shaders/utils/palette.wgsl, which the surface draw reads through `surface_palette`).
pub const WARM_COOL: [[f32; 3]; 3] = [
    [0.851, 0.325, 0.192],
    [0.914, 0.882, 0.827],
    [0.231, 0.443, 0.780],
];

/// The Classic warm-to-cool gradient of the mesh colour: gamma-encoded RGB for `hp`.
pub fn warm_cool(hp: f32) -> [f32; 3] {
    let t = hp.clamp(0.0, 1.0);
    let (a, b, f) = if t < 0.5 {
        (WARM_COOL[0], WARM_COOL[1], t * 2.0)
    } else {
        (WARM_COOL[1], WARM_COOL[2], t * 2.0 - 1.0)
    };
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * f)
}
