//! The extraction driver, shared by the blocking path ([`SurfacePass`]) and the window's
//! worker thread ([`background`]): both methods' pipelines ([`Methods`]) and
//! [`extract_until_fits`], which extracts, reads the counters back and grows the buffers until
//! the surface fits. On the worker the extraction goes to the GPU in slices, one submission per
//! pass, each waited for by polling, so the window's frame submissions (lavapipe has one queue)
//! slip in between instead of waiting for the whole extraction.
//!
//! [`SurfacePass`]: crate::render::surface::pass::SurfacePass
//! [`background`]: crate::render::surface::background

use std::sync::Mutex;

use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::readback::map_buffer;
use crate::render::gpu::timing::Timestamps;
use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::{
    COUNTERS_SIZE, MAX_MAPPED_VERTICES, MeshBuffers, MeshVertex,
};
use crate::render::surface::cpu::{self, CpuGrids, Phases, SurfaceEngine};
use crate::render::surface::dual_contour::DualContourPass;
use crate::render::surface::extraction::{EXTRACTION_PASSES, Slicer};
use crate::render::surface::marching_tets::MarchingTetsPass;
use crate::render::surface::state::{CacheKey, SurfaceState};
use crate::render::surface::{SurfaceCounts, SurfaceError, SurfaceMethod, SurfaceSettings};

/// Timestamps of a timed extraction: a start and an end per pass.
pub(crate) const TIMESTAMPS: u32 = 2 * EXTRACTION_PASSES as u32;

/// Both extraction methods: their pipelines, or on the CPU engine the grids read back for them.
pub(crate) struct Methods {
    pub(crate) engine: SurfaceEngine,
    pub(crate) marching_tets: MarchingTetsPass,
    pub(crate) dual_contour: DualContourPass,
    pub(crate) cpu_grids: CpuGrids,
    /// The phases of the last CPU extraction (benchmarks).
    pub(crate) cpu_phases: Mutex<Phases>,
}

impl Methods {
    pub(crate) fn new(device: &wgpu::Device, engine: SurfaceEngine) -> Self {
        Self {
            engine,
            marching_tets: MarchingTetsPass::new(device),
            dual_contour: DualContourPass::new(device),
            cpu_grids: CpuGrids::default(),
            cpu_phases: Mutex::default(),
        }
    }
}

/// The largest number of `element_size`-byte elements one buffer binding may hold.
fn element_limit(device: &wgpu::Device, element_size: u64) -> u64 {
    (storage_binding_limit(device) / element_size).min(u64::from(u32::MAX))
}

/// The room a surface of `counts` needs (vertices, indices): the capacities it has when they
/// suffice, else the next powers of two, within what one buffer binding of `device` may hold
/// (and, for marching tetrahedra, what its cell map can address); an error when the device
/// cannot. The window's driver and the web page's Surface view grow their buffers by it.
pub fn grown_capacities(
    device: &wgpu::Device,
    counts: &SurfaceCounts,
) -> Result<(u32, u32), SurfaceError> {
    let grow_to = |needed: u32, capacity: u32, what: &'static str, size: u64, max: u64| {
        if needed <= capacity {
            return Ok(capacity);
        }
        let limit = element_limit(device, size).min(max);
        let wanted = u64::from(needed).next_power_of_two().min(limit);
        if wanted < u64::from(needed) {
            return Err(SurfaceError::TooLarge {
                what,
                needed: u64::from(needed),
                limit,
            });
        }
        Ok(wanted as u32)
    };
    // Marching tetrahedra's cell map cannot address more vertices.
    let max_vertices = match counts.method {
        SurfaceMethod::MarchingTetrahedra => MAX_MAPPED_VERTICES,
        SurfaceMethod::DualContouring => u64::MAX,
    };
    let vertices = grow_to(
        counts.vertices_needed,
        counts.vertex_capacity,
        "vertices",
        std::mem::size_of::<MeshVertex>() as u64,
        max_vertices,
    )?;
    let indices = grow_to(
        counts.indices_needed,
        counts.index_capacity,
        "indices",
        4,
        u64::MAX,
    )?;
    Ok((vertices, indices))
}

/// Grows the buffers to hold `counts`; an error when the device cannot.
fn grow(
    device: &wgpu::Device,
    state: &mut SurfaceState,
    counts: &SurfaceCounts,
) -> Result<(), SurfaceError> {
    let (vertices, indices) = grown_capacities(device, counts)?;
    log::info!("surface buffers grow to {vertices} vertices, {indices} indices");
    state.buffers = Some(MeshBuffers::new(device, vertices, indices));
    state.key = None;
    Ok(())
}

/// Maps a MAP_READ buffer by polling the device without blocking it, a millisecond apart. A
/// blocking poll holds the device's fence while it waits, so every `queue.submit` of the
/// window's frames (which needs that fence) would wait for the whole extraction.
pub(crate) fn map_polling(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>, SurfaceError> {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU8, Ordering};
    let state = Arc::new(AtomicU8::new(0));
    let callback_state = state.clone();
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, move |result| {
        callback_state.store(if result.is_ok() { 1 } else { 2 }, Ordering::Release);
    });
    loop {
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        match state.load(Ordering::Acquire) {
            0 => std::thread::sleep(std::time::Duration::from_millis(1)),
            1 => break,
            _ => return Err(SurfaceError::Readback("mapping the counters failed".into())),
        }
    }
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| SurfaceError::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// Maps each (buffer, bytes) of `ranges` with a nonzero length for writing from its start and
/// waits for the mappings: blocking, or by polling without blocking the device (see
/// [`map_polling`]).
fn map_for_writing(
    device: &wgpu::Device,
    ranges: &[(&wgpu::Buffer, u64)],
    blocking: bool,
) -> Result<(), SurfaceError> {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let (done, failed) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
    let mut wanted = 0;
    for &(buffer, bytes) in ranges {
        if bytes == 0 {
            continue;
        }
        wanted += 1;
        let (done, failed) = (done.clone(), failed.clone());
        buffer
            .slice(..bytes)
            .map_async(wgpu::MapMode::Write, move |result| {
                if result.is_err() {
                    failed.fetch_add(1, Ordering::AcqRel);
                }
                done.fetch_add(1, Ordering::AcqRel);
            });
    }
    while done.load(Ordering::Acquire) < wanted {
        let poll = if blocking {
            wgpu::PollType::wait_indefinitely()
        } else {
            wgpu::PollType::Poll
        };
        device
            .poll(poll)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        if !blocking && done.load(Ordering::Acquire) < wanted {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    if failed.load(Ordering::Acquire) > 0 {
        return Err(SurfaceError::Readback(
            "mapping the mesh buffers for writing failed".into(),
        ));
    }
    Ok(())
}

/// Waits for the work submitted so far by polling the device without blocking it (see
/// [`map_polling`]).
pub(crate) fn wait_polling(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), SurfaceError> {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let done = Arc::new(AtomicBool::new(false));
    let callback_done = done.clone();
    queue.on_submitted_work_done(move || callback_done.store(true, Ordering::Release));
    loop {
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        if done.load(Ordering::Acquire) {
            return Ok(());
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
}

/// Extracts the surface into `state`'s buffers and waits for its size, growing the buffers and
/// extracting again until it fits (or cannot fit: then the error, with the counts kept).
/// [`Submit::Worker`] (the window's worker) waits by polling and, sliced, submits each pass on
/// its own (see [`map_polling`]), so other threads' submissions run between them; counts the
/// submissions there. The result is the same as in one submission.
/// How an extraction goes to the GPU and is waited for.
pub(crate) enum Submit<'a> {
    /// One submission, waited for by blocking (tests, export, headless).
    Blocking,
    /// The window's worker: waits by polling (see [`map_polling`]); `sliced`: one submission
    /// per pass; `submissions` counts them; `superseded` is asked before each slice and, once
    /// true, the rest of the extraction is dropped
    /// ([`SurfaceError::Superseded`]).
    Worker {
        sliced: bool,
        submissions: &'a mut usize,
        superseded: &'a dyn Fn() -> bool,
    },
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn extract_until_fits(
    mut submit: Submit<'_>,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    methods: &Methods,
    initial_capacity: (u32, u32),
    timing: Option<&Timestamps>,
    state: &mut SurfaceState,
    grid: &VoxelGrid,
    settings: &SurfaceSettings,
) -> Result<SurfaceCounts, SurfaceError> {
    if methods.engine == SurfaceEngine::Cpu {
        return extract_on_cpu(
            submit,
            device,
            queue,
            methods,
            initial_capacity,
            state,
            grid,
            settings,
        );
    }
    loop {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("surface::extract"),
        });
        let (v, i) = initial_capacity;
        let buffers = state
            .buffers
            .get_or_insert_with(|| MeshBuffers::new(device, v, i));
        let timestamps = timing.map(|t| &t.set);
        let mut slice_error = None;
        let mut sliced = 0usize;
        let mut dropped = false;
        let superseded = match &submit {
            Submit::Worker { superseded, .. } => Some(*superseded),
            Submit::Blocking => None,
        };
        let mut submit_slice = |encoder: &mut wgpu::CommandEncoder| {
            let done = std::mem::replace(
                encoder,
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("surface::extract"),
                }),
            );
            // A newer request waits: the rest of this one is recorded but never submitted.
            dropped = dropped || superseded.is_some_and(|f| f());
            if dropped {
                return;
            }
            queue.submit([done.finish()]);
            sliced += 1;
            if slice_error.is_none() {
                slice_error = wait_polling(device, queue).err();
            }
        };
        let slicer: Option<&mut Slicer<'_>> = match submit {
            Submit::Worker { sliced: true, .. } => Some(&mut submit_slice),
            _ => None,
        };
        // With `timestamps` each pass writes its start and end; with a slicer each pass is a
        // submission of its own.
        let (pipelines, extra) = match settings.method {
            SurfaceMethod::MarchingTetrahedra => methods.marching_tets.extraction(),
            SurfaceMethod::DualContouring => methods.dual_contour.extraction(),
        };
        pipelines.record(
            device,
            queue,
            &mut encoder,
            &extra,
            grid,
            buffers,
            settings.iso_value,
            timestamps,
            slicer,
        );
        state.key = Some(CacheKey::new(grid, settings));
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("surface::counters_readback"),
            size: COUNTERS_SIZE,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_buffer_to_buffer(&buffers.counters, 0, &staging, 0, COUNTERS_SIZE);
        if let Some(timing) = timing {
            timing.resolve(&mut encoder, TIMESTAMPS);
        }
        let (vertex_capacity, index_capacity) = (buffers.vertex_capacity, buffers.index_capacity);
        if dropped || slice_error.is_some() {
            // The grid's word ranges may not have been worked out.
            buffers.forget_grid();
        }
        if dropped {
            state.key = None;
            return Err(SurfaceError::Superseded);
        }
        queue.submit([encoder.finish()]);
        if let Some(e) = slice_error {
            return Err(e);
        }
        let bytes = match &mut submit {
            Submit::Worker { submissions, .. } => {
                **submissions += sliced + 1;
                map_polling(device, &staging)?
            }
            Submit::Blocking => map_buffer(device, &staging, "the surface counters")
                .map_err(|e| SurfaceError::Readback(e.to_string()))?,
        };
        let raw: [u32; 4] = bytemuck::pod_read_unaligned(&bytes[..16]);
        let counts = SurfaceCounts {
            method: settings.method,
            vertices_needed: raw[0],
            indices_needed: raw[1],
            vertex_capacity,
            index_capacity,
        };
        state.counts = Some(counts);
        if counts.fits() {
            state.error = None;
            return Ok(counts);
        }
        if let Err(e) = grow(device, state, &counts) {
            // The truncated surface stays drawable, with the reason beside it.
            state.key = Some(CacheKey::new(grid, settings));
            state.error = Some(e.to_string());
            return Err(e);
        }
    }
}

/// [`extract_until_fits`] on the CPU engine: the grid read back once (kept for the next
/// isovalue), the surface extracted on the CPU's cores, the buffers grown to it before it is
/// written, and the upload waited for as `submit` says.
#[allow(clippy::too_many_arguments)]
fn extract_on_cpu(
    mut submit: Submit<'_>,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    methods: &Methods,
    initial_capacity: (u32, u32),
    state: &mut SurfaceState,
    grid: &VoxelGrid,
    settings: &SurfaceSettings,
) -> Result<SurfaceCounts, SurfaceError> {
    let blocking = matches!(submit, Submit::Blocking);
    let map = |buffer: &wgpu::Buffer| {
        if blocking {
            map_buffer(device, buffer, "surface data")
                .map_err(|e| SurfaceError::Readback(e.to_string()))
        } else {
            map_polling(device, buffer)
        }
    };
    let mut phases = Phases::default();
    let started = cpu::Instant::now();
    let key = CacheKey::new(grid, settings);
    let cpu_grid = methods.cpu_grids.get(device, queue, grid, &key, map)?;
    phases.lap("grid", started);
    let extraction = cpu::CpuExtraction {
        grid: &cpu_grid,
        method: settings.method,
        iso: settings.iso_value,
        threads: cpu::default_threads(),
    };
    let plan = extraction.plan(&mut phases);
    if let Submit::Worker { superseded, .. } = &submit
        && superseded()
    {
        state.key = None;
        return Err(SurfaceError::Superseded);
    }
    let (v, i) = initial_capacity;
    let buffers = state
        .buffers
        .get_or_insert_with(|| MeshBuffers::new(device, v, i));
    let wanted = SurfaceCounts {
        method: settings.method,
        vertices_needed: plan.vertices().min(u32::MAX as usize) as u32,
        indices_needed: plan.indices().min(u32::MAX as usize) as u32,
        vertex_capacity: buffers.vertex_capacity,
        index_capacity: buffers.index_capacity,
    };
    let grown = if wanted.fits() {
        Ok(())
    } else {
        grow(device, state, &wanted)
    };
    let started = cpu::Instant::now();
    let buffers = state
        .buffers
        .get_or_insert_with(|| MeshBuffers::new(device, v, i));
    let fits = grown.is_ok()
        && plan.vertices() <= buffers.vertex_capacity as usize
        && plan.indices() <= buffers.index_capacity as usize;
    if fits && buffers.host_writable {
        // The buffers are host memory: written in place, no staging copy.
        map_for_writing(device, &cpu::write_ranges(buffers, &plan), blocking)?;
        cpu::write_mapped(queue, buffers, &extraction, &plan)?;
    } else {
        cpu::write_from_memory(queue, buffers, extraction.mesh(&plan), plan.active_cells);
    }
    phases.lap("vertices and triangles", started);
    let started = cpu::Instant::now();
    let counts = SurfaceCounts {
        vertex_capacity: buffers.vertex_capacity,
        index_capacity: buffers.index_capacity,
        ..wanted
    };
    queue.submit([]);
    match &mut submit {
        Submit::Blocking => device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| SurfaceError::Readback(e.to_string()))?,
        Submit::Worker { submissions, .. } => {
            **submissions += 1;
            wait_polling(device, queue)?;
        }
    }
    phases.lap("upload", started);
    *methods.cpu_phases.lock().unwrap_or_else(|e| e.into_inner()) = phases;
    state.key = Some(CacheKey::new(grid, settings));
    state.counts = Some(counts);
    match grown {
        Ok(()) => {
            state.error = None;
            Ok(counts)
        }
        Err(e) => {
            // The truncated surface stays drawable, with the reason beside it.
            state.error = Some(e.to_string());
            Err(e)
        }
    }
}
