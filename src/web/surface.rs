//! The page's Surface view: the isosurface of the grid at the isovalue of the side panel's
//! slider, extracted by the window's marching tetrahedra compute passes
//! (src/render/surface/marching_tets.rs) into the surface's mesh buffers and drawn by the
//! window's surface draw pass, without ever waiting for the GPU.
//!
//! Reads: the cloud's [`VoxelGrid`] (built on the GPU for the Volume and Surface views) and
//! the side panel's method (the window's marching tetrahedra or dual contouring passes).
//! Writes: the mesh buffers of the scene's [`ExtractedSurface`] and its cache key, so
//! [`Renderer::render`](crate::render::scene::Renderer::render) draws that mesh and starts no
//! extraction of its own (the window's background thread, which a page has not).
//!
//! How: an extraction is recorded and submitted in one go; the draw that follows reads the
//! indirect arguments the extraction's last pass wrote, so the new surface is on screen in the
//! next frame. Its counters come back asynchronously (`map_async`, which the browser resolves
//! between frames): until they do, no other extraction starts, so a dragged slider extracts
//! the value it is at whenever the last one is done, never a backlog. When a surface needed
//! more room than the buffers had, they grow and it is extracted again.
//!
//! [`GridReadback`] brings the grid's density and mean hp back once after its build, as the
//! window reads its grid back for hover picking (`view::pick`'s ray against the grid): the
//! read-out over the Surface and Volume views.
//!
//! Why not the CPU engine (src/render/surface/cpu/), as the window uses on a software adapter:
//! a page has no threads, so there it runs serially on the page's one thread, within the frame,
//! and a real GPU extracts many times sooner. It serves WebGL2, which has no compute passes
//! ([`super::gl_surface`]).

use std::sync::{Arc, Mutex};

use crate::data::field::Field;
use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::{COUNTERS_SIZE, MeshBuffers};
use crate::render::surface::driver::grown_capacities;
use crate::render::surface::dual_contour::DualContourPass;
use crate::render::surface::marching_tets::MarchingTetsPass;
use crate::render::surface::state::{CacheKey, ExtractedSurface};
use crate::render::surface::{SurfaceCounts, SurfaceError, SurfaceMethod, SurfaceSettings};

/// The first buffers' room: 256 Ki vertices (8 MiB) and 768 Ki indices; they grow as surfaces
/// need.
const INITIAL_CAPACITY: (u32, u32) = (1 << 18, 3 << 18);

/// The counters of the extraction in flight, once the browser has mapped them.
type Arrival = Arc<Mutex<Option<Result<(), String>>>>;

/// An extraction whose counters have not come back.
struct InFlight {
    staging: wgpu::Buffer,
    arrived: Arrival,
    settings: SurfaceSettings,
    capacity: (u32, u32),
}

/// The page's surface extraction (see the module's header).
pub(super) struct WebSurface {
    marching_tets: MarchingTetsPass,
    dual_contour: DualContourPass,
    in_flight: Option<InFlight>,
    /// The surface the mesh buffers hold (or will once the GPU is done): what is drawn.
    submitted: Option<SurfaceSettings>,
    /// The counts of the last extraction whose counters came back.
    pub(super) counts: Option<SurfaceCounts>,
    /// Why the surface shown is incomplete, when it is.
    pub(super) error: Option<String>,
}

impl WebSurface {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        Self {
            marching_tets: MarchingTetsPass::new(device),
            dual_contour: DualContourPass::new(device),
            in_flight: None,
            submitted: None,
            counts: None,
            error: None,
        }
    }

    /// Once a frame while the Surface view is shown: takes the counters of the extraction in
    /// flight if they came back (growing the buffers when the surface did not fit), and starts
    /// the extraction of `wanted` when none is in flight and the mesh is not that surface.
    /// Returns the settings of the surface to draw (None: nothing extracted yet) and whether
    /// the page should come back for another frame.
    pub(super) fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &VoxelGrid,
        surface: &ExtractedSurface,
        wanted: SurfaceSettings,
    ) -> (Option<SurfaceSettings>, bool) {
        self.collect(device, surface);
        if self.in_flight.is_none() && self.submitted != Some(wanted) {
            self.submit(device, queue, grid, surface, wanted);
        }
        (self.submitted, self.in_flight.is_some())
    }

    /// Forgets the surface (a new grid): the next update extracts again.
    pub(super) fn reset(&mut self) {
        self.submitted = None;
        self.counts = None;
        self.error = None;
    }

    fn submit(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &VoxelGrid,
        surface: &ExtractedSurface,
        settings: SurfaceSettings,
    ) {
        let mut state = surface.lock();
        let (v, i) = INITIAL_CAPACITY;
        let buffers = state
            .buffers
            .get_or_insert_with(|| MeshBuffers::new(device, v, i));
        let capacity = (buffers.vertex_capacity, buffers.index_capacity);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("web::surface_extract"),
        });
        let (pipelines, extra) = match settings.method {
            SurfaceMethod::MarchingTetrahedra => self.marching_tets.extraction(),
            SurfaceMethod::DualContouring => self.dual_contour.extraction(),
        };
        pipelines.record(
            device,
            queue,
            &mut encoder,
            &extra,
            grid,
            buffers,
            settings.iso_value,
            None,
            None,
        );
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("web::surface_counters_readback"),
            size: COUNTERS_SIZE,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_buffer_to_buffer(&buffers.counters, 0, &staging, 0, COUNTERS_SIZE);
        queue.submit([encoder.finish()]);
        state.key = Some(CacheKey::new(grid, &settings));
        state.requested = None;
        let arrived: Arrival = Arc::default();
        let slot = arrived.clone();
        staging.map_async(wgpu::MapMode::Read, .., move |result| {
            let result = result.map_err(|e| e.to_string());
            *slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
        });
        self.submitted = Some(settings);
        self.in_flight = Some(InFlight {
            staging,
            arrived,
            settings,
            capacity,
        });
    }

    /// Takes the counters of the extraction in flight if they came back.
    fn collect(&mut self, device: &wgpu::Device, surface: &ExtractedSurface) {
        let Some(flight) = &self.in_flight else {
            return;
        };
        let Some(result) = flight
            .arrived
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        else {
            return;
        };
        let Some(flight) = self.in_flight.take() else {
            return;
        };
        let raw = match result.map_err(|e| e.to_string()).and_then(|()| {
            let view = flight
                .staging
                .get_mapped_range(..)
                .map_err(|e| e.to_string())?;
            Ok(bytemuck::pod_read_unaligned::<[u32; 4]>(&view[..16]))
        }) {
            Ok(raw) => raw,
            Err(e) => {
                self.error = Some(SurfaceError::Readback(e).to_string());
                return;
            }
        };
        let counts = SurfaceCounts {
            method: flight.settings.method,
            vertices_needed: raw[0],
            indices_needed: raw[1],
            vertex_capacity: flight.capacity.0,
            index_capacity: flight.capacity.1,
        };
        self.counts = Some(counts);
        let mut state = surface.lock();
        state.counts = Some(counts);
        if counts.fits() {
            self.error = None;
            return;
        }
        match grown_capacities(device, &counts) {
            Ok((vertices, indices)) => {
                log::info!("surface buffers grow to {vertices} vertices, {indices} indices");
                state.buffers = Some(MeshBuffers::new(device, vertices, indices));
                // Extracted again, in the new buffers, by the next update.
                self.submitted = None;
                state.key = None;
            }
            // The truncated surface stays on screen, with the reason beside it.
            Err(e) => self.error = Some(e.to_string()),
        }
    }
}

/// The grid's density and mean hp on their way back to the CPU, for the read-out.
pub(super) struct GridReadback {
    staging: wgpu::Buffer,
    arrived: Arrival,
    grid: (glam::UVec3, glam::Vec3, glam::Vec3),
}

impl GridReadback {
    /// Copies `grid`'s two fields into one mappable buffer and asks for it.
    pub(super) fn start(device: &wgpu::Device, queue: &wgpu::Queue, grid: &VoxelGrid) -> Self {
        let size = grid.voxel_count() * 4;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("web::grid_readback"),
            size: 2 * size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("web::grid_readback"),
        });
        encoder.copy_buffer_to_buffer(&grid.density, 0, &staging, 0, size);
        encoder.copy_buffer_to_buffer(&grid.hp_mean, 0, &staging, size, size);
        queue.submit([encoder.finish()]);
        let arrived: Arrival = Arc::default();
        let slot = arrived.clone();
        staging.map_async(wgpu::MapMode::Read, .., move |result| {
            let result = result.map_err(|e| e.to_string());
            *slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
        });
        Self {
            staging,
            arrived,
            grid: (grid.dims, grid.box_min, grid.box_max),
        }
    }

    /// The grid as a [`Field`] once the browser has mapped it (None: not yet); Err says why it
    /// cannot come back.
    pub(super) fn take(&self) -> Option<Result<Field, String>> {
        let result = self
            .arrived
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()?;
        Some(result.and_then(|()| {
            let view = self
                .staging
                .get_mapped_range(..)
                .map_err(|e| e.to_string())?;
            let values: &[f32] = bytemuck::try_cast_slice(&view).map_err(|e| e.to_string())?;
            let (density, hp_mean) = values.split_at(values.len() / 2);
            let (dims, box_min, box_max) = self.grid;
            Ok(Field {
                dims,
                box_min,
                box_max,
                density: density.to_vec(),
                hp_mean: hp_mean.to_vec(),
            })
        }))
    }
}
