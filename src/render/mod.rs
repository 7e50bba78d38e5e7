//! GPU passes. Nothing here knows of egui: the window and the headless renderer both drive
//! [`scene::Renderer`], which owns one instance of every pass.

pub mod composite;
pub mod context;
pub mod dual_contour;
pub mod frame;
pub mod grid;
pub mod headless;
pub mod lines;
pub mod marching_tets;
pub mod markers;
pub mod mesh;
pub mod palette;
pub mod points;
pub mod scene;
pub mod shaders;
pub mod target;
pub mod transfer;
pub mod volume;
pub mod voxelize;
