//! Surface view: the extracted isosurface, kept on the GPU and drawn lit and hp-coloured.
//!
//! Words: the *surface* is the isosurface of the density at the isovalue, as the view shows it;
//! its *mesh* is the vertex and index data it is stored as (GPU [`buffers`], CPU [`cpu_mesh`],
//! the `loudscape mesh` export).
//!
//! Reads: a [`VoxelGrid`](crate::render::grid::VoxelGrid) (density, hp_mean). Writes: an indexed
//! mesh in [`buffers::MeshBuffers`] (vertex records, an index buffer, the active-cell list, atomic
//! counters and indirect dispatch and draw arguments), then colour and depth of the render target.
//! Files, each beside its shader in shaders/surface/: [`extraction`] (the skeleton both methods
//! share, extraction.wgsl), [`marching_tets`] and [`dual_contour`] (the methods), [`draw`]
//! (draw.wgsl's CPU side), [`pass`] (the per-device [`pass::SurfacePass`]: requests, read-back,
//! draw), [`driver`] (the extraction driver: extract, read the counters back, grow the buffers
//! until the surface fits, on the GPU or the [`cpu`] engine), [`background`] (the window's worker
//! thread that runs the driver) and [`state`] (one cloud's [`state::ExtractedSurface`], owned by
//! its `SceneData`). Both methods first classify every cell and append only the cells that straddle the
//! isovalue to an active list, then run their expensive passes over those cells alone through
//! indirect dispatches; output is reserved in preallocated buffers with atomics and a one-thread
//! pass turns the counters into indirect draw arguments. The surface is re-extracted only when the
//! method, isovalue or grid changes. The counters keep counting past capacity; when a surface
//! needed more room the buffers grow and the surface is extracted again (never silently
//! truncated: see [`state::ExtractedSurface::counts`]). The window never waits for any of it:
//! [`background`] extracts on its own thread into spare buffers, coalescing requests, while the
//! last mesh is drawn. For interaction it also keeps a coarse surface, extracted first from the
//! grid downsampled (level of detail, [`lod`]), which a slow device draws while the camera moves
//! or the isovalue is dragged. Tests and export use [`pass::SurfacePass::extract_blocking`] and
//! [`pass::SurfacePass::read_mesh`], which do wait.

pub mod background;
pub mod buffers;
pub mod cpu;
pub mod cpu_mesh;
pub mod draw;
pub mod driver;
pub mod dual_contour;
pub mod extraction;
pub mod lod;
pub mod marching_tets;
pub mod pass;
pub mod state;

use thiserror::Error;

/// Which isosurface algorithm extracts the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum SurfaceMethod {
    /// Marching tetrahedra: six tetrahedra per cell, vertices on grid edges.
    MarchingTetrahedra,
    /// Dual contouring: one QEF vertex per cell, quads across crossing edges.
    DualContouring,
}

impl SurfaceMethod {
    pub const ALL: [SurfaceMethod; 2] = [
        SurfaceMethod::MarchingTetrahedra,
        SurfaceMethod::DualContouring,
    ];

    /// The short name used on the command line: "mt" or "dc".
    pub fn short_name(self) -> &'static str {
        match self {
            SurfaceMethod::MarchingTetrahedra => "mt",
            SurfaceMethod::DualContouring => "dc",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            SurfaceMethod::MarchingTetrahedra => "Marching tetrahedra",
            SurfaceMethod::DualContouring => "Dual contouring",
        }
    }

    /// Parses "mt" / "dc" (or the full names, any case).
    pub fn parse(text: &str) -> Option<Self> {
        crate::parse_value(text)
    }
}

/// `mt` and `dc` on the command line, the full names (hyphenated) as aliases.
impl clap::ValueEnum for SurfaceMethod {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let full = self.name().to_lowercase().replace(' ', "-");
        Some(clap::builder::PossibleValue::new(self.short_name()).alias(full))
    }
}

/// How the surface is extracted and drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSettings {
    pub method: SurfaceMethod,
    /// The density level the surface follows, in [0, 1]; a voxel is inside when its density is
    /// above it.
    pub iso_value: f32,
    /// Phong lighting by the directional light from above; off draws the flat hp colour.
    pub lit: bool,
}

impl Default for SurfaceSettings {
    fn default() -> Self {
        Self {
            method: SurfaceMethod::MarchingTetrahedra,
            iso_value: 0.5,
            lit: true,
        }
    }
}

/// What went wrong while extracting or reading a surface.
#[derive(Debug, Error)]
pub enum SurfaceError {
    #[error("reading the surface back from the GPU failed: {0}")]
    Readback(String),
    #[error(
        "the surface needs {needed} {what} but this GPU holds at most {limit} in one buffer; \
         raise the isovalue or lower the grid resolution"
    )]
    TooLarge {
        what: &'static str,
        needed: u64,
        limit: u64,
    },
    #[error("no surface has been extracted yet")]
    NotExtracted,
    #[error("a newer surface was asked for before this one was done")]
    Superseded,
}

/// How much a surface needed and how much room it had.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SurfaceCounts {
    pub method: SurfaceMethod,
    pub vertices_needed: u32,
    pub indices_needed: u32,
    pub vertex_capacity: u32,
    pub index_capacity: u32,
}

impl SurfaceCounts {
    /// True when the whole surface fitted in the buffers.
    pub fn fits(&self) -> bool {
        self.vertices_needed <= self.vertex_capacity && self.indices_needed <= self.index_capacity
    }

    /// Triangles in the (complete) surface.
    pub fn triangles(&self) -> u32 {
        self.indices_needed / 3
    }

    /// The extraction fitted and found no surface (the isovalue is above every voxel).
    pub fn found_nothing(&self) -> bool {
        self.fits() && self.triangles() == 0
    }
}
