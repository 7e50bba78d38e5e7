//! Surface extraction off the UI thread: [`BackgroundExtractor`] runs on its own thread with its
//! own pipelines (built there, so their creation does not stall the window either), extracts
//! into a spare set of mesh buffers, waits for the GPU there, grows the buffers until the
//! surface fits, and leaves the finished mesh in the cloud's [`Mailbox`]. The window keeps
//! drawing the last mesh until [`ExtractedSurface::install_finished`] swaps the new one in.
//!
//! Requests are coalesced ([`Coalescer`]): while one extraction runs, a newer request for the
//! same surface replaces the waiting one, so a dragged isovalue slider extracts the value it
//! was at when the worker became free and, last, the value it was left at, never a backlog.
//!
//! Level of detail ([`crate::render::surface::lod`]): a job first extracts the coarse surface
//! from the grid downsampled (built once per grid, kept in the mailbox) in one submission and
//! posts it, then the full one in slices. A full extraction that a newer request for the same
//! surface overtakes is dropped between two slices (its buffers are kept for the next job), so
//! during a sweep the worker goes from one coarse surface to the next and the full one of the
//! value the slider stops at follows.
//!
//! [`ExtractedSurface::install_finished`]: crate::render::surface::state::ExtractedSurface::install_finished

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex};

use crate::render::grid::VoxelGrid;
use crate::render::grid::downsample::DownsamplePass;
use crate::render::surface::buffers::MeshBuffers;
use crate::render::surface::cpu::SurfaceEngine;
use crate::render::surface::driver::{Methods, Submit, extract_until_fits};
use crate::render::surface::lod::COARSE_LEVELS;
use crate::render::surface::state::{CacheKey, Finished, Mailbox, SurfaceState};
use crate::render::surface::{SurfaceError, SurfaceSettings};

/// A queue of work in which a new item replaces a waiting one with the same key (the latest
/// request for a thing is the only one worth doing). Items with other keys wait in order.
pub struct Coalescer<K, T> {
    inner: Mutex<(VecDeque<(K, T)>, bool)>,
    ready: Condvar,
}

impl<K, T> Default for Coalescer<K, T> {
    fn default() -> Self {
        Self {
            inner: Mutex::new((VecDeque::new(), false)),
            ready: Condvar::new(),
        }
    }
}

impl<K: PartialEq, T> Coalescer<K, T> {
    fn lock(&self) -> std::sync::MutexGuard<'_, (VecDeque<(K, T)>, bool)> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Queues `item` under `key`; returns the waiting item it replaced, if any.
    pub fn submit(&self, key: K, item: T) -> Option<T> {
        let mut inner = self.lock();
        let replaced = match inner.0.iter_mut().find(|(k, _)| *k == key) {
            Some(slot) => Some(std::mem::replace(&mut slot.1, item)),
            None => {
                inner.0.push_back((key, item));
                None
            }
        };
        self.ready.notify_one();
        replaced
    }

    /// The oldest waiting item, without waiting.
    pub fn try_take(&self) -> Option<(K, T)> {
        self.lock().0.pop_front()
    }

    /// The oldest waiting item; waits for one. None once [`Coalescer::close`] was called.
    pub fn take(&self) -> Option<(K, T)> {
        let mut inner = self.lock();
        loop {
            if inner.1 {
                return None;
            }
            if let Some(item) = inner.0.pop_front() {
                return Some(item);
            }
            inner = self.ready.wait(inner).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Whether an item waits under `key` for which `pred` holds.
    pub fn waiting(&self, key: &K, pred: impl Fn(&T) -> bool) -> bool {
        self.lock().0.iter().any(|(k, item)| k == key && pred(item))
    }

    /// Items waiting.
    pub fn len(&self) -> usize {
        self.lock().0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Stops [`Coalescer::take`]: it returns None from now on.
    pub fn close(&self) {
        self.lock().1 = true;
        self.ready.notify_all();
    }
}

/// One extraction to run: what to extract, the buffers to extract into, and where to leave it.
pub(crate) struct Job {
    pub(crate) key: CacheKey,
    pub(crate) grid: VoxelGrid,
    pub(crate) settings: SurfaceSettings,
    /// Buffers to reuse (the mesh shown before the current one), when there are any.
    pub(crate) spare: Option<MeshBuffers>,
    /// Room the last surface needed: new buffers start at least this large.
    pub(crate) capacity: (u32, u32),
    pub(crate) mailbox: Arc<Mailbox>,
    /// The coarse surface to extract first (level of detail); None: the full one only.
    pub(crate) coarse: Option<CoarseJob>,
}

/// The coarse part of a [`Job`]: buffers to reuse and the room to start with.
pub(crate) struct CoarseJob {
    pub(crate) spare: Option<MeshBuffers>,
    pub(crate) capacity: (u32, u32),
}

/// What a worker keeps between jobs.
pub(crate) struct Worker {
    pub(crate) methods: Methods,
    pub(crate) downsample: DownsamplePass,
    /// The buffers of a full extraction that was dropped (superseded), for the next job.
    pub(crate) pool: Option<MeshBuffers>,
}

impl Worker {
    pub(crate) fn new(device: &wgpu::Device, engine: SurfaceEngine) -> Self {
        Self {
            methods: Methods::new(device, engine),
            downsample: DownsamplePass::new(device),
            pool: None,
        }
    }
}

/// The worker thread and its queue of jobs (one waiting job per surface).
pub(crate) struct BackgroundExtractor {
    jobs: Arc<Coalescer<usize, Job>>,
}

impl BackgroundExtractor {
    pub(crate) fn spawn(
        device: wgpu::Device,
        queue: wgpu::Queue,
        engine: SurfaceEngine,
    ) -> std::io::Result<Self> {
        let jobs: Arc<Coalescer<usize, Job>> = Arc::default();
        let worker_jobs = jobs.clone();
        std::thread::Builder::new()
            .name("surface-extraction".into())
            .spawn(move || {
                let mut worker = Worker::new(&device, engine);
                while let Some((slot, job)) = worker_jobs.take() {
                    let key = job.key.clone();
                    // Overtaken: a request for other settings of this surface waits.
                    let superseded = || worker_jobs.waiting(&slot, |next| next.key != key);
                    run_job(&device, &queue, &mut worker, job, &superseded);
                }
            })?;
        Ok(Self { jobs })
    }

    /// Queues `job`, replacing a waiting job for the same surface.
    pub(crate) fn submit(&self, job: Job) {
        let key = Arc::as_ptr(&job.mailbox) as usize;
        self.jobs.submit(key, job);
    }
}

impl Drop for BackgroundExtractor {
    fn drop(&mut self) {
        // The thread ends after the job it is running; nothing waits for it.
        self.jobs.close();
    }
}

/// Extracts one job (waiting for the GPU on this thread) and posts the result: the coarse
/// surface first when the job asks for one, then the full one, dropped when `superseded` says
/// so between two of its slices.
pub(crate) fn run_job(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    worker: &mut Worker,
    mut job: Job,
    superseded: &dyn Fn() -> bool,
) {
    // Asked again for the surface just posted and not yet installed (the isovalue went A -> B
    // -> A while A was extracted, so A waited behind itself): installing that one answers this
    // request too. Its spare buffers are kept for the next job.
    if job.mailbox.holds(&job.key) {
        if worker.pool.is_none() {
            worker.pool = job.spare;
        }
        return;
    }
    if let Some(coarse) = job.coarse.take() {
        run_coarse(device, queue, worker, &job, coarse);
    }
    let (v, i) = job.capacity;
    let spare = job
        .spare
        .or_else(|| worker.pool.take())
        .filter(|b| b.vertex_capacity >= v && b.index_capacity >= i);
    let mut state = SurfaceState {
        buffers: Some(spare.unwrap_or_else(|| MeshBuffers::new(device, v, i))),
        ..Default::default()
    };
    let mut submissions = 0;
    let result = extract_until_fits(
        Submit::Worker {
            sliced: true,
            submissions: &mut submissions,
            superseded,
        },
        device,
        queue,
        &worker.methods,
        (v, i),
        None,
        &mut state,
        &job.grid,
        &job.settings,
    );
    if let Err(SurfaceError::Superseded) = result {
        worker.pool = state.buffers;
        return;
    }
    let error = result.err().map(|e| {
        log::warn!("{e}");
        e.to_string()
    });
    job.mailbox.post(Finished {
        key: job.key,
        buffers: state.buffers,
        counts: state.counts,
        error,
    });
}

/// The coarse surface of `job`: downsamples the grid (once per grid), extracts from it in one
/// submission, waited for by polling, and posts the mesh.
fn run_coarse(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    worker: &Worker,
    job: &Job,
    coarse: CoarseJob,
) {
    let grid = {
        let mut cached = job
            .mailbox
            .coarse_grid
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        match cached.as_ref() {
            Some((key, grid)) if key.same_grid(&job.key) => share_grid(grid),
            _ => {
                let grid = worker
                    .downsample
                    .downsample(device, queue, &job.grid, COARSE_LEVELS);
                let shared = share_grid(&grid);
                *cached = Some((job.key.clone(), grid));
                shared
            }
        }
    };
    let (v, i) = coarse.capacity;
    let mut state = SurfaceState {
        buffers: coarse
            .spare
            .filter(|b| b.vertex_capacity >= v && b.index_capacity >= i),
        ..Default::default()
    };
    let mut submissions = 0;
    let result = extract_until_fits(
        Submit::Worker {
            sliced: false,
            submissions: &mut submissions,
            superseded: &|| false,
        },
        device,
        queue,
        &worker.methods,
        (v, i),
        None,
        &mut state,
        &grid,
        &job.settings,
    );
    if let Err(e) = result {
        log::warn!("coarse surface: {e}");
    }
    job.mailbox.post_coarse(Finished {
        key: job.key.clone(),
        buffers: state.buffers,
        counts: state.counts,
        error: None,
    });
}

/// A second handle on a grid's buffers, for a job (the buffers are shared, not copied).
pub(crate) fn share_grid(grid: &VoxelGrid) -> VoxelGrid {
    VoxelGrid {
        dims: grid.dims,
        box_min: grid.box_min,
        box_max: grid.box_max,
        density: grid.density.clone(),
        hp_mean: grid.hp_mean.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// While one request runs, later ones for the same surface replace each other: only the
    /// latest waits, and it is the one taken next.
    #[test]
    fn only_the_latest_request_per_key_waits() {
        let queue: Coalescer<&str, f32> = Coalescer::default();
        assert!(queue.try_take().is_none());
        assert_eq!(queue.submit("song", 0.30), None);
        // The worker takes 0.30 and works on it; the slider moves on meanwhile.
        assert_eq!(queue.try_take(), Some(("song", 0.30)));
        assert_eq!(queue.submit("song", 0.31), None);
        assert_eq!(queue.submit("song", 0.40), Some(0.31));
        assert_eq!(queue.submit("song", 0.55), Some(0.40));
        assert_eq!(queue.len(), 1);
        assert_eq!(queue.try_take(), Some(("song", 0.55)));
        assert!(queue.is_empty());
    }

    /// A -> B -> A while A is extracted: the second request for A, taken once A's mesh is
    /// posted and before the window installs it, is answered by that mesh instead of being
    /// extracted again; once it is installed, a request for A extracts again.
    #[test]
    fn a_request_for_the_mesh_just_posted_is_not_extracted_again() {
        use crate::render::gpu::context::GpuContext;
        use crate::render::surface::state::ExtractedSurface;
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe will do)");
        let n = 16u32;
        let field: Vec<f32> = (0..n * n * n)
            .map(|i| {
                let p = glam::UVec3::new(i % n, (i / n) % n, i / (n * n)).as_vec3();
                (1.0 - (p - glam::Vec3::splat(7.5)).length() / 6.0).max(0.0)
            })
            .collect();
        let grid = VoxelGrid::from_fields(
            &gpu.device,
            glam::UVec3::splat(n),
            glam::Vec3::splat(-1.0),
            glam::Vec3::ONE,
            &field,
            &vec![0.5; field.len()],
        );
        let settings = SurfaceSettings::default();
        let surface = ExtractedSurface::new();
        let engine = SurfaceEngine::preferred(&gpu.device);
        let mut worker = Worker::new(&gpu.device, engine);
        let job = |spare| Job {
            key: CacheKey::new(&grid, &settings),
            grid: share_grid(&grid),
            settings,
            spare,
            capacity: (1024, 3072),
            mailbox: surface.mailbox.clone(),
            coarse: None,
        };
        run_job(&gpu.device, &gpu.queue, &mut worker, job(None), &|| false);
        let key = CacheKey::new(&grid, &settings);
        assert!(surface.mailbox.holds(&key));
        let spare = MeshBuffers::new(&gpu.device, 8, 8);
        run_job(
            &gpu.device,
            &gpu.queue,
            &mut worker,
            job(Some(spare)),
            &|| false,
        );
        // Not extracted again: the spare was not used but kept.
        assert_eq!(worker.pool.as_ref().map(|b| b.vertex_capacity), Some(8));
        assert!(surface.install_finished());
        assert!(surface.counts().is_some_and(|c| c.triangles() > 0));
        assert!(!surface.mailbox.holds(&key));
        // Installed: the same request now extracts (and posts) again.
        run_job(&gpu.device, &gpu.queue, &mut worker, job(None), &|| false);
        assert!(surface.mailbox.holds(&key));
    }

    /// Requests for different surfaces (Song and Timeline) do not replace each other and are
    /// taken in the order they came.
    #[test]
    fn other_keys_keep_their_place() {
        let queue: Coalescer<&str, f32> = Coalescer::default();
        queue.submit("song", 0.3);
        queue.submit("timeline", 0.5);
        queue.submit("song", 0.4);
        assert_eq!(queue.try_take(), Some(("song", 0.4)));
        assert_eq!(queue.try_take(), Some(("timeline", 0.5)));
        assert_eq!(queue.try_take(), None);
    }

    /// What the worker asks between two slices of a full extraction: does a request for other
    /// settings of the same surface wait? Not for another surface's, nor for the same settings.
    #[test]
    fn waiting_sees_only_newer_requests_for_the_same_surface() {
        let queue: Coalescer<&str, f32> = Coalescer::default();
        let running = 0.30;
        let newer = |v: &f32| *v != running;
        assert!(!queue.waiting(&"song", newer));
        queue.submit("timeline", 0.5);
        assert!(!queue.waiting(&"song", newer), "another surface");
        queue.submit("song", 0.30);
        assert!(!queue.waiting(&"song", newer), "the same settings again");
        queue.submit("song", 0.35);
        assert!(queue.waiting(&"song", newer));
    }

    /// A waiting worker wakes for a request and stops when the queue closes.
    #[test]
    fn take_waits_for_work_and_ends_on_close() {
        let queue: Arc<Coalescer<u32, u32>> = Arc::default();
        let worker = {
            let queue = queue.clone();
            std::thread::spawn(move || {
                let mut seen = Vec::new();
                while let Some((_, item)) = queue.take() {
                    seen.push(item);
                }
                seen
            })
        };
        queue.submit(1, 7);
        while !queue.is_empty() {
            std::thread::yield_now();
        }
        queue.close();
        assert_eq!(worker.join().unwrap(), vec![7]);
        assert!(queue.take().is_none());
    }
}
