//! Dual contouring on the GPU (paper 3.2).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean. Writes: into [`MeshBuffers`] one vertex per
//! cell that straddles the isovalue (the cell's index in the active list), the cell map, six
//! indices (two triangles) per grid edge that straddles it, the counters and the indexed
//! indirect draw arguments.
//! Passes (see shaders/surface/dual_contour.wgsl and surface/extraction.wgsl, whose skeleton
//! `ExtractionPipelines` runs): `inside_bits_pass` packs which samples are inside into bits;
//! `classify` sweeps 32 cells per thread (cells from -1 to dims - 1 with samples outside the grid
//! reading zero, so surfaces close at the border) and appends the straddling ones to the active
//! list, reserving six indices for each crossing edge from the cell's corner 0 along +x, +y, +z;
//! `dispatch_active` writes the indirect dispatch over them; `cell_vertices` places each active
//! cell's vertex by minimising the QEF of the tangent planes at the cell's edge crossings, pulled
//! toward their mass point (`QEF_BIAS` 0.5: strong on purpose, a loudness field has no sharp
//! features to keep) and clamped into the cell (Schaefer and Warren); `quads` joins the four
//! cells around every crossing edge into one quad (two triangles), wound so it faces lower
//! density; `finalize` writes the vertex count and the draw.
//! Crossing normals and vertex normals come from the density's central-difference gradient
//! (trilinearly interpolated at the vertex), negated so they point toward lower density.
//!
//! [`VoxelGrid`]: crate::render::grid::VoxelGrid
//! [`MeshBuffers`]: crate::render::surface::buffers::MeshBuffers

use crate::render::shaders;
use crate::render::surface::extraction::{EXTRACTION_PASSES, ExtractionPipelines};

/// The dual contouring pipelines, built once.
pub struct DualContourPass {
    pipelines: ExtractionPipelines,
}

impl DualContourPass {
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            pipelines: ExtractionPipelines::new(
                device,
                "dual_contour",
                &shaders::dual_contour(),
                0,
                ["cell_vertices", "quads"],
            ),
        }
    }

    /// The names of the passes an extraction records, in order.
    pub fn pass_names(&self) -> [&'static str; EXTRACTION_PASSES] {
        self.pipelines.pass_names()
    }

    /// The pipelines that record the extraction, which takes no bind-group entries of its own
    /// (see [`ExtractionPipelines::record`]).
    pub(crate) fn extraction(&self) -> (&ExtractionPipelines, Vec<wgpu::BindGroupEntry<'_>>) {
        (&self.pipelines, Vec::new())
    }
}
