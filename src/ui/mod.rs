//! The window: egui panels around the 3D view. [`bridge`] is the one place where egui meets the
//! render passes (an egui_wgpu paint callback: prepare renders offscreen, paint composites).

pub mod app;
pub mod audio;
pub mod bridge;
mod hover;
pub mod labels;
mod legends;
mod panels;
mod persistence;
pub mod screenshot;
mod slots;
mod state;
mod window_screenshot;

pub use app::{WindowOptions, run};
