//! GPU plumbing shared by every pass: the device and its limits ([`context`]), render targets
//! ([`target`]), waiting read-back ([`readback`]), bind-group layout entries ([`layouts`]), the
//! draw passes' shared pipeline states ([`pipeline`]), GPU timestamps ([`timing`]) and the
//! per-frame uniforms ([`frame`]).

pub mod context;
pub mod frame;
pub mod layouts;
pub mod pipeline;
pub mod readback;
pub mod target;
pub mod timing;
