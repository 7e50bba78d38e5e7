//! One cloud's extracted surface ([`ExtractedSurface`], owned by its `SceneData`): the mesh
//! buffers, what they were extracted from (the cache key) and where the read-back of their size
//! stands. The per-device [`SurfacePass`](crate::render::surface::pass::SurfacePass) fills and
//! draws it, so each cloud (Song, Timeline) keeps its own surface.

use std::sync::atomic::AtomicU8;
use std::sync::{Arc, Mutex, MutexGuard};

use glam::UVec3;

use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::MeshBuffers;
use crate::render::surface::{SurfaceCounts, SurfaceMethod, SurfaceSettings};

/// Identifies the extracted surface: a change re-extracts it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CacheKey {
    pub(crate) method: SurfaceMethod,
    pub(crate) iso_bits: u32,
    pub(crate) density: wgpu::Buffer,
    pub(crate) hp_mean: wgpu::Buffer,
    pub(crate) dims: UVec3,
    pub(crate) box_bits: [u32; 6],
}

impl CacheKey {
    pub(crate) fn new(grid: &VoxelGrid, settings: &SurfaceSettings) -> Self {
        let (a, b) = (grid.box_min, grid.box_max);
        Self {
            method: settings.method,
            iso_bits: settings.iso_value.to_bits(),
            density: grid.density.clone(),
            hp_mean: grid.hp_mean.clone(),
            dims: grid.dims,
            box_bits: [a.x, a.y, a.z, b.x, b.y, b.z].map(f32::to_bits),
        }
    }
}

pub(crate) const MAP_PENDING: u8 = 0;
pub(crate) const MAP_DONE: u8 = 1;
pub(crate) const MAP_FAILED: u8 = 2;

/// Where the counters' read-back stands.
#[derive(Default)]
pub(crate) enum Readback {
    #[default]
    Idle,
    /// A copy into the staging buffer was recorded; it is mapped on the next frame, after the
    /// frame that holds the copy has been submitted.
    Copied { generation: u64 },
    Mapping {
        generation: u64,
        flag: Arc<AtomicU8>,
    },
}

#[derive(Default)]
pub(crate) struct SurfaceState {
    pub(crate) buffers: Option<MeshBuffers>,
    pub(crate) key: Option<CacheKey>,
    /// Counts extractions; a read-back only speaks for the extraction it copied.
    pub(crate) generation: u64,
    pub(crate) counts_unchecked: bool,
    pub(crate) readback: Readback,
    /// Where the counters are copied to be mapped; made on the first read-back.
    pub(crate) staging: Option<wgpu::Buffer>,
    pub(crate) counts: Option<SurfaceCounts>,
    pub(crate) error: Option<String>,
}

/// One cloud's surface: filled by [`SurfacePass::prepare`] or
/// [`SurfacePass::extract_blocking`], drawn by [`SurfacePass::draw`], read by
/// [`SurfacePass::read_mesh`]. Behind a lock because the frame that draws it holds the cloud's
/// data by shared reference.
///
/// [`SurfacePass::prepare`]: crate::render::surface::pass::SurfacePass::prepare
/// [`SurfacePass::extract_blocking`]: crate::render::surface::pass::SurfacePass::extract_blocking
/// [`SurfacePass::draw`]: crate::render::surface::pass::SurfacePass::draw
/// [`SurfacePass::read_mesh`]: crate::render::surface::pass::SurfacePass::read_mesh
#[derive(Default)]
pub struct ExtractedSurface {
    state: Mutex<SurfaceState>,
}

impl ExtractedSurface {
    pub fn new() -> Self {
        Self::default()
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, SurfaceState> {
        // A panic elsewhere while holding the lock leaves plain data; carry on with it.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The counts of the last extraction whose read-back arrived (None before the first).
    pub fn counts(&self) -> Option<SurfaceCounts> {
        self.lock().counts
    }

    /// Why the surface is incomplete, when it is (it needs more room than the GPU has).
    pub fn error(&self) -> Option<String> {
        self.lock().error.clone()
    }

    /// True while a read-back or a re-extraction is pending: the window should draw again.
    pub fn needs_another_frame(&self) -> bool {
        let state = self.lock();
        state.key.is_none() || state.counts_unchecked || !matches!(state.readback, Readback::Idle)
    }
}
