//! Isosurface extraction on the CPU, for devices that are themselves the CPU.
//!
//! On a software adapter (lavapipe, WARP, SwiftShader: `wgpu::DeviceType::Cpu`) the GPU passes
//! run on the same cores as native code would, but through a shader compiler that turns every
//! storage-buffer load and store whose address differs between SIMD lanes into a loop over the
//! lanes; the extraction passes are made of such loads and stores and ran 4 to 5 times slower
//! than VTK's flying edges there (docs/PERFORMANCE.md). So on such a device the surface is
//! extracted here instead ([`SurfaceEngine::preferred`]), on all cores, into the same buffers
//! and with the same surface: the same cells, vertices, normals, hp and winding as
//! shaders/surface/marching_tets.wgsl and dual_contour.wgsl (tests/it/surface/cpu_engine.rs
//! compares the two engines triangle for triangle). On a real GPU the GPU passes run.
//!
//! Reads: a [`VoxelGrid`], read back once per grid into a padded [`CpuGrid`] (kept for the next
//! isovalue). Writes: the mesh into [`MeshBuffers`] (vertices, indices, counters and the indexed
//! indirect draw, as the GPU's `finalize` leaves them), so drawing, read-back and export do not
//! know which engine ran. On a CPU adapter the mesh buffers are host memory that can be mapped
//! (`wanted_features`), and every thread writes its share of the mesh straight into them;
//! elsewhere (the engine pinned on a GPU) the mesh is built in memory and written through the
//! queue. On wasm32 (the web page on WebGL2, src/web/gl_surface.rs) it runs serially, on the
//! page's one thread ([`for_each_part`]), timed by the browser's clock. Files: [`grid`] (the
//! padded grid, the inside bits and the cell sweep), [`plan`] (counting the output and writing
//! it on all threads, both methods' skeleton), [`marching_tets`], [`dual_contour`].

pub mod dual_contour;
pub mod grid;
pub mod marching_tets;
pub mod plan;
pub mod recycle;

use std::sync::{Arc, Mutex};

use bytemuck::Zeroable;

use crate::render::gpu::readback::copy_to_staging;
use crate::render::grid::VoxelGrid;
use crate::render::surface::buffers::{INDEXED_ARGS_OFFSET, MeshBuffers, MeshVertex};
use crate::render::surface::state::CacheKey;
use crate::render::surface::{SurfaceError, SurfaceMethod};
use grid::CpuGrid;
use plan::Plan;
use wgpu::WriteOnly;

/// The clock of [`Phases`]: std's natively; on wasm32, where std's panics, the browser's
/// (`performance.now()`, through web_time).
#[cfg(not(target_arch = "wasm32"))]
pub use std::time::Instant;
#[cfg(target_arch = "wasm32")]
pub use web_time::Instant;

/// Runs `work` on each of `parts` and gives back their results in order: each part a task of
/// rayon's pool, whose threads stay between extractions (spawning two threads per sweep cost
/// about 85 us on the 2-core machine of docs/PERFORMANCE.md, three sweeps an extraction); where
/// there is one part, or on wasm32 always (a web page has no threads), [`in_turn`] on the
/// calling thread. The engine's sweeps share out their rows through this, so one thread (what
/// [`default_threads`] is on wasm32) is the serial path, with the same output. A panic in a part
/// is raised again on the calling thread.
pub fn for_each_part<P: Send, R: Send>(parts: Vec<P>, work: impl Fn(P) -> R + Sync) -> Vec<R> {
    #[cfg(not(target_arch = "wasm32"))]
    if parts.len() > 1 {
        use rayon::prelude::*;
        // One part a task: the parts are already the threads' balanced shares.
        return parts.into_par_iter().with_max_len(1).map(&work).collect();
    }
    in_turn(parts, work)
}

/// [`for_each_part`]'s serial path: each part after the other, on the calling thread.
pub fn in_turn<P, R>(parts: Vec<P>, work: impl Fn(P) -> R) -> Vec<R> {
    parts.into_iter().map(work).collect()
}

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

/// An extraction on the CPU: `grid`, `method`, `iso` and the threads it runs on.
pub struct CpuExtraction<'a> {
    pub grid: &'a CpuGrid,
    pub method: SurfaceMethod,
    pub iso: f32,
    pub threads: usize,
}

impl CpuExtraction<'_> {
    /// Counts the surface (inside bits, each cell row's vertices and indices).
    pub fn plan(&self, phases: &mut Phases) -> Plan {
        match self.method {
            SurfaceMethod::MarchingTetrahedra => {
                marching_tets::plan(self.grid, self.iso, self.threads, phases)
            }
            SurfaceMethod::DualContouring => {
                dual_contour::plan(self.grid, self.iso, self.threads, phases)
            }
        }
    }

    /// Writes the surface `plan` counted: exactly `plan.vertices()` [`MeshVertex`] records and
    /// `plan.indices()` indices.
    pub fn write(&self, plan: &Plan, vertices: WriteOnly<'_, [u8]>, indices: WriteOnly<'_, [u8]>) {
        let (grid, iso, threads) = (self.grid, self.iso, self.threads);
        match self.method {
            SurfaceMethod::MarchingTetrahedra => {
                marching_tets::write(grid, iso, plan, threads, vertices, indices);
            }
            SurfaceMethod::DualContouring => {
                dual_contour::write(grid, iso, plan, threads, vertices, indices);
            }
        }
    }

    /// The whole surface in memory (where it cannot go straight to the GPU: a surface larger
    /// than the device's buffers, and tests).
    pub fn mesh(&self, plan: &Plan) -> (Vec<MeshVertex>, Vec<u32>) {
        let mut vertices = vec![MeshVertex::zeroed(); plan.vertices()];
        let mut indices = vec![0u32; plan.indices()];
        self.write(
            plan,
            WriteOnly::from(bytemuck::cast_slice_mut::<MeshVertex, u8>(&mut vertices)),
            WriteOnly::from(bytemuck::cast_slice_mut::<u32, u8>(&mut indices)),
        );
        (vertices, indices)
    }
}

/// The threads a CPU extraction runs on: every core (at most 16); one on wasm32 (a web page
/// has none to spawn: [`for_each_part`]).
pub fn default_threads() -> usize {
    if cfg!(target_arch = "wasm32") {
        return 1;
    }
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
    /// The CPU copy of `grid`, read back (mapped with `map`) unless it is kept already.
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
        let read = |label: &str, field: &wgpu::Buffer| {
            map(&copy_to_staging(device, queue, label, field, bytes))
        };
        let density = read("surface::cpu_density_readback", &grid.density)?;
        let hp = read("surface::cpu_hp_readback", &grid.hp_mean)?;
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

/// Writes the surface `plan` counted straight into `buffers`, mapped for writing by the caller
/// over the first `plan.vertices()` vertices and `plan.indices()` indices (through
/// [`write_ranges`]), and unmaps them; then the counters (what the surface needs) and the
/// indexed indirect draw, as the GPU's `finalize` leaves them.
pub(crate) fn write_mapped(
    queue: &wgpu::Queue,
    buffers: &MeshBuffers,
    extraction: &CpuExtraction<'_>,
    plan: &Plan,
) -> Result<(), SurfaceError> {
    let view = |buffer: &wgpu::Buffer, bytes: u64| {
        if bytes == 0 {
            return Ok(None);
        }
        buffer
            .slice(..bytes)
            .get_mapped_range_mut()
            .map(Some)
            .map_err(|e| SurfaceError::Readback(e.to_string()))
    };
    let [(_, vertex_bytes), (_, index_bytes)] = write_ranges(buffers, plan);
    {
        let mut vertices = view(&buffers.vertices, vertex_bytes)?;
        let mut indices = view(&buffers.indices, index_bytes)?;
        extraction.write(
            plan,
            vertices
                .as_mut()
                .map_or_else(WriteOnly::default, |v| v.slice(..)),
            indices
                .as_mut()
                .map_or_else(WriteOnly::default, |v| v.slice(..)),
        );
    }
    if vertex_bytes > 0 {
        buffers.vertices.unmap();
    }
    if index_bytes > 0 {
        buffers.indices.unmap();
    }
    write_counts(
        queue,
        buffers,
        [plan.vertices(), plan.indices()],
        plan.active_cells,
        plan.indices(),
    );
    Ok(())
}

/// The buffers and byte ranges [`write_mapped`] writes (a zero length is not mapped).
pub(crate) fn write_ranges<'b>(
    buffers: &'b MeshBuffers,
    plan: &Plan,
) -> [(&'b wgpu::Buffer, u64); 2] {
    [
        (
            &buffers.vertices,
            (plan.vertices() * std::mem::size_of::<MeshVertex>()) as u64,
        ),
        (&buffers.indices, (plan.indices() * 4) as u64),
    ]
}

/// The counters (what the surface needs) and the indexed indirect draw of `drawn` indices.
fn write_counts(
    queue: &wgpu::Queue,
    buffers: &MeshBuffers,
    needed: [usize; 2],
    active_cells: u64,
    drawn: usize,
) {
    let clamp = |n: u64| n.min(u64::from(u32::MAX)) as u32;
    let counters = [
        clamp(needed[0] as u64),
        clamp(needed[1] as u64),
        clamp(active_cells),
        0,
    ];
    queue.write_buffer(&buffers.counters, 0, bytemuck::cast_slice(&counters));
    let draw = [clamp(drawn as u64), 1, 0, 0, 0];
    queue.write_buffer(
        &buffers.indirect,
        INDEXED_ARGS_OFFSET,
        bytemuck::cast_slice(&draw),
    );
}

/// Writes a surface held in memory into `buffers` through the queue (where they cannot be
/// mapped: a device that is not the CPU), as much as fits, as the GPU extraction leaves a
/// surface too large for the device: the vertices that fit, whole triangles only, a triangle
/// with a vertex that does not fit made degenerate, the counters saying what the whole surface
/// needs.
pub(crate) fn write_from_memory(
    queue: &wgpu::Queue,
    buffers: &MeshBuffers,
    (vertices, indices): (Vec<MeshVertex>, Vec<u32>),
    active_cells: u64,
) {
    let vertex_count = vertices.len().min(buffers.vertex_capacity as usize);
    if vertex_count > 0 {
        queue.write_buffer(
            &buffers.vertices,
            0,
            bytemuck::cast_slice(&vertices[..vertex_count]),
        );
    }
    let index_capacity = (buffers.index_capacity - buffers.index_capacity % 3) as usize;
    let index_count = indices.len().min(index_capacity);
    let clean: Vec<u32> = indices[..index_count]
        .chunks_exact(3)
        .flat_map(|t| {
            if t.iter().all(|&i| (i as usize) < vertex_count) {
                [t[0], t[1], t[2]]
            } else {
                [0; 3]
            }
        })
        .collect();
    if !clean.is_empty() {
        queue.write_buffer(&buffers.indices, 0, bytemuck::cast_slice(&clean));
    }
    write_counts(
        queue,
        buffers,
        [vertices.len(), indices.len()],
        active_cells,
        index_count,
    );
}

#[cfg(test)]
mod tests {
    use glam::{UVec3, Vec3};

    use super::*;

    /// The serial path, wasm32's (one thread: every part in turn on the calling thread, no
    /// thread spawned), writes the same mesh byte for byte as the threaded one, for both
    /// methods at isovalues low and high on the song-like field.
    #[test]
    fn the_serial_path_gives_the_threaded_mesh() {
        let caller = std::thread::current().id();
        let ran_on = |parts: Vec<u32>| for_each_part(parts, |_| std::thread::current().id());
        assert_eq!(
            ran_on(vec![7]),
            vec![caller],
            "one part ran on another thread"
        );
        assert!(
            ran_on(vec![1, 2, 3]).iter().all(|&id| id != caller),
            "the parts did not run on threads of their own"
        );
        assert_eq!(in_turn(vec![1, 2, 3], |p| p * 10), vec![10, 20, 30]);

        let dims = UVec3::new(64, 57, 49);
        let (density, hp) = crate::data::synthetic::song_like_field(dims);
        let grid = CpuGrid::new(dims, Vec3::splat(-1.0), Vec3::ONE, &density, &hp);
        let mut triangles = 0;
        for method in SurfaceMethod::ALL {
            for iso in [0.2, 0.5] {
                let mesh = |threads| {
                    let extraction = CpuExtraction {
                        grid: &grid,
                        method,
                        iso,
                        threads,
                    };
                    let plan = extraction.plan(&mut Phases::default());
                    extraction.mesh(&plan)
                };
                let (serial_vertices, serial_indices) = mesh(1);
                let (threaded_vertices, threaded_indices) = mesh(4);
                let at = format!("{} at {iso}", method.name());
                assert!(
                    bytemuck::cast_slice::<_, u8>(&serial_vertices)
                        == bytemuck::cast_slice::<_, u8>(&threaded_vertices),
                    "{at}: vertices"
                );
                assert_eq!(serial_indices, threaded_indices, "{at}: indices");
                triangles += serial_indices.len() / 3;
            }
        }
        assert!(triangles > 10_000, "only {triangles} triangles compared");
    }
}
