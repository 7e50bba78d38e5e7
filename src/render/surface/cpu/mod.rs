//! Isosurface extraction on the CPU, for devices that are themselves the CPU.
//!
//! On a software adapter (lavapipe, WARP, SwiftShader: `wgpu::DeviceType::Cpu`) the GPU passes
//! run on the same cores as native code would, but through a shader compiler that turns every
//! storage-buffer load and store whose address differs between SIMD lanes into a loop over the
//! lanes; the extraction passes are made of such loads and stores and ran 4 to 5 times slower
//! than VTK's flying edges there (docs/PERFORMANCE.md). So on such a device the surface is
//! extracted here instead ([`SurfaceEngine::preferred`]), on all cores, into the same buffers
//! and with the same surface: the same cells, vertices, normals, hp and winding as
//! shaders/surface/marching_tets.wgsl and dual_contour.wgsl (tests/surface.rs compares the two
//! engines triangle for triangle). On a real GPU the GPU passes run.
//!
//! Reads: a [`VoxelGrid`], read back once per grid into a padded [`CpuGrid`] (kept for the next
//! isovalue). Writes: the mesh into [`MeshBuffers`] (vertices, indices, counters and the indexed
//! indirect draw, as the GPU's `finalize` leaves them), so drawing, read-back and export do not
//! know which engine ran. Files: [`grid`] (the padded grid and the cell sweep both methods
//! share), [`marching_tets`], [`dual_contour`].

pub mod dual_contour;
pub mod grid;
pub mod marching_tets;

use std::sync::{Arc, Mutex};
use std::time::Instant;

use bytemuck::Zeroable;

use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::{INDEXED_ARGS_OFFSET, MeshBuffers, MeshVertex};
use crate::render::surface::state::CacheKey;
use crate::render::surface::{SurfaceError, SurfaceMethod};
use grid::CpuGrid;

/// Where the surface is extracted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceEngine {
    /// The compute passes in shaders/surface/.
    Gpu,
    /// This module, on the CPU's cores.
    Cpu,
}

impl SurfaceEngine {
    /// The CPU on a device that is the CPU (a software adapter), the GPU otherwise.
    pub fn preferred(device: &wgpu::Device) -> Self {
        if device.adapter_info().device_type == wgpu::DeviceType::Cpu {
            Self::Cpu
        } else {
            Self::Gpu
        }
    }

    /// "gpu" / "cpu", as the command line names them.
    pub fn name(self) -> &'static str {
        match self {
            Self::Gpu => "gpu",
            Self::Cpu => "cpu",
        }
    }

    /// Parses "gpu" / "cpu" (any case).
    pub fn parse(text: &str) -> Option<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "gpu" => Some(Self::Gpu),
            "cpu" => Some(Self::Cpu),
            _ => None,
        }
    }
}

/// A surface extracted on the CPU, in the GPU's vertex records. Reused from one extraction to
/// the next, so its memory is not allocated (and faulted in) again for every isovalue.
#[derive(Default)]
pub struct CpuMesh32 {
    vertices: Vec<MeshVertex>,
    indices: Vec<u32>,
    vertex_count: usize,
    index_count: usize,
    /// Cells that straddle the isovalue.
    pub active_cells: u64,
}

impl CpuMesh32 {
    pub fn vertices(&self) -> &[MeshVertex] {
        &self.vertices[..self.vertex_count]
    }

    pub fn indices(&self) -> &[u32] {
        &self.indices[..self.index_count]
    }

    /// Room for `vertices` vertices and `indices` indices, to be overwritten whole: the memory
    /// of earlier extractions is reused (and given back when it is over four times the need).
    fn make_room(&mut self, vertices: usize, indices: usize) -> (&mut [MeshVertex], &mut [u32]) {
        fn fit<T: Clone>(v: &mut Vec<T>, n: usize, fill: T) {
            if v.len() > 4 * n.max(1 << 16) {
                v.truncate(n);
                v.shrink_to_fit();
            }
            if v.len() < n {
                v.resize(n, fill);
            }
        }
        fit(&mut self.vertices, vertices, MeshVertex::zeroed());
        fit(&mut self.indices, indices, 0);
        self.vertex_count = vertices;
        self.index_count = indices;
        (&mut self.vertices[..vertices], &mut self.indices[..indices])
    }
}

/// Wall-clock time of each phase of a CPU extraction, in milliseconds, by name.
#[derive(Clone, Debug, Default)]
pub struct Phases {
    pub times: Vec<(&'static str, f64)>,
}

impl Phases {
    /// Records the phase `name` as having run from `started` until now.
    pub fn lap(&mut self, name: &'static str, started: Instant) {
        self.times
            .push((name, started.elapsed().as_secs_f64() * 1e3));
    }
}

/// Extracts the surface of `grid` with `method` at `iso` on `threads` threads into `out`.
pub fn extract(
    grid: &CpuGrid,
    method: SurfaceMethod,
    iso: f32,
    threads: usize,
    phases: &mut Phases,
    out: &mut CpuMesh32,
) {
    match method {
        SurfaceMethod::MarchingTetrahedra => {
            marching_tets::extract(grid, iso, threads, phases, out);
        }
        SurfaceMethod::DualContouring => dual_contour::extract(grid, iso, threads, phases, out),
    }
}

/// The threads a CPU extraction runs on: every core (at most 16).
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get().min(16))
}

/// Grids read back to the CPU, most recent first: the window alternates between a surface's
/// coarse grid and its full one, and between Song and Timeline, so a few are kept.
#[derive(Default)]
pub(crate) struct CpuGrids {
    grids: Mutex<Vec<(CacheKey, Arc<CpuGrid>)>>,
}

/// Grids kept by [`CpuGrids`].
const KEPT_GRIDS: usize = 3;

impl CpuGrids {
    /// The CPU copy of `grid`, read back (waiting with `wait`) unless it is kept already.
    pub(crate) fn get(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &VoxelGrid,
        key: &CacheKey,
        map: impl Fn(&wgpu::Buffer) -> Result<Vec<u8>, SurfaceError>,
    ) -> Result<Arc<CpuGrid>, SurfaceError> {
        let mut grids = self.grids.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(at) = grids.iter().position(|(k, _)| k.same_grid(key)) {
            let entry = grids.remove(at);
            let found = entry.1.clone();
            grids.insert(0, entry);
            return Ok(found);
        }
        let bytes = grid.voxel_count() * 4;
        let staging = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(4),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        };
        let (density, hp) = (
            staging("surface::cpu_density_readback"),
            staging("surface::cpu_hp_readback"),
        );
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("surface::cpu_grid_readback"),
        });
        encoder.copy_buffer_to_buffer(&grid.density, 0, &density, 0, bytes);
        encoder.copy_buffer_to_buffer(&grid.hp_mean, 0, &hp, 0, bytes);
        queue.submit([encoder.finish()]);
        let density = map(&density)?;
        let hp = map(&hp)?;
        let n = grid.voxel_count() as usize;
        let cpu = Arc::new(CpuGrid::new(
            grid.dims,
            grid.box_min,
            grid.box_max,
            &bytemuck::cast_slice::<u8, f32>(&density)[..n],
            &bytemuck::cast_slice::<u8, f32>(&hp)[..n],
        ));
        grids.insert(0, (key.clone(), cpu.clone()));
        grids.truncate(KEPT_GRIDS);
        Ok(cpu)
    }
}

/// Writes `mesh` into `buffers` as the GPU extraction leaves its output: the vertices and
/// indices that fit (a triangle with a vertex that does not fit becomes degenerate, as on the
/// GPU), the counters (which count what the surface needs) and the indexed indirect draw of the
/// whole triangles that fit. Returns (vertices, indices) needed.
pub(crate) fn upload(queue: &wgpu::Queue, buffers: &MeshBuffers, mesh: &CpuMesh32) -> (u32, u32) {
    let needed_vertices = mesh.vertices().len().min(u32::MAX as usize) as u32;
    let needed_indices = mesh.indices().len().min(u32::MAX as usize) as u32;
    let vertex_count = mesh.vertices().len().min(buffers.vertex_capacity as usize);
    if vertex_count > 0 {
        queue.write_buffer(
            &buffers.vertices,
            0,
            bytemuck::cast_slice(&mesh.vertices()[..vertex_count]),
        );
    }
    // Whole triangles only, so every index below the drawn count is written.
    let index_capacity = (buffers.index_capacity - buffers.index_capacity % 3) as usize;
    let index_count = mesh.indices().len().min(index_capacity);
    if index_count > 0 {
        let indices = &mesh.indices()[..index_count];
        if vertex_count == mesh.vertices().len() {
            queue.write_buffer(&buffers.indices, 0, bytemuck::cast_slice(indices));
        } else {
            let clean: Vec<u32> = indices
                .chunks_exact(3)
                .flat_map(|t| {
                    if t.iter().all(|&i| (i as usize) < vertex_count) {
                        [t[0], t[1], t[2]]
                    } else {
                        [0; 3]
                    }
                })
                .collect();
            queue.write_buffer(&buffers.indices, 0, bytemuck::cast_slice(&clean));
        }
    }
    let active = mesh.active_cells.min(u64::from(u32::MAX)) as u32;
    let counters = [needed_vertices, needed_indices, active, 0];
    queue.write_buffer(&buffers.counters, 0, bytemuck::cast_slice(&counters));
    let draw = [index_count as u32, 1, 0, 0, 0];
    queue.write_buffer(
        &buffers.indirect,
        INDEXED_ARGS_OFFSET,
        bytemuck::cast_slice(&draw),
    );
    (needed_vertices, needed_indices)
}
