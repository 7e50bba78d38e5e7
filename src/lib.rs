//! loudscape: see how music is loud.
//!
//! The library half of the app: loading point clouds ([`data`]), the point of view and picking
//! ([`view`]), the GPU passes ([`render`]), which know nothing of the window, audio playback
//! ([`playback`]) and the egui window ([`ui`]). The binary (`src/main.rs`) adds the command line.

pub mod data;
pub mod playback;
pub mod render;
pub mod ui;
pub mod view;
