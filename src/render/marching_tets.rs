//! Marching tetrahedra on the GPU (paper 3.2).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean. Writes: into [`MeshBuffers`] a triangle soup
//! (three [`MeshVertex`](crate::render::mesh::MeshVertex) per triangle), the vertex counter and
//! the non-indexed indirect draw arguments.
//! One thread per cell (cells run from -1 to dims - 1, samples outside the grid read as zero so
//! surfaces close at its border). A cell is split into six tetrahedra around its main diagonal,
//! the same split in every cell, so neighbouring cells cut their shared face the same way and the
//! surface is watertight. Each tetrahedron's inside mask indexes a 16-entry case table of up to
//! two triangles; vertices are interpolated linearly on the edges, computed from the edge's lower
//! end so both cells sharing an edge produce the bit-identical point. A cell reserves room for
//! all its triangles with one atomic add. Normals: the central-difference gradient of the density
//! interpolated along the edge, negated (toward lower density), so shading is smooth across the
//! soup; a vanishing gradient falls back to the triangle's own normal.

use crate::render::grid::VoxelGrid;
use crate::render::mesh::{
    MeshBuffers, cell_workgroups, compute_pipeline, extraction_entries, extraction_layout,
};
use crate::render::shaders;

/// The marching tetrahedra pipelines, built once.
pub struct MarchingTetsPass {
    layout: wgpu::BindGroupLayout,
    extract: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
}

impl MarchingTetsPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "marching_tets", &shaders::marching_tets());
        let layout = extraction_layout(device, "marching_tets::layout", 0);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("marching_tets::pipeline_layout"),
            bind_group_layouts: &[None, Some(&layout)],
            immediate_size: 0,
        });
        Self {
            extract: compute_pipeline(
                device,
                "marching_tets::extract",
                &pipeline_layout,
                &module,
                "extract",
            ),
            finalize: compute_pipeline(
                device,
                "marching_tets::finalize",
                &pipeline_layout,
                &module,
                "finalize",
            ),
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
        buffers.write_params(queue, grid, iso_value);
        encoder.clear_buffer(&buffers.counters, 0, None);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("marching_tets::bind_group"),
            layout: &self.layout,
            entries: &extraction_entries(grid, buffers),
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("marching_tets::pass"),
            timestamp_writes: None,
        });
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_pipeline(&self.extract);
        let [x, y, z] = cell_workgroups(grid.dims);
        pass.dispatch_workgroups(x, y, z);
        pass.set_pipeline(&self.finalize);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
