//! The compare's scene being prepared on a thread (`ui/compare_scene.rs` starts it): where the
//! prepared clouds come, and whether it is the first scene of this A.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Duration;

use crate::data::cloud::PointCloud;
use crate::render::points::PointBuffers;
use crate::ui::labels::AxisLabels;

/// A and the version beside it on their union axes, with the labels of that box.
pub(in crate::ui) struct Prepared {
    /// The scene's own (`CompareScene` owns its clouds).
    pub(in crate::ui) clouds: (PointCloud, PointCloud),
    /// The same, the copy the window keeps (hover read-outs, grids built on a thread).
    pub(in crate::ui) shared: Arc<(PointCloud, PointCloud)>,
    /// A's and B's point buffers on the GPU, filled.
    pub(in crate::ui) buffers: [PointBuffers; 2],
    pub(in crate::ui) labels: AxisLabels,
    /// How long the thread took.
    pub(in crate::ui) took: Duration,
}

/// A scene being prepared on a thread.
pub(in crate::ui) struct SceneBuild {
    receiver: Receiver<Result<Prepared, String>>,
    /// The first scene of this A: the compare is fitted when it comes.
    pub(in crate::ui) first: bool,
}

impl SceneBuild {
    pub(in crate::ui) fn new(receiver: Receiver<Result<Prepared, String>>, first: bool) -> Self {
        Self { receiver, first }
    }

    /// The prepared scene once it came (or why it could not be), None while it is prepared.
    pub(in crate::ui) fn poll(&self) -> Option<Result<Prepared, String>> {
        match self.receiver.try_recv() {
            Ok(answer) => Some(answer),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err("the compare's scene stopped".into())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::channel;

    /// Nothing until the answer comes; a thread that ended without one is an error.
    #[test]
    fn the_answer_or_a_stopped_thread() {
        let (sender, receiver) = channel();
        let build = SceneBuild::new(receiver, true);
        assert!(build.poll().is_none());
        sender.send(Err("no union axes".into())).unwrap();
        assert_eq!(
            build.poll().unwrap().err().as_deref(),
            Some("no union axes")
        );
        drop(sender);
        assert!(build.poll().unwrap().is_err());
    }
}
