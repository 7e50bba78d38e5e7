//! GPU passes. Nothing here knows of egui: the window and the headless renderer both drive
//! [`scene::Renderer`], which owns one instance of every pass.

pub mod composite;
pub mod gpu;
pub mod grid;
pub mod headless;
pub mod lines;
pub mod markers;
pub mod palette;
pub mod points;
pub mod scene;
pub mod shaders;
pub mod surface;
pub mod transfer;
pub mod volume;
