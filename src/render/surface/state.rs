//! One cloud's extracted surface ([`ExtractedSurface`], owned by its `SceneData`): the mesh
//! buffers, what they were extracted from (the cache key), the surface asked of the background
//! extraction and the mailbox its result arrives in; beside them the coarse mesh of the level of
//! detail ([`super::lod`]) and, in the mailbox, the coarse grid it is extracted from. The per-device
//! [`SurfacePass`](crate::render::surface::pass::SurfacePass) fills and draws it, so each cloud
//! (Song, Timeline) keeps its own surface.

use std::sync::{Arc, Mutex, MutexGuard};

use glam::UVec3;

use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::MeshBuffers;
use crate::render::surface::lod::{Level, SurfaceDetail, choose_mesh};
use crate::render::surface::{SurfaceCounts, SurfaceMethod, SurfaceSettings};

/// Where a cloud's surface stands, read once a frame by the window
/// ([`ExtractedSurface::status`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExtractionStatus {
    /// The counts of the last extraction whose read-back arrived (None before the first).
    pub counts: Option<SurfaceCounts>,
    /// Why the surface is incomplete, when it is (it needs more room than the GPU has).
    pub error: Option<String>,
    /// An extraction runs in the background or its result waits to be installed: the window
    /// comes back for it (and shows that it is busy).
    pub extracting: bool,
}

impl ExtractionStatus {
    /// Triangles in the last complete extraction (0 before the first).
    pub fn triangles(&self) -> u32 {
        self.counts.map_or(0, |c| c.triangles())
    }
}

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

    /// Whether both keys were extracted from the same grid (whatever the method and isovalue).
    pub(crate) fn same_grid(&self, other: &CacheKey) -> bool {
        self.density == other.density
            && self.hp_mean == other.hp_mean
            && self.dims == other.dims
            && self.box_bits == other.box_bits
    }
}

/// The coarse mesh of a surface (level of detail): its buffers and the full surface's key it
/// stands for (the full grid's, method and isovalue).
pub(crate) struct CoarseMesh {
    pub(crate) buffers: MeshBuffers,
    pub(crate) key: CacheKey,
    pub(crate) counts: Option<SurfaceCounts>,
}

#[derive(Default)]
pub(crate) struct SurfaceState {
    /// The mesh that is drawn.
    pub(crate) buffers: Option<MeshBuffers>,
    /// What `buffers` hold.
    pub(crate) key: Option<CacheKey>,
    pub(crate) counts: Option<SurfaceCounts>,
    pub(crate) error: Option<String>,
    /// The mesh drawn before `buffers`, reused by the next background extraction.
    pub(crate) spare: Option<MeshBuffers>,
    /// The surface last asked of the background extraction, until it is installed.
    pub(crate) requested: Option<CacheKey>,
    /// Background extractions installed so far.
    pub(crate) installed: u64,
    /// The coarse mesh (level of detail), extracted before the full one by the background
    /// extraction; None before the first and outside the window (blocking extractions).
    pub(crate) coarse: Option<CoarseMesh>,
    /// The coarse mesh drawn before `coarse`, reused by the next background extraction.
    pub(crate) coarse_spare: Option<MeshBuffers>,
    /// Coarse meshes installed so far.
    pub(crate) coarse_installed: u64,
}

/// A finished background extraction, waiting to be installed.
pub(crate) struct Finished {
    pub(crate) key: CacheKey,
    pub(crate) buffers: Option<MeshBuffers>,
    pub(crate) counts: Option<SurfaceCounts>,
    pub(crate) error: Option<String>,
}

/// Where the background extraction leaves its results for the window to pick up (the full
/// mesh and the coarse one, each in its own slot), and the coarse grid it keeps for the level of
/// detail.
#[derive(Default)]
pub(crate) struct Mailbox {
    finished: Mutex<Option<Finished>>,
    coarse: Mutex<Option<Finished>>,
    /// The coarse grid and the key of the full one it was downsampled from (built and read by
    /// the worker only).
    pub(crate) coarse_grid: Mutex<Option<(CacheKey, VoxelGrid)>>,
}

fn lock<T>(slot: &Mutex<T>) -> MutexGuard<'_, T> {
    slot.lock().unwrap_or_else(|e| e.into_inner())
}

impl Mailbox {
    pub(crate) fn post(&self, finished: Finished) {
        *lock(&self.finished) = Some(finished);
    }

    /// Leaves a coarse mesh (its `buffers` and `key`; counts and error are the full one's
    /// business).
    pub(crate) fn post_coarse(&self, finished: Finished) {
        *lock(&self.coarse) = Some(finished);
    }

    fn take(&self) -> Option<Finished> {
        lock(&self.finished).take()
    }

    /// Whether the full mesh of `key` waits here to be installed.
    pub(crate) fn holds(&self, key: &CacheKey) -> bool {
        lock(&self.finished).as_ref().is_some_and(|f| f.key == *key)
    }

    fn take_coarse(&self) -> Option<Finished> {
        lock(&self.coarse).take()
    }

    fn is_full(&self) -> bool {
        lock(&self.finished).is_some() || lock(&self.coarse).is_some()
    }
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
    pub(crate) mailbox: Arc<Mailbox>,
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

    /// Whether any surface (full or coarse, or an extraction's error) was installed: before
    /// the first, there is nothing to draw.
    pub fn extracted_any(&self) -> bool {
        let state = self.lock();
        state.key.is_some() || state.coarse.is_some()
    }

    /// Whether a frame asking for `detail` has a mesh of this surface to draw: the full one
    /// (or the error that came instead), or the coarse one where the detail asks for it (the
    /// camera moves, or the isovalue is dragged, on a slow device). Before that the points stand
    /// in: the coarse mesh of a song's first surface is a pale slab, shown for seconds while the
    /// full one was extracted (the two halves of a compare wait for one worker).
    pub fn ready_for(&self, detail: SurfaceDetail) -> bool {
        let state = self.lock();
        state.key.is_some() || (detail != SurfaceDetail::Full && state.coarse.is_some())
    }

    /// True while an extraction runs in the background or its result waits to be installed:
    /// the window should come back (and show that it is busy).
    pub fn needs_another_frame(&self) -> bool {
        self.lock().requested.is_some() || self.mailbox.is_full()
    }

    /// The counts, the error and whether an extraction is under way, under one lock.
    pub fn status(&self) -> ExtractionStatus {
        let state = self.lock();
        ExtractionStatus {
            counts: state.counts,
            error: state.error.clone(),
            extracting: state.requested.is_some() || self.mailbox.is_full(),
        }
    }

    /// True while the surface on screen is not yet the one asked for (an extraction runs).
    pub fn is_extracting(&self) -> bool {
        self.lock().requested.is_some()
    }

    /// Installs a finished background extraction, if one arrived: its mesh is drawn from now on
    /// (the one it replaces is kept as the next extraction's spare). Returns whether the surface
    /// changed, so the window renders the scene again. Never waits for the GPU.
    pub fn install_finished(&self) -> bool {
        let coarse = self.install_coarse();
        let Some(finished) = self.mailbox.take() else {
            return coarse;
        };
        let mut state = self.lock();
        if state.requested.as_ref() == Some(&finished.key) {
            state.requested = None;
        }
        let old = std::mem::replace(&mut state.buffers, finished.buffers);
        if old.is_some() {
            state.spare = old;
        }
        state.key = Some(finished.key);
        state.installed += 1;
        state.counts = finished.counts;
        state.error = finished.error;
        true
    }

    /// Installs a finished coarse mesh, if one arrived (the one it replaces is kept as the next
    /// coarse extraction's spare).
    fn install_coarse(&self) -> bool {
        let Some(finished) = self.mailbox.take_coarse() else {
            return false;
        };
        let mut state = self.lock();
        if let Some(buffers) = finished.buffers {
            let old = state.coarse.replace(CoarseMesh {
                buffers,
                key: finished.key,
                counts: finished.counts,
            });
            if let Some(old) = old {
                state.coarse_spare = Some(old.buffers);
            }
            state.coarse_installed += 1;
        }
        true
    }

    /// Coarse meshes installed so far (the level of detail; the window's tests read it).
    pub fn coarse_installed(&self) -> u64 {
        self.lock().coarse_installed
    }

    /// Which mesh a frame asking for `detail` draws, `wanted` being the key of the current
    /// settings (None: no grid).
    pub(crate) fn level_to_draw(
        state: &SurfaceState,
        detail: SurfaceDetail,
        wanted: Option<&CacheKey>,
    ) -> Option<Level> {
        let matches = |key: &CacheKey| wanted == Some(key);
        let full = state.buffers.as_ref().and(state.key.as_ref()).map(matches);
        let coarse = state.coarse.as_ref().map(|c| matches(&c.key));
        choose_mesh(detail, full, coarse)
    }

    /// How many background extractions were installed (fewer than requests when they were
    /// coalesced).
    pub fn installed(&self) -> u64 {
        self.lock().installed
    }

    /// Whether the full mesh drawn is the surface `settings` ask of `grid` (extracted and
    /// installed: what a fresh extraction of them gives).
    pub fn shows(&self, grid: &VoxelGrid, settings: &SurfaceSettings) -> bool {
        self.lock().key.as_ref() == Some(&CacheKey::new(grid, settings))
    }

    /// The isovalue of the surface on screen (None before the first extraction).
    pub fn shown_iso_value(&self) -> Option<f32> {
        self.lock().key.as_ref().map(|k| f32::from_bits(k.iso_bits))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::context::GpuContext;

    /// A first surface at rest waits for its full mesh (the points stand in); the coarse one
    /// that comes before it is drawn only where the detail asks for it.
    #[test]
    fn a_first_surface_at_rest_waits_for_its_full_mesh() {
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe will do)");
        let buffer = |label| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 64,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let grid = VoxelGrid {
            dims: UVec3::splat(2),
            box_min: glam::Vec3::ZERO,
            box_max: glam::Vec3::ONE,
            density: buffer("density"),
            hp_mean: buffer("hp_mean"),
        };
        let key = CacheKey::new(&grid, &SurfaceSettings::default());
        let finished = || Finished {
            key: key.clone(),
            buffers: Some(MeshBuffers::new(&gpu.device, 16, 48)),
            counts: None,
            error: None,
        };
        let surface = ExtractedSurface::new();
        let details = [
            SurfaceDetail::Full,
            SurfaceDetail::Coarse,
            SurfaceDetail::CoarseUntilFull,
        ];
        assert!(
            details.iter().all(|d| !surface.ready_for(*d)),
            "nothing yet"
        );
        surface.mailbox.post_coarse(finished());
        assert!(surface.install_finished());
        assert!(surface.extracted_any());
        assert!(
            !surface.ready_for(SurfaceDetail::Full),
            "the coarse mesh alone: the points stand in at rest"
        );
        assert!(surface.ready_for(SurfaceDetail::Coarse));
        assert!(surface.ready_for(SurfaceDetail::CoarseUntilFull));
        surface.mailbox.post(finished());
        assert!(surface.install_finished());
        assert!(
            details.iter().all(|d| surface.ready_for(*d)),
            "the full mesh"
        );
    }
}
