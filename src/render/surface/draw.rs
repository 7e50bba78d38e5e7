//! The CPU side of shaders/surface/draw.wgsl: the style uniform. The surface's colours are the
//! palette uniform's (src/render/colormap.rs, read through `surface_palette`).

/// Keep in sync with `SurfaceStyle` in shaders/surface/draw.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct SurfaceStyle {
    pub(crate) lit: u32,
    pub(crate) pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<SurfaceStyle>() == 16);
