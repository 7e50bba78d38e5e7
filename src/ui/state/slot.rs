//! Which of the window's two data slots (Song, Timeline).

use crate::data::cloud::DataMode;

/// Which of the two data slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum Slot {
    Song,
    Timeline,
}

impl Slot {
    pub(in crate::ui) fn for_mode(mode: DataMode) -> Self {
        match mode {
            DataMode::Timeline => Slot::Timeline,
            DataMode::Song | DataMode::Generic => Slot::Song,
        }
    }
    /// The other slot.
    pub(in crate::ui) fn other(self) -> Self {
        match self {
            Slot::Song => Slot::Timeline,
            Slot::Timeline => Slot::Song,
        }
    }
    pub(in crate::ui) fn name(self) -> &'static str {
        match self {
            Slot::Song => "Song",
            Slot::Timeline => "Timeline",
        }
    }
}
