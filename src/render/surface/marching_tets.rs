//! Marching tetrahedra on the GPU (paper 3.2).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean. Writes: into [`MeshBuffers`] an indexed mesh with
//! one [`MeshVertex`](crate::render::surface::buffers::MeshVertex) per grid edge that crosses the
//! isovalue (shared by all the triangles on it), the active-cell list and cell map, the counters
//! and the indexed indirect draw arguments. Cells run from -1 to dims - 1 (samples outside the grid
//! read as zero, so surfaces close at its border). A cell is split into six tetrahedra around its
//! main diagonal, the same split in every cell, so neighbouring cells cut their shared face the
//! same way and the surface is watertight. Each tetrahedron's inside mask indexes a 16-entry case
//! table of up to two triangles; the six are folded into one 256-entry table per cell mask
//! ([`case_table`]). Passes (see shaders/surface/marching_tets.wgsl and surface/extraction.wgsl):
//! `inside_bits_pass` packs which samples are inside into bits; `classify` sweeps 32 cells per
//! thread with bitwise operations and appends the straddling ones to the active list, reserving
//! their vertices and indices with atomics; `dispatch_active` writes the indirect dispatch over
//! them; `edge_vertices` places one vertex on each crossing edge a cell owns (the seven edges from
//! its corner 0: three box edges, three face diagonals and the body diagonal, so every edge of
//! every tetrahedron has exactly one owner); `triangles` writes three indices per triangle, finding
//! each edge's vertex through the owner's entry in the cell map (each owner's entry loaded once per
//! cell); `finalize` writes the draw. Vertex normals: the central-difference gradient of the
//! density interpolated along the edge, negated (toward lower density); a vanishing gradient falls
//! back to the edge's direction from inside to outside.
//!
//! [`VoxelGrid`]: crate::render::grid::VoxelGrid
//! [`MeshBuffers`]: crate::render::surface::buffers::MeshBuffers

use crate::render::shaders;
use crate::render::surface::extraction::{EXTRACTION_PASSES, ExtractionPipelines};
use wgpu::util::DeviceExt;

/// The six tetrahedra of a cell as cube-corner indices (bit 0: x, bit 1: y, bit 2: z), each a
/// chain 0 -> a -> a + b -> 7 around the main diagonal, so a lower corner index in a tetrahedron
/// has a subset of the higher one's offset bits.
const TETS: [[u32; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Tetrahedron edges as vertex pairs: e0 = 01, e1 = 02, e2 = 03, e3 = 12, e4 = 13, e5 = 23.
const EDGE_A: [usize; 6] = [0, 0, 0, 1, 1, 2];
const EDGE_B: [usize; 6] = [1, 2, 3, 2, 3, 3];

/// Per tetrahedron inside mask (bit v: vertex v inside): the triangles as edge triples.
const TET_TRIANGLES: [&[[usize; 3]]; 16] = [
    &[],
    &[[0, 1, 2]],
    &[[0, 3, 4]],
    &[[1, 3, 4], [1, 4, 2]],
    &[[1, 3, 5]],
    &[[0, 3, 5], [0, 5, 2]],
    &[[0, 1, 5], [0, 5, 4]],
    &[[2, 4, 5]],
    &[[2, 4, 5]],
    &[[0, 4, 5], [0, 5, 1]],
    &[[0, 2, 5], [0, 5, 3]],
    &[[1, 3, 5]],
    &[[1, 2, 4], [1, 4, 3]],
    &[[0, 3, 4]],
    &[[0, 1, 2]],
    &[],
];

/// Words per cell mask in [`case_table`].
pub(crate) const CASE_STRIDE: usize = 13;

fn corner(k: u32) -> glam::Vec3 {
    glam::Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32)
}

/// The triangles of a cell for each inside mask of its corners (bit k: corner k), as read by
/// shaders/surface/marching_tets.wgsl: word 13m holds the count in its low byte and, from bit 8,
/// which corners (bit c: corner c) are the lower end of some triangle's edge, so the shader loads
/// those owners' cell-map entries once per cell; words 13m + 1.. one triangle each, three six-bit
/// edges (lower corner | direction << 3), wound to face away from the inside corners. The winding
/// is decided at the edge midpoints: a triangle on given tetrahedron edges keeps its orientation
/// wherever on the open edges its corners lie.
pub(crate) fn case_table() -> Vec<u32> {
    let mut table = vec![0u32; 256 * CASE_STRIDE];
    for mask in 0..256u32 {
        let row = &mut table[mask as usize * CASE_STRIDE..][..CASE_STRIDE];
        for tet in TETS {
            let inside = |v: usize| (mask >> tet[v]) & 1 == 1;
            let tet_mask = (0..4).fold(0, |m, v| m | (usize::from(inside(v)) << v));
            let triangles = TET_TRIANGLES[tet_mask];
            if triangles.is_empty() {
                continue;
            }
            let (mut inside_sum, mut outside_sum, mut inside_count) =
                (glam::Vec3::ZERO, glam::Vec3::ZERO, 0.0);
            for (v, &k) in tet.iter().enumerate() {
                if inside(v) {
                    inside_sum += corner(k);
                    inside_count += 1.0;
                } else {
                    outside_sum += corner(k);
                }
            }
            let outward = outside_sum / (4.0 - inside_count) - inside_sum / inside_count;
            for triangle in triangles {
                let mut edges = triangle.map(|e| (tet[EDGE_A[e]], tet[EDGE_B[e]]));
                let mid = edges.map(|(a, b)| (corner(a) + corner(b)) * 0.5);
                if (mid[1] - mid[0]).cross(mid[2] - mid[0]).dot(outward) < 0.0 {
                    edges.swap(1, 2);
                }
                let code = edges.iter().enumerate().fold(0, |code, (c, &(a, b))| {
                    code | ((a | (a ^ b) << 3) << (6 * c))
                });
                row[0] += 1;
                let slot = (row[0] & 0xff) as usize;
                row[slot] = code;
                for (a, _) in edges {
                    row[0] |= 1 << (8 + a);
                }
            }
        }
    }
    table
}

/// The marching tetrahedra pipelines, built once.
pub struct MarchingTetsPass {
    pipelines: ExtractionPipelines,
    /// [`case_table`] on the GPU.
    cases: wgpu::Buffer,
}

impl MarchingTetsPass {
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            pipelines: ExtractionPipelines::new(
                device,
                "marching_tets",
                &shaders::marching_tets(),
                1,
                ["edge_vertices", "triangles"],
            ),
            cases: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("marching_tets::cases"),
                contents: bytemuck::cast_slice(&case_table()),
                usage: wgpu::BufferUsages::STORAGE,
            }),
        }
    }

    /// The names of the passes an extraction records, in order.
    pub fn pass_names(&self) -> [&'static str; EXTRACTION_PASSES] {
        self.pipelines.pass_names()
    }

    /// The pipelines that record the extraction and the bind-group entries of its own (the case
    /// table, binding 10) that they take (see [`ExtractionPipelines::record`]).
    pub(crate) fn extraction(&self) -> (&ExtractionPipelines, Vec<wgpu::BindGroupEntry<'_>>) {
        let cases = wgpu::BindGroupEntry {
            binding: 10,
            resource: self.cases.as_entire_binding(),
        };
        (&self.pipelines, vec![cases])
    }
}
