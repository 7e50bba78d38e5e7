//! The CPU side of shaders/surface/draw.wgsl: the style uniform and the colour gradient.

/// Keep in sync with `SurfaceStyle` in shaders/surface/draw.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct SurfaceStyle {
    pub(crate) lit: u32,
    pub(crate) pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<SurfaceStyle>() == 16);

/// The warm-to-cool gradient of the mesh colour, as in shaders/surface/draw.wgsl (keep in sync):
/// gamma-encoded RGB for `hp` (0 percussive, warm; 1 harmonic, cool).
pub fn warm_cool(hp: f32) -> [f32; 3] {
    const WARM: [f32; 3] = [0.851, 0.325, 0.192];
    const NEUTRAL: [f32; 3] = [0.914, 0.882, 0.827];
    const COOL: [f32; 3] = [0.231, 0.443, 0.780];
    let t = hp.clamp(0.0, 1.0);
    let (a, b, f) = if t < 0.5 {
        (WARM, NEUTRAL, t * 2.0)
    } else {
        (NEUTRAL, COOL, t * 2.0 - 1.0)
    };
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * f)
}
