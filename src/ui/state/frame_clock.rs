//! The window's frames as its stats line shows them ([`FrameClock`], the `clock` field of
//! `LoudscapeApp`): the frame number the view is drawn with, the mean time of frames drawn one
//! after another, and the scene renders counted by the bridge.

#[derive(Default)]
pub(in crate::ui) struct FrameClock {
    index: u32,
    /// Mean time of frames that followed the last at once (ms); 0 before one.
    ms: f32,
    /// Scene renders so far.
    pub(in crate::ui) renders: u64,
}

impl FrameClock {
    /// A frame begins after one that took `frame_ms` (None: it did not follow the last at once,
    /// so time spent waiting for input is not shown as frame time).
    pub(in crate::ui) fn observe(&mut self, frame_ms: Option<f32>) {
        if let Some(dt) = frame_ms {
            self.ms = if self.ms == 0.0 {
                dt
            } else {
                self.ms * 0.8 + dt * 0.2
            };
        }
    }

    /// The number of the view's frame now drawn (the next call gets the next one).
    pub(in crate::ui) fn next_index(&mut self) -> u32 {
        let index = self.index;
        self.index = self.index.wrapping_add(1);
        index
    }

    pub(in crate::ui) fn ms(&self) -> f32 {
        self.ms
    }

    /// The bridge has rendered the scene `renders` times so far.
    pub(in crate::ui) fn rendered(&mut self, renders: u64) {
        self.renders = renders;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_frames_that_followed_at_once_move_the_mean() {
        let mut clock = FrameClock::default();
        clock.observe(None);
        assert_eq!(clock.ms(), 0.0);
        clock.observe(Some(20.0));
        assert_eq!(clock.ms(), 20.0, "the first frame is the mean");
        clock.observe(Some(40.0));
        assert!((clock.ms() - 24.0).abs() < 1e-4, "{}", clock.ms());
        clock.observe(None);
        assert!(
            (clock.ms() - 24.0).abs() < 1e-4,
            "a wait for input is not a frame"
        );
        assert_eq!((clock.next_index(), clock.next_index()), (0, 1));
    }
}
