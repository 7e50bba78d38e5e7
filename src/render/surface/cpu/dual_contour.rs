//! Dual contouring on the CPU: the same surface as shaders/surface/dual_contour.wgsl (one QEF
//! vertex per active cell, biased toward the crossings' mass point and clamped into the cell;
//! quads across the crossing edges from each cell's corner 0), written in cell order.
//!
//! Reads: a [`CpuGrid`]. Writes: [`MeshVertex`] records and triangle indices (two triangles per
//! quad). As in [`super::marching_tets`], [`plan()`] counts (each active cell is a vertex and has
//! six indices per quad it owns) and [`write()`] writes each cell row's vertices and quads,
//! finding the vertices of the cells below it in y and z through those rows' maps.

use glam::{IVec3, Vec3, Vec3A};

use crate::render::surface::buffers::MeshVertex;
use wgpu::WriteOnly;

use crate::render::surface::cpu::Phases;
use crate::render::surface::cpu::grid::{CpuGrid, corner_offset_a, corner_step, weighted_hp};
use crate::render::surface::cpu::plan::Plan;

/// The pull toward the mass point, relative to one unit-normal plane (QEF_BIAS in
/// shaders/surface/dual_contour.wgsl).
const QEF_BIAS: f32 = 0.5;

/// The lower corner of cube edge e (0..11): edges 4a .. 4a + 3 run along axis a.
#[inline]
const fn cube_edge_start(e: u32) -> u32 {
    let j = e & 3;
    match e >> 2 {
        0 => j << 1,
        1 => (j & 1) | ((j & 2) << 1),
        _ => j,
    }
}

/// `CROSSED_EDGES[mask]`: bit e set when cube edge e (see [`cube_edge_start`]) joins an inside
/// corner to an outside one.
const CROSSED_EDGES: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut mask = 0;
    while mask < 256 {
        let mut e = 0;
        while e < 12 {
            let ka = cube_edge_start(e);
            let kb = ka | (1 << (e >> 2));
            if (mask >> ka) & 1 != (mask >> kb) & 1 {
                table[mask as usize] |= 1 << e;
            }
            e += 1;
        }
        mask += 1;
    }
    table
};

/// The cube edges (see [`cube_edge_start`]) that corner mask `mask` crosses, in increasing order,
/// each with its two corners: (e, ka, kb).
#[inline]
fn crossed_edges(mask: u32) -> impl Iterator<Item = (u32, u32, u32)> {
    let mut crossed = CROSSED_EDGES[mask as usize & 0xff];
    std::iter::from_fn(move || {
        if crossed == 0 {
            return None;
        }
        let e = crossed.trailing_zeros();
        crossed &= crossed - 1;
        let ka = cube_edge_start(e);
        Some((e, ka, ka | (1 << (e >> 2))))
    })
}

/// Bit a set when the edge from the cell's corner 0 along axis a crosses the isovalue and the
/// four cells around it exist (`base` is the cell's lowest sample). Without branches: it is
/// asked of every active cell when counting.
#[inline]
fn quad_edges(base: IVec3, mask: u32) -> u32 {
    // Corner 1 << a is the edge's far end.
    let inside = mask & 1;
    let crossed = ((mask >> 1) ^ inside) & 1
        | (((mask >> 2) ^ inside) & 1) << 1
        | (((mask >> 4) ^ inside) & 1) << 2;
    // The cells around the edge along a lie below the cell on the two other axes.
    let below = u32::from(base.x < 0) | u32::from(base.y < 0) << 1 | u32::from(base.z < 0) << 2;
    let open = u32::from(below & 0b110 == 0)
        | u32::from(below & 0b101 == 0) << 1
        | u32::from(below & 0b011 == 0) << 2;
    crossed & open
}

/// Counts the dual contouring surface of `grid` at `iso` on `threads` threads.
pub fn plan(grid: &CpuGrid, iso: f32, threads: usize, phases: &mut Phases) -> Plan {
    Plan::new(grid, iso, threads, phases, cell_counts)
}

/// The vertices and indices active cell (cx, cy, cz) with corner mask `mask` writes.
pub(super) fn cell_counts(cx: usize, cy: usize, cz: usize, mask: u32) -> [u32; 2] {
    let base = CpuGrid::cell_sample(cx, cy, cz);
    // The set bits of the three quad edges, from a table: x86-64's baseline has no popcount
    // instruction.
    const QUADS: [u32; 8] = [0, 1, 1, 2, 1, 2, 2, 3];
    [1, 6 * QUADS[quad_edges(base, mask) as usize & 7]]
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
    let width = plan.cells_x + 1;
    plan.write(
        threads,
        vertices,
        indices,
        || -> ([Vec<u32>; 4], Option<usize>, EdgeRows) {
            (
                std::array::from_fn(|_| vec![0u32; width]),
                None,
                EdgeRows::new(width + 1),
            )
        },
        |(maps, last_row, edges), rows, row, vertices, indices| {
            let cells_y = rows.cells_y;
            let (cy, cz) = (row % cells_y, row / cells_y);
            // The vertices of this row and of the rows one below in y, z and both; after row
            // (cy - 1, cz) the maps of (cy - 1, cz) and (cy - 1, cz - 1) are its maps 0 and 2.
            let follows = cy > 0 && *last_row == Some(row - 1);
            *last_row = Some(row);
            if follows {
                maps.swap(0, 1);
                maps.swap(2, 3);
            }
            edges.next_row(follows);
            for (k, map) in maps.iter_mut().enumerate() {
                let (dy, dz) = (k & 1, k >> 1);
                if cy < dy || cz < dz || (follows && dy == 1) {
                    continue;
                }
                let (y, z) = (cy - dy, cz - dz);
                let first = rows.vertex_start[y + cells_y * z] as u32;
                for (vertex, (cx, _)) in (first..).zip(rows.cells(y, z)) {
                    map[cx] = vertex;
                }
            }
            let row_start = vertices.len();
            for (cx, mask) in rows.cells(cy, cz) {
                vertices.push(cell_vertex(grid, iso, cx, cy, cz, mask, edges));
                let s = CpuGrid::cell_sample(cx, cy, cz);
                let edges = quad_edges(s, mask);
                for axis in 0..3 {
                    if (edges >> axis) & 1 == 0 {
                        continue;
                    }
                    // The four cells around the edge, counter-clockwise seen from +axis (as in
                    // the shader's `quads`): s - eb - ec, s - ec, s, s - eb.
                    let own = maps[0][cx];
                    let mut q = match axis {
                        0 => [maps[3][cx], maps[2][cx], own, maps[1][cx]],
                        1 => [maps[2][cx - 1], maps[0][cx - 1], own, maps[2][cx]],
                        _ => [maps[1][cx - 1], maps[1][cx], own, maps[0][cx - 1]],
                    };
                    if mask & 1 == 0 {
                        // Inside beyond the edge: the surface faces -axis.
                        q.swap(1, 3);
                    }
                    indices.extend_from_slice(&[q[0], q[1], q[2], q[0], q[2], q[3]]);
                }
            }
            grid.outward_normals(&mut vertices[row_start..], |vertex| {
                let code = vertex.pad as u32;
                let (cx, mask) = ((code >> 8) as usize, code & 0xff);
                mean_edge_normal(grid, iso, cx, cy, cz, mask)
            });
        },
    );
}

/// Each crossed edge's unit normal and crossing, worked out by the first of the four cells
/// around it to need them and read by the others (they depend only on the edge's two samples):
/// the edges from the samples of the four sample rows a cell row's corners lie on, slot `dy + 2
/// dz` holding sample row (cy - 1 + dy, cz - 1 + dz) of cell row (cy, cz), the edge along axis
/// a from the sample at x = cx - 1 + dx at `3 (cx + dx) + a`. An entry is valid while its stamp
/// is its slot's; the next cell row in y takes over the two rows at dy = 1 as its rows at
/// dy = 0 (as the vertex maps are), so an edge is worked out at most twice (once per cell row in
/// z around it) instead of four times. The same operations on the same values either way, so
/// the same mesh.
struct EdgeRows {
    /// (normal x, y, z, crossing t) of each edge.
    entries: [Vec<[f32; 4]>; 4],
    stamps: [Vec<u32>; 4],
    /// The stamp of each slot's valid entries.
    slot_stamps: [u32; 4],
    next_stamp: u32,
}

impl EdgeRows {
    /// Rows of `width` samples (cells along x, plus one).
    fn new(width: usize) -> Self {
        Self {
            entries: std::array::from_fn(|_| vec![[0.0; 4]; 3 * width]),
            stamps: std::array::from_fn(|_| vec![0; 3 * width]),
            slot_stamps: [0; 4],
            next_stamp: 0,
        }
    }

    /// Moves to the next cell row: after the cell row one below in y (`follows`) its rows at
    /// dy = 1 are this row's at dy = 0 and only the rows at dy = 1 are new; otherwise all four.
    fn next_row(&mut self, follows: bool) {
        if follows {
            self.entries.swap(0, 1);
            self.stamps.swap(0, 1);
            self.slot_stamps.swap(0, 1);
            self.entries.swap(2, 3);
            self.stamps.swap(2, 3);
            self.slot_stamps.swap(2, 3);
        }
        for slot in 0..4 {
            if !follows || slot & 1 == 1 {
                self.next_stamp += 1;
                self.slot_stamps[slot] = self.next_stamp;
            }
        }
    }

    /// Entry `i` of row slot `slot`, from `make` unless it is there already.
    #[inline]
    fn get(&mut self, slot: usize, i: usize, make: impl FnOnce() -> [f32; 4]) -> [f32; 4] {
        let stamp = self.slot_stamps[slot];
        if self.stamps[slot][i] == stamp {
            self.entries[slot][i]
        } else {
            let entry = make();
            self.entries[slot][i] = entry;
            self.stamps[slot][i] = stamp;
            entry
        }
    }
}

/// The vertex of active cell (cx, cy, cz) with corner mask `mask` (as `cell_vertices` in the
/// shader), its crossed edges' normals and crossings through `edges`.
#[inline]
fn cell_vertex(
    grid: &CpuGrid,
    iso: f32,
    cx: usize,
    cy: usize,
    cz: usize,
    mask: u32,
    edges: &mut EdgeRows,
) -> MeshVertex {
    let origin = grid.cell_origin(cx, cy, cz);
    let strides = grid.strides();
    let h = grid.hp();
    let values = grid.corners(origin);
    // In SIMD lanes (Vec3A): each lane's operations, and the dot products' order, are the
    // scalar ones, so the values are the same.
    // Written out corner by corner: through `array::from_fn` each was a call that picked its
    // loads by branches on the corner's bits (the same central differences either way).
    let [sx, sy, sz] = strides;
    let gradients: [Vec3A; 8] = [
        grid.gradient(origin),
        grid.gradient(origin + sx),
        grid.gradient(origin + sy),
        grid.gradient(origin + sx + sy),
        grid.gradient(origin + sz),
        grid.gradient(origin + sx + sz),
        grid.gradient(origin + sy + sz),
        grid.gradient(origin + sx + sy + sz),
    ];
    let mut count = 0u32;
    let (mut mass, mut b) = (Vec3A::ZERO, Vec3A::ZERO);
    let (mut row0, mut row1, mut a22) = (Vec3A::ZERO, Vec3A::ZERO, 0.0f32);
    // The crossed edges in increasing order, as the shader's `cell_vertices` visits them (the
    // same sums in the same order), without a branch per edge that the corner pattern decides.
    for (e, ka, kb) in crossed_edges(mask) {
        // The edge's normal and crossing depend only on its two samples (see [`EdgeRows`]).
        let slot = (ka >> 1) as usize;
        let at = 3 * (cx + (ka & 1) as usize) + (e >> 2) as usize;
        let [nx, ny, nz, t] = edges.get(slot, at, || {
            edge_crossing(
                values[ka as usize],
                values[kb as usize],
                gradients[ka as usize],
                gradients[kb as usize],
                iso,
            )
        });
        let n = Vec3A::new(nx, ny, nz);
        let pa = corner_offset_a(ka);
        let p = pa + (corner_offset_a(kb) - pa) * t;
        // The products n n^T summed entry by entry in lanes: (a00, a01, a02) and (·, a11, a12).
        row0 += n * n.x;
        row1 += n * n.y;
        a22 += n.z * n.z;
        b += n * n.dot(p);
        mass += p;
        count += 1;
    }
    let (mut a00, a01, a02) = (row0.x, row0.y, row0.z);
    let (mut a11, a12) = (row1.y, row1.z);
    mass /= count.max(1) as f32;
    // (A + bias I) y = b - A mass, y = x - mass, solved by the adjugate.
    // A mass by A's columns in lanes (each lane's products summed in the scalar order).
    let a_mass = Vec3A::new(a00, a01, a02) * mass.x
        + Vec3A::new(a01, a11, a12) * mass.y
        + Vec3A::new(a02, a12, a22) * mass.z;
    let rhs = b - a_mass;
    a00 += QEF_BIAS;
    a11 += QEF_BIAS;
    a22 += QEF_BIAS;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    let mut local = mass;
    if det.abs() > 1e-12 {
        let y = (Vec3A::new(c00, c01, c02) * rhs.x
            + Vec3A::new(c01, c11, c12) * rhs.y
            + Vec3A::new(c02, c12, c22) * rhs.z)
            / det;
        local = mass + y;
    }
    local = local.clamp(Vec3A::ZERO, Vec3A::ONE);

    let mut gradient = Vec3A::ZERO;
    let (mut hp_sum, mut weight_sum) = (0.0f32, 0.0f32);
    // A corner's trilinear weight on an axis is 1 - l on its near side and l on its far side
    // (the values `c * l + (1 - c) * (1 - l)` takes for c = 0 and 1 with l in [0, 1], but for
    // the sign of a zero, which the sums do not see), worked out once per axis.
    let sides = [Vec3A::ONE - local, local];
    for k in 0..8u32 {
        let (x, y, z) = (k as usize & 1, (k as usize >> 1) & 1, k as usize >> 2);
        let weight = sides[x].x * sides[y].y * sides[z].z;
        gradient += weight * gradients[k as usize];
        let w = values[k as usize].max(0.0);
        hp_sum += w * h[origin + corner_step(strides, k)];
        weight_sum += w;
    }
    let base = CpuGrid::cell_sample(cx, cy, cz).as_vec3();
    let local = Vec3::from(local);
    // The gradient for now, made the outward unit normal for the whole row at once
    // (`CpuGrid::outward_normals`); without one, the crossings' normals' sum is the normal
    // (`mean_edge_normal`, the cell found again by the row and the pad).
    MeshVertex {
        position: grid.data_position(base + local).to_array(),
        hp: weighted_hp(hp_sum, weight_sum),
        normal: gradient.to_array(),
        pad: ((cx as u32) << 8 | mask) as f32,
    }
}

/// The outward normal of the sum of cell (cx, cy, cz)'s crossings' unit normals (mask `mask`),
/// where its vertex has no gradient: the crossings worked out again as [`cell_vertex`] works them
/// out (the same operations, so the same sum).
#[cold]
fn mean_edge_normal(
    grid: &CpuGrid,
    iso: f32,
    cx: usize,
    cy: usize,
    cz: usize,
    mask: u32,
) -> [f32; 3] {
    let origin = grid.cell_origin(cx, cy, cz);
    let values = grid.corners(origin);
    let strides = grid.strides();
    let mut normal_sum = Vec3A::ZERO;
    for (_, ka, kb) in crossed_edges(mask) {
        let n = edge_crossing(
            values[ka as usize],
            values[kb as usize],
            grid.gradient(origin + corner_step(strides, ka)),
            grid.gradient(origin + corner_step(strides, kb)),
            iso,
        );
        normal_sum += Vec3A::new(n[0], n[1], n[2]);
    }
    grid.outward_normal_a(normal_sum).to_array()
}

/// An edge's unit normal and crossing (x, y, z, t) from its ends' values and gradients.
#[inline]
fn edge_crossing(va: f32, vb: f32, ga: Vec3A, gb: Vec3A, iso: f32) -> [f32; 4] {
    let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
    let g = ga + (gb - ga) * t;
    let length = g.length();
    let n = if length > 1e-20 {
        g / length
    } else {
        Vec3A::ZERO
    };
    [n.x, n.y, n.z, t]
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;

    /// The normal a vertex without a gradient takes is the outward normal of the sum of its
    /// crossings' unit normals, worked out here edge by edge from each corner's own gradient,
    /// for every active cell of an irregular field on voxels that are not cubes.
    #[test]
    fn a_flat_vertex_takes_its_crossings_mean_normal() {
        let dims = UVec3::new(9, 8, 7);
        let density: Vec<f32> = (0..dims.element_product())
            .map(|i| ((i * 37 + i / 9 * 11) % 17) as f32 / 16.0)
            .collect();
        let grid = CpuGrid::new(
            dims,
            Vec3::new(-1.0, 0.0, 2.0),
            Vec3::new(2.0, 0.5, 7.0),
            &density,
            &vec![0.5; density.len()],
        );
        let iso = 0.45;
        let mut checked = 0;
        for cz in 0..=dims.z as usize {
            for cy in 0..=dims.y as usize {
                for cx in 0..=dims.x as usize {
                    let origin = grid.cell_origin(cx, cy, cz);
                    let values = grid.corners(origin);
                    let mask = (0..8).fold(0u32, |m, k| m | u32::from(values[k] > iso) << k);
                    if mask == 0 || mask == 0xff {
                        continue;
                    }
                    let mut sum = Vec3::ZERO;
                    for ka in 0..8u32 {
                        for axis in 0..3 {
                            let kb = ka | 1 << axis;
                            if kb == ka || (mask >> ka) & 1 == (mask >> kb) & 1 {
                                continue;
                            }
                            let (va, vb) = (values[ka as usize], values[kb as usize]);
                            let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
                            let ga = grid.corner_gradient(origin, &values, ka);
                            let gb = grid.corner_gradient(origin, &values, kb);
                            sum += (ga + (gb - ga) * t).normalize_or_zero();
                        }
                    }
                    let expected = grid.outward_normal(sum);
                    let normal = Vec3::from(mean_edge_normal(&grid, iso, cx, cy, cz, mask));
                    assert!(
                        (normal - expected).length() < 1e-6,
                        "cell ({cx}, {cy}, {cz}): {normal} against {expected}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 100, "only {checked} cells checked");
    }
}
