//! GPU passes. Nothing here knows of egui: the window and the headless renderer both drive
//! [`scene::Renderer`], which owns one instance of every pass, and one [`scene::SceneData`] per
//! loaded cloud. One pass a file, each beside its shader in shaders/ (same folders) and its CPU
//! mirror: [`gpu`] (device, targets, read-back, layouts, frame uniforms), [`grid`] (voxelize),
//! [`surface`] (marching tetrahedra, dual contouring, the draw), [`points`], [`lines`],
//! [`markers`], [`volume`] (with [`transfer`] and [`volume_grids`]), [`composite`]; [`shaders`] composes the WGSL;
//! [`colormap`] holds the colour maps and background every pass reads (the palette uniform).

pub mod colormap;
pub mod colormap_data;
pub mod compare;
pub mod composite;
pub mod gpu;
pub mod grid;
pub mod headless;
pub mod lines;
pub mod markers;
pub mod points;
pub mod points_attributes;
pub mod scene;
pub mod shaders;
pub mod still;
pub mod surface;
pub mod transfer;
pub mod volume;
pub mod volume_grids;
