//! loudscape: see how music is loud.
//!
//! The library half of the app: loading point clouds ([`cloud`]), axis labelling ([`axes`]),
//! the camera ([`camera`]) and the GPU passes ([`render`]), which know nothing of the window.
//! The binary (`src/main.rs`) adds the command line and the egui window ([`ui`]).

pub mod axes;
pub mod camera;
pub mod cloud;
pub mod overlay;
pub mod pick;
pub mod playback;
pub mod render;
pub mod screenshot;
mod synthetic;
pub mod ui;
