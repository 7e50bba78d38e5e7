//! WGSL sources. WGSL has no `#include`, so a pass's module is its own file with the shared
//! helpers of shaders/utils/ prepended; [`all`] lists every module so one test can translate each
//! to MSL (Metal) with naga.

pub const FRAME: &str = include_str!("../../shaders/utils/frame.wgsl");
pub const PALETTE: &str = include_str!("../../shaders/utils/palette.wgsl");
pub const FREQ_AXIS: &str = include_str!("../../shaders/utils/freq_axis.wgsl");
pub const POINT_DISC: &str = include_str!("../../shaders/utils/point_disc.wgsl");

pub const POINTS: &str = include_str!("../../shaders/points.wgsl");
pub const POINTS_ATTRIBUTES: &str = include_str!("../../shaders/points_attributes.wgsl");
pub const LINES: &str = include_str!("../../shaders/lines.wgsl");
pub const COMPOSITE: &str = include_str!("../../shaders/composite.wgsl");
pub const MARKERS: &str = include_str!("../../shaders/markers.wgsl");
pub const SURFACE_EXTRACTION: &str = include_str!("../../shaders/surface/extraction.wgsl");
pub const MARCHING_TETS: &str = include_str!("../../shaders/surface/marching_tets.wgsl");
pub const DUAL_CONTOUR: &str = include_str!("../../shaders/surface/dual_contour.wgsl");
pub const SURFACE_DRAW: &str = include_str!("../../shaders/surface/draw.wgsl");
pub const VOXELIZE: &str = include_str!("../../shaders/grid/voxelize.wgsl");
pub const VOLUME: &str = include_str!("../../shaders/volume.wgsl");
pub const VOLUME_GRIDS: &str = include_str!("../../shaders/volume_grids.wgsl");
pub const DIFFERENCE: &str = include_str!("../../shaders/grid/difference.wgsl");
pub const DOWNSAMPLE: &str = include_str!("../../shaders/grid/downsample.wgsl");

/// Concatenates helper sources and a pass's own source into one module.
pub fn compose(parts: &[&str]) -> String {
    parts.join("\n")
}

pub fn points() -> String {
    compose(&[FRAME, PALETTE, FREQ_AXIS, POINT_DISC, POINTS])
}

/// The points without storage buffers (WebGL2): `render::points_attributes`.
pub fn points_attributes() -> String {
    compose(&[FRAME, PALETTE, POINT_DISC, POINTS_ATTRIBUTES])
}

pub fn lines() -> String {
    compose(&[FRAME, PALETTE, LINES])
}

pub fn markers() -> String {
    compose(&[FRAME, MARKERS])
}

pub fn voxelize() -> String {
    compose(&[FRAME, FREQ_AXIS, VOXELIZE])
}

pub fn difference() -> String {
    DIFFERENCE.to_string()
}

pub fn downsample() -> String {
    DOWNSAMPLE.to_string()
}

pub fn volume() -> String {
    compose(&[FRAME, PALETTE, VOLUME])
}

pub fn volume_grids() -> String {
    VOLUME_GRIDS.to_string()
}

pub fn composite() -> String {
    COMPOSITE.to_string()
}

pub fn marching_tets() -> String {
    compose(&[SURFACE_EXTRACTION, MARCHING_TETS])
}

pub fn dual_contour() -> String {
    compose(&[SURFACE_EXTRACTION, DUAL_CONTOUR])
}

pub fn surface_draw() -> String {
    compose(&[FRAME, PALETTE, SURFACE_DRAW])
}

/// Every shader module the app builds, by name, as handed to the GPU.
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("points", points()),
        ("points_attributes", points_attributes()),
        ("lines", lines()),
        ("composite", composite()),
        ("markers", markers()),
        ("marching_tets", marching_tets()),
        ("dual_contour", dual_contour()),
        ("surface_draw", surface_draw()),
        ("voxelize", voxelize()),
        ("volume", volume()),
        ("volume_grids", volume_grids()),
        ("difference", difference()),
        ("downsample", downsample()),
    ]
}

/// Creates a shader module from composed source, labelled with its name. (Left out where
/// only the text is compiled: the MSL translation test, crates/shader-msl.)
#[cfg(not(shader_text_only))]
pub fn module(device: &wgpu::Device, name: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
