//! The scripted isovalue sweep's state (the `iso_sweep` field of `LoudscapeApp`): the values
//! asked for in `LOUDSCAPE_ISO_SWEEP`, how far it has gone and what it has measured so far
//! (frames, frames while an extraction ran, the longest frame, the extractions installed before
//! it began). Read from the environment here; each frame's step and the line it prints are
//! `ui/iso_sweep.rs`.

use std::time::Instant;

/// The environment variable that asks for a sweep (screenshot runs only).
pub const ISO_SWEEP_VAR: &str = "LOUDSCAPE_ISO_SWEEP";

/// A sweep on its way: the isovalues to set and what has been measured.
pub(in crate::ui) struct IsoSweep {
    pub(in crate::ui) values: Vec<f32>,
    /// Values set so far (None: waiting for the first surface).
    pub(in crate::ui) next: Option<usize>,
    pub(in crate::ui) last_frame: Option<Instant>,
    pub(in crate::ui) longest_ms: f64,
    pub(in crate::ui) frames: u32,
    pub(in crate::ui) busy_frames: u32,
    pub(in crate::ui) installed_before: u64,
    pub(in crate::ui) coarse_before: u64,
    pub(in crate::ui) done: bool,
}

impl IsoSweep {
    /// The sweep asked for in the environment, if any (a list of isovalues).
    pub(in crate::ui) fn from_env() -> Option<Self> {
        let text = std::env::var(ISO_SWEEP_VAR).ok()?;
        let values: Vec<f32> = text
            .split(',')
            .filter_map(|v| v.trim().parse().ok())
            .collect();
        (!values.is_empty()).then_some(Self {
            values,
            next: None,
            last_frame: None,
            longest_ms: 0.0,
            frames: 0,
            busy_frames: 0,
            installed_before: 0,
            coarse_before: 0,
            done: false,
        })
    }
}

impl IsoSweep {
    /// Whether it is setting values (as a dragged slider does), not waiting to start or done.
    pub(in crate::ui) fn sweeping(&self) -> bool {
        self.next.is_some() && !self.done
    }
}
