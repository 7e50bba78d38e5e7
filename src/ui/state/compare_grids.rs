//! The compare's grids built on a thread (`ui/compare_window.rs` starts the build): what a
//! frame does about them, the build waited for and its answer. Part of [`CompareState`], kept
//! apart from `compare_window.rs`.

use std::sync::mpsc::{Receiver, TryRecvError};

use crate::render::compare::BuiltGrids;
use crate::render::grid::voxelize::VoxelSettings;

use super::compare_window::CompareState;

/// The compare's grids built on a thread (`render::compare::build_grids`): the voxel settings
/// they are built with, where the answer comes, and the frames the window drew meanwhile.
pub(in crate::ui) struct GridBuild {
    pub(in crate::ui) voxels: VoxelSettings,
    pub(in crate::ui) receiver: Receiver<Result<BuiltGrids, String>>,
    pub(in crate::ui) frames: u32,
    pub(in crate::ui) started: std::time::Instant,
}

/// What a frame does about the compare's grids ([`CompareState::grid_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum GridStep {
    /// Built for the settings shown: draw them.
    Ready,
    /// None for these settings and none coming: start a build.
    Start,
    /// A build for these settings runs: come back.
    Wait,
    /// None for these settings, and the versions' alignment is still on its way: come back
    /// once it came (it may move the version beside A, and the scene with it).
    Align,
    /// The build for these settings failed (its error is told): nothing to do.
    Failed,
}

impl CompareState {
    /// What this frame does about the grids, `built` saying whether the scene has them for
    /// `voxels`: a build for other settings is dropped (its answer is not waited for).
    pub(in crate::ui) fn grid_step(&mut self, voxels: &VoxelSettings, built: bool) -> GridStep {
        if built {
            return GridStep::Ready;
        }
        if let Some(build) = &mut self.grid_build {
            if build.voxels == *voxels {
                build.frames += 1;
                return GridStep::Wait;
            }
            self.grid_build = None;
        }
        if self.grids_failed == Some(*voxels) {
            return GridStep::Failed;
        }
        // The comparison on its way (or still to start: a version is loading) moves the
        // version beside A when it comes, and the scene is built again then: grids built now
        // would be built twice (seconds each on a real song). The points stand in until then.
        if self.alignment.aligning() || self.loading() {
            return GridStep::Align;
        }
        GridStep::Start
    }

    /// Waits for a build started on a thread with `voxels`.
    pub(in crate::ui) fn building(
        &mut self,
        voxels: VoxelSettings,
        receiver: Receiver<Result<BuiltGrids, String>>,
    ) {
        self.grids_failed = None;
        self.grid_build = Some(GridBuild {
            voxels,
            receiver,
            frames: 0,
            started: std::time::Instant::now(),
        });
    }

    /// Whether grids are being built on a thread.
    pub(in crate::ui) fn grids_building(&self) -> bool {
        self.grid_build.is_some()
    }

    /// The build's answer once it came, with the frames drawn while it ran and how long it
    /// took; a failure (or a
    /// thread that ended without answering) is kept as the compare's error and not tried again
    /// for the same settings.
    pub(in crate::ui) fn poll_grid_build(
        &mut self,
    ) -> Option<(BuiltGrids, u32, std::time::Duration)> {
        let build = self.grid_build.as_ref()?;
        let answer = match build.receiver.try_recv() {
            Ok(answer) => answer,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => Err("the compare grids' build stopped".into()),
        };
        let build = self.grid_build.take()?;
        match answer {
            Ok(built) => Some((built, build.frames, build.started.elapsed())),
            Err(message) => {
                self.grids_failed = Some(build.voxels);
                self.error = Some(message);
                None
            }
        }
    }
}
