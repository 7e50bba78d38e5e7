//! GPU plumbing shared by every pass: the device, render targets and read-back, the per-frame
//! uniforms.

pub mod context;
pub mod frame;
pub mod layouts;
pub mod readback;
pub mod target;
