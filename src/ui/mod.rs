//! The window and everything egui (nothing else in the crate knows egui): [`app`] opens the
//! window and draws a frame over the state in `state/` (the floor under the behaviour files),
//! whose behaviour is split by concern (`slots.rs`, `panels.rs`, `legends.rs`, `hover.rs`,
//! `persistence.rs`, `window_screenshot.rs`, `open.rs`, `compare_window.rs`, ...). egui meets
//! the render passes in two places: [`bridge`] (the window's egui_wgpu paint callbacks, the 3D
//! view's and the compare's: prepare renders offscreen, paint composites) and [`labels`] (axis
//! labels, also drawn headless into a render target); [`screenshot`] renders a view offscreen
//! and saves PNGs, [`audio`] is the transport bar.

mod alsa_quiet;
pub mod annotation;
pub mod app;
pub mod audio;
pub mod bridge;
mod colour_controls;
pub mod compare;
mod compare_align;
mod compare_panel;
mod compare_readouts;
pub mod compare_refine;
mod compare_save;
mod compare_scene;
pub mod compare_shot;
mod compare_view;
mod compare_window;
mod extract_settings;
pub mod frame_cache;
mod freq_axis;
mod hover;
mod iso_sweep;
pub mod labels;
pub mod legends;
mod messages;
pub mod normalize;
mod open;
mod panels;
mod persistence;
pub mod progressive;
mod recent;
mod report_link;
mod save_slices;
pub mod screenshot;
mod shortcuts;
mod slots;
mod state;
pub mod strip;
mod style;
mod timeline_build;
mod video_export;
mod view_3d;
mod window_gone;
mod window_screenshot;
#[cfg(test)]
mod window_state_tests;

pub use app::{WindowOptions, run};
