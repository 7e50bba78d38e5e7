//! Marching tetrahedra on the CPU: the same surface as shaders/surface/marching_tets.wgsl (the
//! same split, case table, edge owners, vertex placement, normals and hp), written in cell order.
//!
//! Reads: a [`CpuGrid`]. Writes: [`MeshVertex`] records and triangle indices. [`plan()`] counts
//! each active cell's vertices (one per crossed edge it owns: the seven from its corner 0) and
//! indices (three per triangle of its case) through [`Plan`]; [`write()`] then writes each cell
//! row's vertices and triangles in its place, finding the vertex of an edge owned by a
//! neighbouring cell through that row's map of first vertices. Deterministic: the output is the
//! same whatever the number of threads.

use glam::Vec3;

use crate::render::surface::buffers::MeshVertex;
use wgpu::WriteOnly;

use crate::render::surface::cpu::Phases;
use crate::render::surface::cpu::grid::{CpuGrid, corner_offset, corner_step, weighted_hp};
use crate::render::surface::cpu::plan::{Plan, Rows};
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

/// Counts the marching tetrahedra surface of `grid` at `iso` on `threads` threads.
pub fn plan(grid: &CpuGrid, iso: f32, threads: usize, phases: &mut Phases) -> Plan {
    let cases = case_table();
    Plan::new(grid, iso, threads, phases, |_, _, _, mask| {
        [
            owned_edges(mask).count_ones(),
            3 * (cases[mask as usize * CASE_STRIDE] & 0xff),
        ]
    })
}

/// Writes the surface `plan` counted into `vertices` and `indices` (see [`Plan::write`]).
pub fn write(
    grid: &CpuGrid,
    iso: f32,
    plan: &Plan,
    threads: usize,
    vertices: WriteOnly<'_, [u8]>,
    indices: WriteOnly<'_, [u8]>,
) {
    let cases = case_table();
    let width = plan.cells_x + 1;
    plan.write(
        threads,
        vertices,
        indices,
        || RowWriter {
            grid,
            cases: &cases,
            iso,
            maps: std::array::from_fn(|_| vec![Owner::default(); width]),
        },
        |writer, rows, row, vertices, indices| writer.row(rows, row, vertices, indices),
    );
}

/// Writes the vertices and triangles of one cell row at a time.
struct RowWriter<'a> {
    grid: &'a CpuGrid,
    cases: &'a [u32],
    iso: f32,
    /// The owners' maps of the rows (cy + (k & 1), cz + (k >> 1)), k = 0..4.
    maps: [Vec<Owner>; 4],
}

impl RowWriter<'_> {
    fn row(
        &mut self,
        rows: &Rows<'_>,
        row: usize,
        vertices: &mut Vec<MeshVertex>,
        indices: &mut Vec<u32>,
    ) {
        let (cells_y, cells_z) = (rows.cells_y, rows.cells_z);
        let (cy, cz) = (row % cells_y, row / cells_y);
        // The owner maps of this row and of the three rows above it (an edge's owner is the
        // cell whose corner 0 is the edge's lower end: at most one step up in y and z).
        for k in 0..4 {
            let (y, z) = (cy + (k & 1), cz + (k >> 1));
            if y >= cells_y || z >= cells_z {
                continue;
            }
            let map = &mut self.maps[k];
            let mut first = rows.vertex_start[y + cells_y * z] as u32;
            for (cx, mask) in rows.cells(y, z) {
                let owned = owned_edges(mask);
                map[cx] = Owner { first, owned };
                first += u32::from(BELOW[owned as usize][7]) + (owned >> 7);
            }
        }
        let grid = self.grid;
        let strides = grid.strides();
        let h = grid.hp();
        let iso = self.iso;
        let maps = &self.maps;
        let cases = self.cases;
        for (cx, mask) in rows.cells(cy, cz) {
            let origin = grid.cell_origin(cx, cy, cz);
            let owned = owned_edges(mask);
            if owned != 0 {
                let base = CpuGrid::cell_sample(cx, cy, cz).as_vec3();
                let values = grid.corners(origin);
                let v0 = values[0];
                let g0 = grid.corner_gradient(origin, &values, 0);
                let h0 = h[origin];
                let w0 = v0.max(0.0);
                let inside0 = mask & 1 != 0;
                let mut todo = owned;
                while todo != 0 {
                    let k = todo.trailing_zeros();
                    todo &= todo - 1;
                    let offset = corner_offset(k);
                    let at = origin + corner_step(strides, k);
                    let vk = values[k as usize];
                    let hk = h[at];
                    let t = ((iso - v0) / (vk - v0)).clamp(0.0, 1.0);
                    let gk = grid.corner_gradient(origin, &values, k);
                    let mut normal = grid.outward_normal(g0 + (gk - g0) * t);
                    if normal == Vec3::ZERO {
                        // No gradient: the edge's own direction, from its inside end outward.
                        let along = (offset * grid.voxel_size).normalize();
                        normal = if inside0 { along } else { -along };
                    }
                    let wk = vk.max(0.0);
                    vertices.push(MeshVertex {
                        position: grid.data_position(base + offset * t).to_array(),
                        hp: weighted_hp(w0 * h0 + wk * hk, w0 + wk),
                        normal: normal.to_array(),
                        pad: 0.0,
                    });
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
                    indices.push(
                        owner.first + u32::from(BELOW[owner.owned as usize][direction as usize]),
                    );
                }
            }
        }
    }
}
