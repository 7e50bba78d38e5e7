//! Axes in physical units.
