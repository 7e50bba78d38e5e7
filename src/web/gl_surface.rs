//! The page's Surface view on WebGL2, where there are no compute passes, no storage buffers and
//! no indirect draws: the grid and the isosurface are made on the CPU by the app's CPU mirrors
//! of the GPU passes, and drawn by the window's surface draw pipeline with an ordinary indexed
//! draw ([`SurfacePass::draw_mesh`]), so the surface looks as on WebGPU.
//!
//! Reads: the page's cloud, the grid's settings and the slider's isovalue. Writes: a vertex and
//! an index buffer (VERTEX and INDEX, filled through the queue) that
//! [`GlRenderer`](super::gl::GlRenderer) draws, and the canvas's `data-surface-timing`
//! (milliseconds of the grid's build and of the last extraction, and its triangles), for
//! scripts and tests.
//!
//! How: the grid is built once, the first frame after the Surface view is chosen, by
//! [`voxelize_host::build`] (the voxelize pass's arithmetic step by step: the grid the GPU
//! builds, tests/it/voxelize.rs compares the two) in the box the WebGPU page's grid has. Each
//! new isovalue or method is then extracted by the CPU engine's marching tetrahedra or dual
//! contouring ([`CpuExtraction`] on one thread: a page has no threads to spawn), the same
//! surface as the GPU passes (tests/it/surface/cpu_engine.rs), and uploaded. The grid is kept
//! as a [`Field`] too, for the read-out under the cursor. It runs within the frame: a dragged
//! slider extracts the value it is at once a frame, never a backlog, and from the coarse grid
//! (the window's level of detail, src/render/surface/lod.rs: downsampled twice, 32^3 for a
//! song) where the full grid's extraction is slower than a moving frame's budget; at rest, the
//! full.

use glam::UVec3;

use crate::data::cloud::PointCloud;
use crate::data::field::Field;
use crate::render::grid::downsample::reference_downsample;
use crate::render::grid::settings::VoxelSettings;
use crate::render::grid::voxelize_cpu::grid_box_of_bounds;
use crate::render::grid::voxelize_host;
use crate::render::surface::SurfaceSettings;
use crate::render::surface::buffers::MeshVertex;
use crate::render::surface::cpu::grid::CpuGrid;
use crate::render::surface::cpu::{CpuExtraction, Instant, Phases};
use crate::render::surface::lod::{self, COARSE_LEVELS, Level, SurfaceDetail};

use super::WebApp;

/// The CPU's grid and the mesh's buffers of the Surface view on WebGL2.
#[derive(Default)]
pub(super) struct GlSurface {
    grid: Option<CpuGrid>,
    /// The grid downsampled [`COARSE_LEVELS`] times (the window's coarse level of detail).
    coarse: Option<CpuGrid>,
    /// The mesh: [`MeshVertex`] records and `u32` indices, grown as surfaces need.
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    index_count: u32,
    /// The surface the buffers hold, and from which grid.
    extracted: Option<(SurfaceSettings, Level)>,
    /// Milliseconds of the grid's build, of the last extraction and of the last one of the
    /// full grid.
    grid_ms: f64,
    pub(super) extract_ms: f64,
    full_ms: f64,
}

impl GlSurface {
    /// The mesh to draw, as the vertex buffer, the index buffer and the indices to draw.
    pub(super) fn mesh(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer, u32)> {
        Some((
            self.vertices.as_ref()?,
            self.indices.as_ref()?,
            self.index_count,
        ))
    }

    /// Builds the grid of `cloud` with `voxels`' resolution and smoothing for its mode, on the
    /// CPU, as the voxelize pass builds it on the GPU (the same box: the points' bounds,
    /// padded).
    /// Returns the grid as a [`Field`], for the read-out's picking.
    fn build_grid(&mut self, cloud: &PointCloud, voxels: &VoxelSettings) -> Field {
        let started = Instant::now();
        let mode = cloud.meta.mode;
        let dims = UVec3::splat(voxels.resolution_for(mode));
        let (box_min, box_max) = grid_box_of_bounds(cloud.bounds.min, cloud.bounds.max);
        let built = voxelize_host::build(
            &cloud.points,
            None,
            dims,
            (box_min, box_max),
            voxels.smoothing_for(mode),
        );
        let field = Field {
            dims,
            box_min,
            box_max,
            density: built.density,
            hp_mean: built.hp_mean,
        };
        self.set_grid(&field, started.elapsed().as_secs_f64() * 1e3);
        field
    }

    /// Takes a grid built elsewhere (the compare page's, on one scale with its other half's),
    /// built in `grid_ms` milliseconds.
    /// Its coarse grid is made here too (the window's downsampling, its CPU mirror).
    pub(super) fn set_grid(&mut self, field: &Field, grid_ms: f64) {
        let (box_min, box_max) = (field.box_min, field.box_max);
        self.grid = Some(CpuGrid::new(
            field.dims,
            box_min,
            box_max,
            &field.density,
            &field.hp_mean,
        ));
        let mut coarse = reference_downsample(field.dims, &field.density, &field.hp_mean);
        for _ in 1..COARSE_LEVELS {
            coarse = reference_downsample(coarse.0, &coarse.1, &coarse.2);
        }
        let (dims, density, hp_mean) = coarse;
        self.coarse = Some(CpuGrid::new(dims, box_min, box_max, &density, &hp_mean));
        self.grid_ms = grid_ms;
        self.extracted = None;
        self.full_ms = 0.0;
    }

    /// Extracts the surface of `wanted` (its method: marching tetrahedra or dual contouring, as
    /// on WebGPU) unless the buffers hold it, and uploads it. While the isovalue slider is
    /// `dragging`, from the coarse grid where the last extraction of the full one took longer
    /// than a moving frame's budget (the window's rule, [`lod::detail_for`]), so the slider
    /// follows the pointer; at rest from the full grid. Returns the surface's triangles and the
    /// grid it came from.
    pub(super) fn extract(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        wanted: SurfaceSettings,
        dragging: bool,
    ) -> Option<(usize, Level)> {
        let too_slow = self.full_ms > f64::from(lod::MOVING_FRAME_MS);
        let level = match lod::detail_for(too_slow, false, dragging, false) {
            SurfaceDetail::CoarseUntilFull | SurfaceDetail::Coarse => Level::Coarse,
            SurfaceDetail::Full => Level::Full,
        };
        if self.extracted == Some((wanted, level)) {
            return Some((self.index_count as usize / 3, level));
        }
        let grid = match level {
            Level::Full => self.grid.as_ref()?,
            Level::Coarse => self.coarse.as_ref()?,
        };
        let started = Instant::now();
        let extraction = CpuExtraction {
            grid,
            method: wanted.method,
            iso: wanted.iso_value,
            threads: 1,
        };
        let plan = extraction.plan(&mut Phases::default());
        let (vertices, indices) = extraction.mesh(&plan);
        upload(
            device,
            queue,
            &mut self.vertices,
            "web::gl_surface_vertices",
            wgpu::BufferUsages::VERTEX,
            bytemuck::cast_slice::<MeshVertex, u8>(&vertices),
        );
        upload(
            device,
            queue,
            &mut self.indices,
            "web::gl_surface_indices",
            wgpu::BufferUsages::INDEX,
            bytemuck::cast_slice::<u32, u8>(&indices),
        );
        self.index_count = u32::try_from(indices.len()).unwrap_or(u32::MAX);
        self.extracted = Some((wanted, level));
        self.extract_ms = started.elapsed().as_secs_f64() * 1e3;
        if level == Level::Full {
            self.full_ms = self.extract_ms;
        }
        Some((indices.len() / 3, level))
    }
}

/// Writes `bytes` at the start of `buffer`, made anew (twice the size needed) when it is too
/// small.
fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &mut Option<wgpu::Buffer>,
    label: &str,
    usage: wgpu::BufferUsages,
    bytes: &[u8],
) {
    let needed = (bytes.len() as u64).max(64);
    if buffer.as_ref().is_none_or(|b| b.size() < needed) {
        *buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: needed.next_power_of_two(),
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }));
    }
    if let (Some(buffer), false) = (buffer.as_ref(), bytes.is_empty()) {
        queue.write_buffer(buffer, 0, bytes);
    }
}

impl WebApp {
    /// The Surface view's frame on WebGL2: the grid built on the CPU the first frame after the
    /// view is chosen (this frame says so), then the slider's surface extracted when it is not
    /// the one drawn. Returns whether the page should come back for another frame.
    pub(super) fn update_gl_surface(&mut self) -> bool {
        let state = &self.render_state;
        let mut renderer = state.renderer.write();
        let Some(surface) = renderer
            .callback_resources
            .get_mut::<super::WebResources>()
            .and_then(super::WebResources::gl_surface)
        else {
            return false;
        };
        if surface.grid.is_none() {
            if self.surface_status.is_empty() {
                // Shown for a frame before the grid's build holds the page.
                self.surface_status = "building the voxel grid on the CPU…".to_string();
                return true;
            }
            self.field = Some(surface.build_grid(&self.cloud, &self.settings.voxels));
        }
        let Some((triangles, level)) = surface.extract(
            &state.device,
            &state.queue,
            self.settings.surface,
            self.iso_dragging,
        ) else {
            return false;
        };
        self.drawn_surface = surface.extracted.map(|(settings, _)| settings);
        self.surface_status = if triangles == 0 {
            "no surface: every voxel is below the isovalue".to_string()
        } else {
            format!(
                "{triangles} triangles{}, extracted on the CPU in {:.0} ms",
                if level == Level::Coarse {
                    " (coarse while the slider moves)"
                } else {
                    ""
                },
                surface.extract_ms
            )
        };
        let level = match level {
            Level::Full => "full",
            Level::Coarse => "coarse",
        };
        let timing = format!(
            "{:.1},{:.1},{triangles},{level}",
            surface.grid_ms, surface.extract_ms
        );
        if self.canvas.get_attribute("data-surface-timing").as_deref() != Some(timing.as_str()) {
            self.canvas
                .set_attribute("data-surface-timing", &timing)
                .ok();
        }
        false
    }
}
