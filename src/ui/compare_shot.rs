//! A/B compare pictures without a window: `picture::compare` (kept under this name for the
//! window's Save PNG and the tests).

pub use crate::picture::compare::*;
