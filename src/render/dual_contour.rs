//! Dual contouring on the GPU (paper 3.2).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean. Writes: into [`MeshBuffers`] one vertex per
//! cell that straddles the isovalue, the cell-to-vertex map, six indices (two triangles) per
//! grid edge that straddles it, the counters and the indexed indirect draw arguments.
//! Three dispatches: `cell_vertices` (one thread per cell, cells from -1 to dims - 1 with samples
//! outside the grid reading zero, so surfaces close at the border) places the vertex by
//! minimising the QEF of the tangent planes at the cell's edge crossings, with a small bias
//! toward their mass point, clamped into the cell (Schaefer and Warren), and appends it with an
//! atomic add; `quads` (one thread per sample, three edges each) joins the four cells around
//! every crossing edge, wound so the quad faces lower density; `finalize` writes the draw.
//! Crossing normals and vertex normals come from the density's central-difference gradient
//! (trilinearly interpolated at the vertex), negated so they point toward lower density.

use crate::render::grid::VoxelGrid;
use crate::render::mesh::{
    MeshBuffers, cell_workgroups, compute_pipeline, extraction_entries, extraction_layout,
};
use crate::render::shaders;

/// The dual contouring pipelines, built once.
pub struct DualContourPass {
    layout: wgpu::BindGroupLayout,
    cell_vertices: wgpu::ComputePipeline,
    quads: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
}

impl DualContourPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "dual_contour", &shaders::dual_contour());
        let layout = extraction_layout(device, "dual_contour::layout", 2);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("dual_contour::pipeline_layout"),
            bind_group_layouts: &[None, Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            compute_pipeline(
                device,
                &format!("dual_contour::{entry}"),
                &pipeline_layout,
                &module,
                entry,
            )
        };
        Self {
            cell_vertices: pipeline("cell_vertices"),
            quads: pipeline("quads"),
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
        buffers.write_params(queue, grid, iso_value);
        encoder.clear_buffer(&buffers.counters, 0, None);
        let cells = (grid.dims.as_u64vec3() + glam::U64Vec3::ONE).element_product();
        let needed = cells * 4;
        if buffers.cell_map.as_ref().is_none_or(|b| b.size() < needed) {
            buffers.cell_map = Some(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("dual_contour::cell_map"),
                size: needed,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }));
        }
        let Some(cell_map) = &buffers.cell_map else {
            return;
        };
        let mut entries = extraction_entries(grid, buffers);
        entries.push(wgpu::BindGroupEntry {
            binding: 6,
            resource: buffers.indices.as_entire_binding(),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 7,
            resource: cell_map.as_entire_binding(),
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("dual_contour::bind_group"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("dual_contour::pass"),
            timestamp_writes: None,
        });
        pass.set_bind_group(1, &bind_group, &[]);
        let [x, y, z] = cell_workgroups(grid.dims);
        pass.set_pipeline(&self.cell_vertices);
        pass.dispatch_workgroups(x, y, z);
        pass.set_pipeline(&self.quads);
        pass.dispatch_workgroups(x, y, z);
        pass.set_pipeline(&self.finalize);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
