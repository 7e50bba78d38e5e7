//! The data floor: point clouds as they come from files (or from code), before any GPU.

pub mod axes;
pub mod cloud;
pub mod compare;
pub mod field;
pub mod freq_axis;
pub mod normalize;
#[cfg(not(target_arch = "wasm32"))]
pub mod npy;
pub mod page_cloud;
pub mod synthetic;
