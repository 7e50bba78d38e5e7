//! The extraction skeleton both methods share, the CPU side of shaders/surface/extraction.wgsl:
//! the bind-group layout of group 1, the pipelines in the order they run (once per grid the
//! density range of each word of inside bits, then pack the inside bits, classify, the dispatch
//! over the active cells, two passes over the active cells only, the draw arguments) and their
//! recording, with optional per-pass timestamps.

use crate::render::gpu::layouts::{storage_entry, uniform_entry, whole_buffer_entries};
use crate::render::grid::VoxelGrid;
use crate::render::shaders;
use crate::render::surface::buffers::{
    ACTIVE_DISPATCH_OFFSET, DISPATCH_SIZE, MeshBuffers, bit_threads,
};

/// Bind group layout shared by the extraction passes (group 1, bindings 0..=9 of
/// shaders/surface/extraction.wgsl), plus `extra` read-only storage bindings from 10 on.
fn extraction_layout(device: &wgpu::Device, label: &str, extra: u32) -> wgpu::BindGroupLayout {
    let storage = |binding: u32, read_only: bool| {
        storage_entry(binding, wgpu::ShaderStages::COMPUTE, read_only)
    };
    let mut entries = vec![
        uniform_entry(0, wgpu::ShaderStages::COMPUTE),
        storage(1, true),
        storage(2, true),
        storage(3, false),
        storage(4, false),
        storage(5, false),
    ];
    for b in 6..=9 {
        entries.push(storage(b, false));
    }
    for b in 0..extra {
        entries.push(storage(10 + b, true));
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// The bind group entries for bindings 0..=9 (call [`MeshBuffers::ensure_grid_buffers`] first).
pub(crate) fn extraction_entries<'a>(
    grid: &'a VoxelGrid,
    buffers: &'a MeshBuffers,
) -> Vec<wgpu::BindGroupEntry<'a>> {
    let expect = "ensure_grid_buffers before binding";
    let cell_map = buffers.cell_map.as_ref().expect(expect);
    let inside_bits = buffers.inside_bits.as_ref().expect(expect);
    whole_buffer_entries(&[
        &buffers.params,
        &grid.density,
        &grid.hp_mean,
        &buffers.vertices,
        &buffers.counters,
        &buffers.indirect,
        &buffers.indices,
        cell_map,
        &buffers.active,
        inside_bits,
    ])
}

/// A compute pipeline for one entry point of an extraction shader.
fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// The pipelines of one extraction method, in the order they run (see
/// shaders/surface/extraction.wgsl). Both methods share this skeleton: pack the inside bits, list
/// the active cells, then two passes over the active cells only and one that writes the draw
/// arguments.
pub(crate) struct ExtractionPipelines {
    /// The method's name, the prefix of every label ("marching_tets").
    name: &'static str,
    /// The method's layout of group 1 (see [`extraction_layout`]).
    layout: wgpu::BindGroupLayout,
    /// Over every word of inside bits, once per grid: the density range of its samples.
    word_range: wgpu::ComputePipeline,
    /// Over every sample: packs which are inside into bits.
    inside_bits: wgpu::ComputePipeline,
    /// Over every 32 cells along x: appends the active cells.
    classify: wgpu::ComputePipeline,
    /// One thread: the dispatch over the active cells.
    dispatch_active: wgpu::ComputePipeline,
    /// Over the active cells, one after the other.
    per_active: [wgpu::ComputePipeline; 2],
    /// Their entry points.
    per_active_names: [&'static str; 2],
    /// One thread: the draw arguments.
    finalize: wgpu::ComputePipeline,
}

impl ExtractionPipelines {
    /// Builds a method's pipelines from its composed shader `source`, whose entry points are
    /// `word_range_pass`, `inside_bits_pass`, `classify`, `dispatch_active`, the two
    /// `per_active` ones and `finalize`; `extra` bindings from 10 on belong to the method.
    pub(crate) fn new(
        device: &wgpu::Device,
        name: &'static str,
        source: &str,
        extra: u32,
        per_active: [&'static str; 2],
    ) -> Self {
        let module = shaders::module(device, name, source);
        let layout = extraction_layout(device, &format!("{name}::layout"), extra);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&format!("{name}::pipeline_layout")),
            bind_group_layouts: &[None, Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            compute_pipeline(
                device,
                &format!("{name}::{entry}"),
                &pipeline_layout,
                &module,
                entry,
            )
        };
        Self {
            name,
            word_range: pipeline("word_range_pass"),
            inside_bits: pipeline("inside_bits_pass"),
            classify: pipeline("classify"),
            dispatch_active: pipeline("dispatch_active"),
            per_active: per_active.map(pipeline),
            per_active_names: per_active,
            finalize: pipeline("finalize"),
            layout,
        }
    }

    /// The names of the dispatches [`ExtractionPipelines::record`] records, in order.
    pub fn pass_names(&self) -> [&'static str; EXTRACTION_PASSES] {
        let [a, b] = self.per_active_names;
        [
            "inside_bits",
            "classify",
            "dispatch_active",
            a,
            b,
            "finalize",
        ]
    }

    /// Records an extraction at `iso_value` into `buffers`: classify every cell, then the passes
    /// over the active cells only. `extra` are the method's own bindings (from 10 on). With
    /// `timestamps` (a query set of at least 2 * [`EXTRACTION_PASSES`] timestamps) every
    /// dispatch runs in a compute pass of its own and writes its start and end there (queries
    /// 2i and 2i + 1 for the i-th of [`ExtractionPipelines::pass_names`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        extra: &[wgpu::BindGroupEntry<'_>],
        grid: &VoxelGrid,
        buffers: &mut MeshBuffers,
        iso_value: f32,
        timestamps: Option<&wgpu::QuerySet>,
        mut slice: Option<&mut Slicer<'_>>,
    ) {
        let label = format!("{}::extract", self.name);
        buffers.write_params(queue, grid, iso_value);
        buffers.ensure_grid_buffers(device, grid);
        encoder.clear_buffer(&buffers.counters, 0, None);
        let mut entries = extraction_entries(grid, buffers);
        entries.extend_from_slice(extra);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&label),
            layout: &self.layout,
            entries: &entries,
        });
        let sweep = |pad| {
            let [words, rows] = bit_threads(grid.dims, pad);
            Dispatch::Direct(flat_workgroups(words * rows))
        };
        // The density range of each word of inside bits, once per grid (kept in `buffers` for
        // the next isovalue); recorded ahead of the timed passes, in the first slice.
        if buffers.take_new_grid(grid) {
            record_dispatches(
                encoder,
                &label,
                &bind_group,
                &[(&self.word_range, sweep(2))],
                None,
                0,
            );
        }
        let before = [
            (&self.inside_bits, sweep(2)),
            (&self.classify, sweep(1)),
            (&self.dispatch_active, Dispatch::Direct([1, 1])),
        ];
        let [first, second] = &self.per_active;
        let after = [
            (first, Dispatch::Indirect(&buffers.dispatch)),
            (second, Dispatch::Indirect(&buffers.dispatch)),
            (&self.finalize, Dispatch::Direct([1, 1])),
        ];
        let Some(slice) = slice.as_mut() else {
            record_dispatches(encoder, &label, &bind_group, &before, timestamps, 0);
            copy_dispatch(encoder, buffers);
            record_dispatches(encoder, &label, &bind_group, &after, timestamps, 3);
            return;
        };
        // One submission per pass, the same work in the same order (the copy of the dispatch
        // arguments rides with the pass before it); the caller submits what follows the last.
        for (i, work) in before.iter().enumerate() {
            let first = i as u32;
            record_dispatches(
                encoder,
                &label,
                &bind_group,
                std::slice::from_ref(work),
                timestamps,
                first,
            );
            if i + 1 == before.len() {
                copy_dispatch(encoder, buffers);
            }
            slice(encoder);
        }
        for (i, work) in after.iter().enumerate() {
            let first = (before.len() + i) as u32;
            record_dispatches(
                encoder,
                &label,
                &bind_group,
                std::slice::from_ref(work),
                timestamps,
                first,
            );
            if i + 1 < after.len() {
                slice(encoder);
            }
        }
    }
}

/// Ends a slice of an extraction: submits what `encoder` holds, leaves a fresh encoder in its
/// place and waits for the GPU (see [`crate::render::surface::methods`]).
pub(crate) type Slicer<'a> = dyn FnMut(&mut wgpu::CommandEncoder) + 'a;

/// Copies the indirect dispatch over the active cells where the per-active passes read it.
fn copy_dispatch(encoder: &mut wgpu::CommandEncoder, buffers: &MeshBuffers) {
    encoder.copy_buffer_to_buffer(
        &buffers.indirect,
        ACTIVE_DISPATCH_OFFSET,
        &buffers.dispatch,
        0,
        DISPATCH_SIZE,
    );
}

/// Dispatches recorded by an extraction.
pub const EXTRACTION_PASSES: usize = 6;

/// How a pass is dispatched.
enum Dispatch<'a> {
    /// Workgroups (x, y).
    Direct([u32; 2]),
    /// From dispatch arguments in a buffer.
    Indirect(&'a wgpu::Buffer),
}

/// Records `work` in one compute pass, or, with `timestamps`, one pass per dispatch writing
/// queries 2 (first + i) and 2 (first + i) + 1 around the i-th.
fn record_dispatches(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    bind_group: &wgpu::BindGroup,
    work: &[(&wgpu::ComputePipeline, Dispatch<'_>)],
    timestamps: Option<&wgpu::QuerySet>,
    first: u32,
) {
    let begin = |encoder: &mut wgpu::CommandEncoder, writes| {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: writes,
        });
        pass.set_bind_group(1, bind_group, &[]);
        pass.forget_lifetime()
    };
    let dispatch = |pass: &mut wgpu::ComputePass<'_>, pipeline, how: &Dispatch<'_>| {
        pass.set_pipeline(pipeline);
        match how {
            Dispatch::Direct([x, y]) => pass.dispatch_workgroups(*x, *y, 1),
            Dispatch::Indirect(buffer) => pass.dispatch_workgroups_indirect(buffer, 0),
        }
    };
    match timestamps {
        None => {
            let mut pass = begin(encoder, None);
            for (pipeline, how) in work {
                dispatch(&mut pass, pipeline, how);
            }
        }
        Some(set) => {
            for (i, (pipeline, how)) in work.iter().enumerate() {
                let query = 2 * (first + i as u32);
                let mut pass = begin(
                    encoder,
                    Some(wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(query),
                        end_of_pass_write_index: Some(query + 1),
                    }),
                );
                dispatch(&mut pass, pipeline, how);
            }
        }
    }
}

/// Threads per workgroup and workgroups per row of the one-dimensional dispatches (keep in sync
/// with ACTIVE_WORKGROUP and ACTIVE_ROW in shaders/surface/extraction.wgsl).
const FLAT_WORKGROUP: u64 = 64;
const FLAT_ROW: u64 = 32768;

/// Workgroups (x, y) covering `threads` threads of a one-dimensional pass.
fn flat_workgroups(threads: u64) -> [u32; 2] {
    let groups = threads.div_ceil(FLAT_WORKGROUP);
    let x = groups.min(FLAT_ROW);
    [x as u32, groups.div_ceil(FLAT_ROW) as u32]
}
