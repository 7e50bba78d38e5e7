//! The window: egui panels around the 3D view. [`bridge`] is the one place where egui meets the
//! render passes (an egui_wgpu paint callback: prepare renders offscreen, paint composites).

pub mod app;
pub mod audio;
pub mod bridge;

pub use app::{WindowOptions, run};
