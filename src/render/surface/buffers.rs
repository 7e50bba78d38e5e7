//! The GPU buffers one surface lives in, and the records in them (keep in sync with
//! shaders/surface/extraction.wgsl).

use glam::UVec3;

use crate::render::grid::VoxelGrid;

/// One mesh vertex. Keep in sync with `MeshVertex` in shaders/surface/extraction.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    /// Data space.
    pub position: [f32; 3],
    /// Mean hp of the surrounding voxels (density-weighted), [0, 1].
    pub hp: f32,
    /// Unit normal in data space, toward lower density.
    pub normal: [f32; 3],
    pub pad: f32,
}
const _: () = assert!(std::mem::size_of::<MeshVertex>() == 32);

/// Keep in sync with `IsoParams` in shaders/surface/extraction.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct IsoParams {
    pub dims: [u32; 3],
    pub vertex_capacity: u32,
    pub box_min: [f32; 3],
    pub iso_value: f32,
    pub voxel_size: [f32; 3],
    pub index_capacity: u32,
    pub active_capacity: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<IsoParams>() == 64);

/// Bytes of the counters buffer: vertices, indices, active cells (atomics) and padding.
pub(crate) const COUNTERS_SIZE: u64 = 16;
/// Bytes of the indirect buffer: DrawIndirectArgs at 0, DrawIndexedIndirectArgs at 16,
/// DispatchIndirectArgs over the active cells at 36.
pub(crate) const INDIRECT_SIZE: u64 = 48;
pub(crate) const INDEXED_ARGS_OFFSET: u64 = 16;
/// Where `dispatch_active` writes the dispatch over the active cells; it is copied into
/// [`MeshBuffers::dispatch`] because a buffer bound as storage cannot also be a dispatch's
/// indirect argument.
pub(crate) const ACTIVE_DISPATCH_OFFSET: u64 = 36;
pub(crate) const DISPATCH_SIZE: u64 = 12;
/// Marching tetrahedra's cell map packs a first vertex index below this (keep in sync with
/// MAX_MAPPED_VERTICES in shaders/surface/marching_tets.wgsl).
pub(crate) const MAX_MAPPED_VERTICES: u64 = 1 << 25;
/// Bytes of one active-cell entry: cell, corner mask, first vertex, first index.
pub(crate) const ACTIVE_ENTRY_SIZE: u64 = 16;

/// The GPU buffers one surface lives in.
pub struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub counters: wgpu::Buffer,
    pub indirect: wgpu::Buffer,
    pub params: wgpu::Buffer,
    /// DispatchIndirectArgs over the active cells.
    pub dispatch: wgpu::Buffer,
    /// The cells that straddle the isovalue (16-byte entries), [`MeshBuffers::active_capacity`]
    /// of them. A complete surface never has more active cells than marching tetrahedra has
    /// triangles or dual contouring has vertices, so the capacities bound it.
    pub active: wgpu::Buffer,
    /// Per cell: what the method keeps of an active cell (its active index for dual
    /// contouring, its first vertex and crossing edges for marching tetrahedra); grown to the
    /// grid on demand.
    pub cell_map: Option<wgpu::Buffer>,
    /// One bit per (padded) sample: inside or not; grown to the grid on demand.
    pub inside_bits: Option<wgpu::Buffer>,
    /// The grid whose per-word density ranges `inside_bits` holds after its bits (its density
    /// buffer and size), once they are recorded; see [`MeshBuffers::take_new_grid`].
    ranges_of: Option<(wgpu::Buffer, UVec3)>,
    pub vertex_capacity: u32,
    pub index_capacity: u32,
    pub active_capacity: u32,
    /// `vertices` and `indices` can be mapped for writing (the device has mappable primary
    /// buffers: an adapter that is the CPU, see `wanted_features`).
    pub host_writable: bool,
}

impl MeshBuffers {
    pub fn new(device: &wgpu::Device, vertex_capacity: u32, index_capacity: u32) -> Self {
        let vertex_capacity = vertex_capacity.max(3);
        let index_capacity = index_capacity.max(6);
        let active_capacity = vertex_capacity.max(index_capacity / 3);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let host_writable = device
            .features()
            .contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS);
        let written = if host_writable {
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_WRITE
        } else {
            wgpu::BufferUsages::COPY_DST
        };
        let make = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            vertices: make(
                "surface::vertex_buffer",
                u64::from(vertex_capacity) * std::mem::size_of::<MeshVertex>() as u64,
                storage | wgpu::BufferUsages::VERTEX | written,
            ),
            indices: make(
                "surface::index_buffer",
                u64::from(index_capacity) * 4,
                storage | wgpu::BufferUsages::INDEX | written,
            ),
            counters: make(
                "surface::counters",
                COUNTERS_SIZE,
                storage | wgpu::BufferUsages::COPY_DST,
            ),
            indirect: make(
                "surface::indirect_args",
                INDIRECT_SIZE,
                storage | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            ),
            dispatch: make(
                "surface::dispatch_args",
                16,
                wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            ),
            params: make(
                "surface::params",
                std::mem::size_of::<IsoParams>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            active: make(
                "surface::active_cells",
                u64::from(active_capacity) * ACTIVE_ENTRY_SIZE,
                storage,
            ),
            cell_map: None,
            inside_bits: None,
            ranges_of: None,
            vertex_capacity,
            index_capacity,
            active_capacity,
            host_writable,
        }
    }

    /// Makes sure `cell_map` has an entry for every cell of `grid` ((dims + 1)^3) and
    /// `inside_bits` a bit for every padded sample, then the density range (two `f32`) of every
    /// word of bits.
    pub(crate) fn ensure_grid_buffers(&mut self, device: &wgpu::Device, grid: &VoxelGrid) {
        let grow = |buffer: &mut Option<wgpu::Buffer>, label: &str, needed: u64| {
            let grown = buffer.as_ref().is_none_or(|b| b.size() < needed);
            if grown {
                *buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: needed,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                }));
            }
            grown
        };
        let cells = (grid.dims.as_u64vec3() + glam::U64Vec3::ONE).element_product();
        grow(&mut self.cell_map, "surface::cell_map", cells * 4);
        let [words, rows] = bit_threads(grid.dims, 2);
        if grow(
            &mut self.inside_bits,
            "surface::inside_bits",
            words * rows * 4 * 3,
        ) {
            self.ranges_of = None;
        }
    }

    /// Whether the word ranges must be worked out for `grid` (`inside_bits` holds another
    /// grid's, or none); if so, takes them as recorded for `grid`. Grids are not written after they are
    /// built, so a grid is known by its density buffer (held here, so its id is not reused)
    /// and size.
    pub(crate) fn take_new_grid(&mut self, grid: &VoxelGrid) -> bool {
        let same = self
            .ranges_of
            .as_ref()
            .is_some_and(|(density, dims)| *density == grid.density && *dims == grid.dims);
        if !same {
            self.ranges_of = Some((grid.density.clone(), grid.dims));
        }
        !same
    }

    /// Forgets which grid's word ranges `inside_bits` holds (an extraction recorded but not run to its end).
    pub(crate) fn forget_grid(&mut self) {
        self.ranges_of = None;
    }

    /// Writes the extraction parameters for `grid` at `iso_value`.
    pub(crate) fn write_params(&self, queue: &wgpu::Queue, grid: &VoxelGrid, iso_value: f32) {
        let params = IsoParams {
            dims: grid.dims.to_array(),
            vertex_capacity: self.vertex_capacity,
            box_min: grid.box_min.to_array(),
            iso_value,
            voxel_size: grid.voxel_size().to_array(),
            index_capacity: self.index_capacity,
            active_capacity: self.active_capacity,
            pad: [0; 3],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }
}

/// Words of 32 along x and rows (y, z) of a grid padded to dims + `pad` on each axis.
pub(crate) fn bit_threads(dims: UVec3, pad: u32) -> [u64; 2] {
    let side = (dims + UVec3::splat(pad)).as_u64vec3();
    let words = (u64::from(dims.x) + 2).div_ceil(32);
    [words, side.y * side.z]
}
