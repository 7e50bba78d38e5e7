//! What a voxel grid is built with, and why a build is refused: the resolution and smoothing
//! (by the data's mode unless chosen), their limits, and the voxelization's errors. The pass
//! (`voxelize.rs`) re-exports them.

use thiserror::Error;

use crate::data::cloud::DataMode;
use crate::render::gpu::readback::ReadbackError;

/// Default grid resolution (voxels per side) for a song (paper 3.1).
pub const SONG_RESOLUTION: u32 = 128;
/// Default grid resolution for a timeline (paper 3.1).
pub const TIMELINE_RESOLUTION: u32 = 224;
pub const MIN_RESOLUTION: u32 = 64;
pub const MAX_RESOLUTION: u32 = 384;
/// Most points per voxelization: the per-voxel count is a u32. A cloud this large would take
/// 86 GB at 20 bytes a point, so no cloud a machine holds reaches it.
pub const MAX_POINTS: usize = u32::MAX as usize;
/// Largest Gaussian sigma, in voxels.
pub const MAX_SMOOTHING_SIGMA: f32 = 10.0;
/// How the grid is built (by default each by the data's mode). Changing these rebuilds the grid;
/// nothing else does.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoxelSettings {
    /// Voxels per side; `None` picks by data mode (128 song, 224 timeline).
    pub resolution: Option<u32>,
    /// Gaussian smoothing of the loudness sums, sigma in voxels; 0 turns it off. `None` picks by
    /// data mode ([`default_smoothing`]: 1 song, 4 timeline).
    pub smoothing_sigma: Option<f32>,
}

impl VoxelSettings {
    pub fn resolution_for(&self, mode: DataMode) -> u32 {
        self.resolution.unwrap_or(default_resolution(mode))
    }

    /// The smoothing sigma (voxels) of a grid of `mode`'s data.
    pub fn smoothing_for(&self, mode: DataMode) -> f32 {
        self.smoothing_sigma.unwrap_or(default_smoothing(mode))
    }
}

pub use super::{SONG_SMOOTHING, TIMELINE_SMOOTHING, default_smoothing};

pub fn default_resolution(mode: DataMode) -> u32 {
    match mode {
        DataMode::Timeline => TIMELINE_RESOLUTION,
        DataMode::Song | DataMode::Generic => SONG_RESOLUTION,
    }
}

#[derive(Debug, Error)]
pub enum VoxelizeError {
    #[error(
        "grid resolution {0} is out of range: choose {MIN_RESOLUTION} to {MAX_RESOLUTION} voxels per side"
    )]
    Resolution(u32),
    #[error("smoothing sigma {0} is out of range: choose 0 (off) to {MAX_SMOOTHING_SIGMA} voxels")]
    Smoothing(f32),
    #[error(
        "a {resolution}^3 grid needs {needed_mib} MiB in one GPU buffer but this GPU allows \
         {limit_mib} MiB; choose a resolution of {largest} or less"
    )]
    TooLarge {
        resolution: u32,
        needed_mib: u64,
        limit_mib: u64,
        largest: u32,
    },
    #[error("the cloud has {0} points; at most 4294967295 can be voxelized at once")]
    TooManyPoints(usize),
    #[error("voxelization: {0}")]
    Readback(#[from] ReadbackError),
}
