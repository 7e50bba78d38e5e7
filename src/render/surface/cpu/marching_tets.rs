//! Marching tetrahedra on the CPU: the same surface as shaders/surface/marching_tets.wgsl (the
//! same split, case table, edge owners, vertex placement, normals and hp), written in cell order.
//!
//! Reads: a [`CpuGrid`]. Writes: [`MeshVertex`] records and triangle indices. Three sweeps, each
//! over cell rows split between threads: the inside bits ([`InsideBits`]); a count of each
//! row's vertices (one per crossed edge a cell owns: the seven from its corner 0) and indices
//! (three per triangle of its case), whose prefix sums give every row its place in the output;
//! then each row writes its vertices and triangles there, finding the vertex of an edge owned by
//! a neighbouring cell through that row's map of first vertices. Deterministic: the output is
//! the same whatever the number of threads.

use glam::Vec3;

use crate::render::surface::buffers::MeshVertex;
use crate::render::surface::cpu::grid::{
    CpuGrid, InsideBits, balanced_ranges, corner_offset, corner_step, weighted_hp,
};
use crate::render::surface::cpu::{CpuMesh32, Phases};
use crate::render::surface::marching_tets::{CASE_STRIDE, case_table};

/// Bit k (1..7) set when the owned edge from corner 0 to corner k crosses the isovalue.
#[inline]
fn owned_edges(mask: u32) -> u32 {
    let flip = if mask & 1 != 0 { 0xff } else { 0 };
    (mask ^ flip) & 0xfe
}

/// `BELOW[owned][d]`: the crossed owned edges below direction d (the offset of edge d's vertex
/// among its owner's), a table because the portable x86-64 target has no popcount instruction.
const BELOW: [[u8; 8]; 256] = {
    let mut table = [[0u8; 8]; 256];
    let mut owned = 0;
    while owned < 256 {
        let mut d = 0;
        while d < 8 {
            table[owned][d] = ((owned as u32) & ((1u32 << d) - 1)).count_ones() as u8;
            d += 1;
        }
        owned += 1;
    }
    table
};

/// Per row of a cell-row map: each active cell's first vertex and owned crossed edges.
#[derive(Clone, Copy, Default)]
struct Owner {
    first: u32,
    owned: u32,
}

/// The marching tetrahedra surface of `grid` at `iso` on `threads` threads.
pub fn extract(grid: &CpuGrid, iso: f32, threads: usize, phases: &mut Phases, out: &mut CpuMesh32) {
    let cases = case_table();
    let started = std::time::Instant::now();
    let bits = InsideBits::new(grid, iso, threads);
    phases.lap("inside bits", started);
    let (cells_y, cells_z) = (grid.dims.y as usize + 1, grid.dims.z as usize + 1);
    let rows = cells_y * cells_z;

    // Counts per cell row: vertices, indices, active cells.
    let started = std::time::Instant::now();
    let mut counts = vec![[0u32; 3]; rows];
    let per = rows.div_ceil(threads.max(1)).max(1);
    std::thread::scope(|scope| {
        for (chunk, out) in counts.chunks_mut(per).enumerate() {
            let (bits, cases) = (&bits, &cases);
            scope.spawn(move || {
                for (r, count) in out.iter_mut().enumerate() {
                    let row = chunk * per + r;
                    bits.row_cells(row % cells_y, row / cells_y, |_, mask| {
                        count[0] += owned_edges(mask).count_ones();
                        count[1] += 3 * (cases[mask as usize * CASE_STRIDE] & 0xff);
                        count[2] += 1;
                    });
                }
            });
        }
    });
    let mut vertex_start = Vec::with_capacity(rows + 1);
    let mut index_start = Vec::with_capacity(rows + 1);
    let (mut v, mut i, mut active) = (0u64, 0u64, 0u64);
    for c in &counts {
        vertex_start.push(v as usize);
        index_start.push(i as usize);
        v += u64::from(c[0]);
        i += u64::from(c[1]);
        active += u64::from(c[2]);
    }
    vertex_start.push(v as usize);
    index_start.push(i as usize);
    phases.lap("classify", started);

    let started = std::time::Instant::now();
    let (vertices, indices) = out.make_room(v as usize, i as usize);
    let ranges = balanced_ranges(rows, threads, |r| u64::from(counts[r][2]));
    std::thread::scope(|scope| {
        let (mut vertex_rest, mut index_rest) = (vertices, indices);
        for range in ranges {
            let (v_len, i_len) = (
                vertex_start[range.end] - vertex_start[range.start],
                index_start[range.end] - index_start[range.start],
            );
            let (vertex_out, vertex_tail) = vertex_rest.split_at_mut(v_len);
            let (index_out, index_tail) = index_rest.split_at_mut(i_len);
            (vertex_rest, index_rest) = (vertex_tail, index_tail);
            let (bits, cases, vertex_start, index_start) =
                (&bits, &cases, &vertex_start, &index_start);
            scope.spawn(move || {
                let mut rows_out = RowWriter {
                    grid,
                    bits,
                    cases,
                    iso,
                    maps: [
                        vec![Owner::default(); bits.cells_x() + 1],
                        vec![Owner::default(); bits.cells_x() + 1],
                        vec![Owner::default(); bits.cells_x() + 1],
                        vec![Owner::default(); bits.cells_x() + 1],
                    ],
                };
                let (v0, i0) = (vertex_start[range.start], index_start[range.start]);
                for row in range {
                    let vertex_slice =
                        &mut vertex_out[vertex_start[row] - v0..vertex_start[row + 1] - v0];
                    let index_slice =
                        &mut index_out[index_start[row] - i0..index_start[row + 1] - i0];
                    rows_out.row(
                        row,
                        cells_y,
                        cells_z,
                        vertex_start,
                        vertex_slice,
                        index_slice,
                    );
                }
            });
        }
    });
    phases.lap("vertices and triangles", started);
    out.active_cells = active;
}

/// Writes the vertices and triangles of one cell row at a time.
struct RowWriter<'a> {
    grid: &'a CpuGrid,
    bits: &'a InsideBits,
    cases: &'a [u32],
    iso: f32,
    /// The owners' maps of the rows (cy + (k & 1), cz + (k >> 1)), k = 0..4.
    maps: [Vec<Owner>; 4],
}

impl RowWriter<'_> {
    fn row(
        &mut self,
        row: usize,
        cells_y: usize,
        cells_z: usize,
        vertex_start: &[usize],
        vertices: &mut [MeshVertex],
        indices: &mut [u32],
    ) {
        let (cy, cz) = (row % cells_y, row / cells_y);
        // The owner maps of this row and of the three rows above it (an edge's owner is the
        // cell whose corner 0 is the edge's lower end: at most one step up in y and z).
        for k in 0..4 {
            let (y, z) = (cy + (k & 1), cz + (k >> 1));
            if y >= cells_y || z >= cells_z {
                continue;
            }
            let map = &mut self.maps[k];
            let mut first = vertex_start[y + cells_y * z] as u32;
            self.bits.row_cells(y, z, |cx, mask| {
                let owned = owned_edges(mask);
                map[cx] = Owner { first, owned };
                first += u32::from(BELOW[owned as usize][7]) + (owned >> 7);
            });
        }
        let grid = self.grid;
        let strides = grid.strides();
        let (d, h) = (grid.density(), grid.hp());
        let iso = self.iso;
        let (mut vertex_out, mut index_out) = (0usize, 0usize);
        let maps = &self.maps;
        let cases = self.cases;
        self.bits.row_cells(cy, cz, |cx, mask| {
            let origin = grid.cell_origin(cx, cy, cz);
            let owned = owned_edges(mask);
            if owned != 0 {
                let base = CpuGrid::cell_sample(cx, cy, cz).as_vec3();
                let v0 = d[origin];
                let g0 = grid.gradient(origin);
                let h0 = h[origin];
                let w0 = v0.max(0.0);
                let inside0 = mask & 1 != 0;
                let mut todo = owned;
                while todo != 0 {
                    let k = todo.trailing_zeros();
                    todo &= todo - 1;
                    let offset = corner_offset(k);
                    let at = origin + corner_step(strides, k);
                    let vk = d[at];
                    let hk = h[at];
                    let t = ((iso - v0) / (vk - v0)).clamp(0.0, 1.0);
                    let gk = grid.gradient(at);
                    let mut normal = grid.outward_normal(g0 + (gk - g0) * t);
                    if normal == Vec3::ZERO {
                        // No gradient: the edge's own direction, from its inside end outward.
                        let along = (offset * grid.voxel_size).normalize();
                        normal = if inside0 { along } else { -along };
                    }
                    let wk = vk.max(0.0);
                    vertices[vertex_out] = MeshVertex {
                        position: grid.data_position(base + offset * t).to_array(),
                        hp: weighted_hp(w0 * h0 + wk * hk, w0 + wk),
                        normal: normal.to_array(),
                        pad: 0.0,
                    };
                    vertex_out += 1;
                }
            }
            let case = &cases[mask as usize * CASE_STRIDE..][..CASE_STRIDE];
            let count = (case[0] & 0xff) as usize;
            for &code in &case[1..1 + count] {
                for corner in 0..3 {
                    let edge = (code >> (6 * corner)) & 0x3f;
                    let lower = edge & 7;
                    let owner = maps[((lower >> 1) & 3) as usize][cx + (lower & 1) as usize];
                    let direction = edge >> 3;
                    indices[index_out] =
                        owner.first + u32::from(BELOW[owner.owned as usize][direction as usize]);
                    index_out += 1;
                }
            }
        });
        debug_assert_eq!(vertex_out, vertices.len());
        debug_assert_eq!(index_out, indices.len());
    }
}
