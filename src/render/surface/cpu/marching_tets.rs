//! Marching tetrahedra on the CPU: the same surface as shaders/surface/marching_tets.wgsl (the
//! same split, case table, edge owners, vertex placement, normals and hp), written in cell order.
//!
//! Reads: a [`CpuGrid`]. Writes: [`MeshVertex`] records and triangle indices. [`plan()`] counts
//! each active cell's vertices (one per crossed edge it owns: the seven from its corner 0) and
//! indices (three per triangle of its case) through [`Plan`]; [`write()`] then writes each cell
//! row's vertices and triangles in its place, finding the vertex of an edge owned by a
//! neighbouring cell through that row's map of first vertices. Deterministic: the output is the
//! same whatever the number of threads.

use glam::Vec3A;

use crate::render::surface::buffers::MeshVertex;
use wgpu::WriteOnly;

use crate::render::surface::cpu::Phases;
use crate::render::surface::cpu::grid::{CpuGrid, corner_offset_a, corner_step, weighted_hp};
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
    // Both counts depend on the mask alone: looked up rather than worked out per cell.
    let counts: Vec<[u32; 2]> = (0..256).map(|mask| cell_counts(&cases, mask)).collect();
    Plan::new(grid, iso, threads, phases, |_, _, _, mask| {
        counts[mask as usize & 0xff]
    })
}

/// The vertices and indices an active cell with corner mask `mask` writes.
pub(super) fn cell_counts(cases: &[u32], mask: u32) -> [u32; 2] {
    [
        owned_edges(mask).count_ones(),
        3 * (cases[mask as usize * CASE_STRIDE] & 0xff),
    ]
}

/// Per cell mask, bit `lower | direction << 3` set when a triangle of the case in `cases` (see
/// [`case_table`]) has a corner on the edge from corner `lower` along `direction`.
fn used_edges(cases: &[u32]) -> Vec<u64> {
    (0..256)
        .map(|mask| {
            let case = &cases[mask * CASE_STRIDE..][..CASE_STRIDE];
            let count = (case[0] & 0xff) as usize;
            case[1..1 + count].iter().fold(0u64, |used, &code| {
                (0..3).fold(used, |used, c| used | 1 << ((code >> (6 * c)) & 0x3f))
            })
        })
        .collect()
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
    let used_edges = used_edges(&cases);
    let width = plan.cells_x + 1;
    plan.write(
        threads,
        vertices,
        indices,
        || RowWriter {
            grid,
            cases: &cases,
            used_edges: &used_edges,
            iso,
            maps: std::array::from_fn(|_| vec![Owner::default(); width]),
            last_row: None,
        },
        |writer, rows, row, vertices, indices| writer.row(rows, row, vertices, indices),
    );
}

/// Writes the vertices and triangles of one cell row at a time.
struct RowWriter<'a> {
    grid: &'a CpuGrid,
    cases: &'a [u32],
    /// [`used_edges`] of `cases`.
    used_edges: &'a [u64],
    iso: f32,
    /// The owners' maps of the rows (cy + (k & 1), cz + (k >> 1)), k = 0..4.
    maps: [Vec<Owner>; 4],
    /// The cell row the maps were last made for.
    last_row: Option<usize>,
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
        // cell whose corner 0 is the edge's lower end: at most one step up in y and z). After
        // row (cy - 1, cz) the maps of (cy, cz) and (cy, cz + 1) are its maps 1 and 3.
        let follows = cy > 0 && self.last_row == Some(row - 1);
        self.last_row = Some(row);
        if follows {
            self.maps.swap(0, 1);
            self.maps.swap(2, 3);
        }
        for k in 0..4 {
            let (y, z) = (cy + (k & 1), cz + (k >> 1));
            if y >= cells_y || z >= cells_z || (follows && k & 1 == 0) {
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
        // `CpuGrid::data_position` in SIMD lanes (the same operations in the same order).
        let (box_min, voxel_size) = (Vec3A::from(grid.box_min), Vec3A::from(grid.voxel_size));
        let row_start = vertices.len();
        for (cx, mask) in rows.cells(cy, cz) {
            let origin = grid.cell_origin(cx, cy, cz);
            let owned = owned_edges(mask);
            if owned != 0 {
                let base = Vec3A::from(CpuGrid::cell_sample(cx, cy, cz).as_vec3());
                let values = grid.corners(origin);
                let v0 = values[0];
                let g0 = grid.gradient(origin);
                let h0 = h[origin];
                let w0 = v0.max(0.0);
                let inside0 = mask & 1 != 0;
                let mut todo = owned;
                while todo != 0 {
                    let k = todo.trailing_zeros() & 7;
                    todo &= todo - 1;
                    let offset = corner_offset_a(k);
                    let at = origin + corner_step(strides, k);
                    let vk = values[k as usize];
                    let hk = h[at];
                    let t = ((iso - v0) / (vk - v0)).clamp(0.0, 1.0);
                    let gk = grid.gradient(at);
                    // The gradient for now, made the unit normal for the whole row at once
                    // (`CpuGrid::outward_normals`); the pad holds the edge and which end is
                    // inside.
                    let gradient = g0 + (gk - g0) * t;
                    let wk = vk.max(0.0);
                    let position = box_min + (base + offset * t + 0.5) * voxel_size;
                    vertices.push(MeshVertex {
                        position: position.to_array(),
                        hp: weighted_hp(w0 * h0 + wk * hk, w0 + wk),
                        normal: gradient.to_array(),
                        pad: (k | u32::from(inside0) << 3) as f32,
                    });
                }
            }
            let case = &cases[mask as usize * CASE_STRIDE..][..CASE_STRIDE];
            let count = (case[0] & 0xff) as usize;
            // The vertex of each edge the cell's triangles use, found once through its owner's
            // map entry (an edge is used by up to six triangle corners).
            let mut vertex_of = [0u32; 64];
            let mut todo = self.used_edges[mask as usize & 0xff];
            while todo != 0 {
                let edge = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let lower = edge & 7;
                let owner = maps[(lower >> 1) & 3][cx + (lower & 1)];
                vertex_of[edge] =
                    owner.first + u32::from(BELOW[owner.owned as usize & 0xff][edge >> 3]);
            }
            for &code in &case[1..1 + count] {
                indices.extend_from_slice(&[
                    vertex_of[(code & 0x3f) as usize],
                    vertex_of[((code >> 6) & 0x3f) as usize],
                    vertex_of[((code >> 12) & 0x3f) as usize],
                ]);
            }
        }
        grid.outward_normals(&mut vertices[row_start..], |v| edge_normal(grid, v.pad));
    }
}

/// The normal of a vertex whose edge has no gradient: the edge's own direction, from its inside
/// end outward (`code`: the edge's far corner k, plus 8 when corner 0 is inside).
#[cold]
fn edge_normal(grid: &CpuGrid, code: f32) -> [f32; 3] {
    let code = code as u32;
    let along = (corner_offset_a(code & 7) * Vec3A::from(grid.voxel_size)).normalize();
    if code & 8 != 0 { along } else { -along }.to_array()
}
