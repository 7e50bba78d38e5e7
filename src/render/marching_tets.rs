//! Marching tetrahedra on the GPU (paper 3.2).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean. Writes: into [`MeshBuffers`] an indexed mesh
//! with one [`MeshVertex`](crate::render::mesh::MeshVertex) per grid edge that crosses the
//! isovalue (shared by all the triangles on it), the active-cell list and cell map, the counters
//! and the indexed indirect draw arguments.
//! Cells run from -1 to dims - 1 (samples outside the grid read as zero, so surfaces close at its
//! border). A cell is split into six tetrahedra around its main diagonal, the same split in every
//! cell, so neighbouring cells cut their shared face the same way and the surface is watertight.
//! Each tetrahedron's inside mask indexes a 16-entry case table of up to two triangles.
//! Passes (see shaders/marching_tets.wgsl): `classify` sweeps every cell (eight loads) and
//! appends the straddling ones to the active list, reserving their vertices and indices with
//! atomics; `dispatch_active` writes the indirect dispatch over them; `edge_vertices` places one
//! vertex on each crossing edge a cell owns (the seven edges from its corner 0: three box edges,
//! three face diagonals and the body diagonal, so every edge of every tetrahedron has exactly one
//! owner); `triangles` writes three indices per triangle, finding each edge's vertex through the
//! owner's entry in the cell map; `finalize` writes the draw. Vertex normals: the
//! central-difference gradient of the density interpolated along the edge, negated (toward lower
//! density); a vanishing gradient falls back to the edge's direction from inside to outside.

use crate::render::grid::VoxelGrid;
use crate::render::mesh::{
    ExtractionPipelines, MeshBuffers, compute_pipeline, extraction_layout, record_extraction_passes,
};
use crate::render::shaders;

/// The marching tetrahedra pipelines, built once.
pub struct MarchingTetsPass {
    layout: wgpu::BindGroupLayout,
    inside_bits: wgpu::ComputePipeline,
    classify: wgpu::ComputePipeline,
    dispatch_active: wgpu::ComputePipeline,
    edge_vertices: wgpu::ComputePipeline,
    triangles: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
}

impl MarchingTetsPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "marching_tets", &shaders::marching_tets());
        let layout = extraction_layout(device, "marching_tets::layout");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("marching_tets::pipeline_layout"),
            bind_group_layouts: &[None, Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            compute_pipeline(
                device,
                &format!("marching_tets::{entry}"),
                &pipeline_layout,
                &module,
                entry,
            )
        };
        Self {
            inside_bits: pipeline("inside_bits_pass"),
            classify: pipeline("classify"),
            dispatch_active: pipeline("dispatch_active"),
            edge_vertices: pipeline("edge_vertices"),
            triangles: pipeline("triangles"),
            finalize: pipeline("finalize"),
            layout,
        }
    }

    /// Records the extraction of the surface at `iso_value` into `buffers`.
    pub fn record(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        grid: &VoxelGrid,
        buffers: &mut MeshBuffers,
        iso_value: f32,
    ) {
        record_extraction_passes(
            device,
            queue,
            encoder,
            &self.layout,
            ExtractionPipelines {
                label: "marching_tets::extract",
                inside_bits: &self.inside_bits,
                classify: &self.classify,
                dispatch_active: &self.dispatch_active,
                per_active: [&self.edge_vertices, &self.triangles],
                finalize: &self.finalize,
            },
            grid,
            buffers,
            iso_value,
        );
    }
}
