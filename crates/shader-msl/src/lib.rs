//! The app's shader modules as text, as src/render/shaders.rs composes them (the file itself,
//! without its wgpu glue), for the MSL translation test in tests/msl.rs.

#[path = "../../../src/render/shaders.rs"]
pub mod shaders;
