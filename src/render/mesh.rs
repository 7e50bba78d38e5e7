//! Surface view: the extracted isosurface, kept on the GPU and drawn lit and hp-coloured.
//!
//! Reads: a [`VoxelGrid`] (density, hp_mean). Writes: an indexed mesh in [`MeshBuffers`] (vertex
//! records [`MeshVertex`], an index buffer, the active-cell list, atomic counters and indirect
//! dispatch and draw arguments), then colour and depth of the render target.
//! [`SurfacePass`] owns the two extraction passes ([`MarchingTetsPass`], [`DualContourPass`]) and
//! the draw pipeline. Both first classify every cell and append only the cells that straddle the
//! isovalue to an active list, then run their expensive passes over those cells alone through
//! indirect dispatches; output is reserved in preallocated buffers with atomics and a one-thread
//! pass turns the counters into indirect draw arguments, so the interactive path never waits on
//! the GPU. The surface is re-extracted only when the method, isovalue or grid changes. The
//! counters keep counting past capacity; they are copied into a staging buffer that is mapped
//! without waiting and read a frame or two later, and when a surface needed more room the
//! buffers grow and the surface is extracted again (never silently truncated: see
//! [`SurfacePass::counts`]). Tests and export use [`SurfacePass::extract_blocking`] and
//! [`SurfacePass::read_mesh`], which do wait.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use glam::{UVec3, Vec3};
use thiserror::Error;

use crate::render::dual_contour::DualContourPass;
use crate::render::frame::FrameBinding;
use crate::render::grid::VoxelGrid;
use crate::render::marching_tets::MarchingTetsPass;
use crate::render::points::depth_state;
use crate::render::shaders;
use crate::render::target::{COLOR_FORMAT, map_buffer};

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
        let t = text
            .trim()
            .to_ascii_lowercase()
            .replace(['-', '_', ' '], "");
        match t.as_str() {
            "mt" | "marchingtetrahedra" | "marchingtets" => Some(Self::MarchingTetrahedra),
            "dc" | "dualcontouring" => Some(Self::DualContouring),
            _ => None,
        }
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

/// One mesh vertex. Keep in sync with `MeshVertex` in shaders/utils/iso_grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    /// Data space.
    pub position: [f32; 3],
    /// Mean hp of the surrounding voxels (density-weighted), [0, 1].
    pub hp: f32,
    /// Unit normal in data space, toward lower density.
    pub normal: [f32; 3],
    pub pad: f32,
}
const _: () = assert!(std::mem::size_of::<MeshVertex>() == 32);

/// Keep in sync with `IsoParams` in shaders/utils/iso_grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct IsoParams {
    pub dims: [u32; 3],
    pub vertex_capacity: u32,
    pub box_min: [f32; 3],
    pub iso_value: f32,
    pub voxel_size: [f32; 3],
    pub index_capacity: u32,
    pub active_capacity: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<IsoParams>() == 64);

/// Keep in sync with `MeshStyle` in shaders/mesh.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct MeshStyle {
    lit: u32,
    pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<MeshStyle>() == 16);

/// Bytes of the counters buffer: vertices, indices, active cells (atomics) and padding.
const COUNTERS_SIZE: u64 = 16;
/// Bytes of the indirect buffer: DrawIndirectArgs at 0, DrawIndexedIndirectArgs at 16,
/// DispatchIndirectArgs over the active cells at 36.
const INDIRECT_SIZE: u64 = 48;
const INDEXED_ARGS_OFFSET: u64 = 16;
/// Where `dispatch_active` writes the dispatch over the active cells; it is copied into
/// [`MeshBuffers::dispatch`] because a buffer bound as storage cannot also be a dispatch's
/// indirect argument.
const ACTIVE_DISPATCH_OFFSET: u64 = 36;
const DISPATCH_SIZE: u64 = 12;
/// Marching tetrahedra's cell map packs a first vertex index below this (keep in sync with
/// MAX_MAPPED_VERTICES in shaders/marching_tets.wgsl).
const MAX_MAPPED_VERTICES: u64 = 1 << 25;
/// Bytes of one active-cell entry: cell, corner mask, first vertex, first index.
const ACTIVE_ENTRY_SIZE: u64 = 16;

/// The warm-to-cool gradient of the mesh colour, as in shaders/mesh.wgsl (keep in sync):
/// gamma-encoded RGB for `hp` (0 percussive, warm; 1 harmonic, cool).
pub fn warm_cool(hp: f32) -> [f32; 3] {
    const WARM: [f32; 3] = [0.851, 0.325, 0.192];
    const NEUTRAL: [f32; 3] = [0.914, 0.882, 0.827];
    const COOL: [f32; 3] = [0.231, 0.443, 0.780];
    let t = hp.clamp(0.0, 1.0);
    let (a, b, f) = if t < 0.5 {
        (WARM, NEUTRAL, t * 2.0)
    } else {
        (NEUTRAL, COOL, t * 2.0 - 1.0)
    };
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * f)
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
}

/// An extracted surface on the CPU (tests, export): indexed triangles in data space.
#[derive(Clone, Debug, Default)]
pub struct CpuMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub hp: Vec<f32>,
    pub indices: Vec<u32>,
}

impl CpuMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let i = &self.indices[t * 3..t * 3 + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }

    /// Total area, in data-space units.
    pub fn area(&self) -> f64 {
        (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                f64::from((b - a).cross(c - a).length()) * 0.5
            })
            .sum()
    }

    /// The same surface with vertices at bit-identical positions merged (crossings that land
    /// exactly on a shared grid sample), and triangles that collapse to a line or point dropped.
    pub fn welded(&self) -> CpuMesh {
        let mut map = std::collections::HashMap::new();
        let mut out = CpuMesh::default();
        let mut remap = Vec::with_capacity(self.positions.len());
        for (i, p) in self.positions.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let index = *map.entry(key).or_insert_with(|| {
                out.positions.push(*p);
                out.normals.push(self.normals[i]);
                out.hp.push(self.hp[i]);
                (out.positions.len() - 1) as u32
            });
            remap.push(index);
        }
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| remap[tri[k] as usize]);
            if a != b && b != c && a != c {
                out.indices.extend_from_slice(&[a, b, c]);
            }
        }
        out
    }
}

/// The GPU buffers one surface lives in.
pub struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub counters: wgpu::Buffer,
    pub indirect: wgpu::Buffer,
    pub params: wgpu::Buffer,
    /// DispatchIndirectArgs over the active cells.
    pub dispatch: wgpu::Buffer,
    /// The cells that straddle the isovalue (16-byte entries), [`MeshBuffers::active_capacity`]
    /// of them. A complete surface never has more active cells than marching tetrahedra has
    /// triangles or dual contouring has vertices, so the capacities bound it.
    pub active: wgpu::Buffer,
    /// Per cell: what the method keeps of an active cell (its active index for dual
    /// contouring, its first vertex and crossing edges for marching tetrahedra); grown to the
    /// grid on demand.
    pub cell_map: Option<wgpu::Buffer>,
    /// One bit per (padded) sample: inside or not; grown to the grid on demand.
    pub inside_bits: Option<wgpu::Buffer>,
    pub vertex_capacity: u32,
    pub index_capacity: u32,
    pub active_capacity: u32,
}

impl MeshBuffers {
    pub fn new(device: &wgpu::Device, vertex_capacity: u32, index_capacity: u32) -> Self {
        let vertex_capacity = vertex_capacity.max(3);
        let index_capacity = index_capacity.max(6);
        let active_capacity = vertex_capacity.max(index_capacity / 3);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let make = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            vertices: make(
                "surface::vertex_buffer",
                u64::from(vertex_capacity) * std::mem::size_of::<MeshVertex>() as u64,
                storage | wgpu::BufferUsages::VERTEX,
            ),
            indices: make(
                "surface::index_buffer",
                u64::from(index_capacity) * 4,
                storage | wgpu::BufferUsages::INDEX,
            ),
            counters: make(
                "surface::counters",
                COUNTERS_SIZE,
                storage | wgpu::BufferUsages::COPY_DST,
            ),
            indirect: make(
                "surface::indirect_args",
                INDIRECT_SIZE,
                storage | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            ),
            dispatch: make(
                "surface::dispatch_args",
                16,
                wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            ),
            params: make(
                "surface::params",
                std::mem::size_of::<IsoParams>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            active: make(
                "surface::active_cells",
                u64::from(active_capacity) * ACTIVE_ENTRY_SIZE,
                storage,
            ),
            cell_map: None,
            inside_bits: None,
            vertex_capacity,
            index_capacity,
            active_capacity,
        }
    }

    /// Makes sure `cell_map` has an entry for every cell of `grid` ((dims + 1)^3) and
    /// `inside_bits` a bit for every padded sample.
    pub(crate) fn ensure_grid_buffers(&mut self, device: &wgpu::Device, grid: &VoxelGrid) {
        let grow = |buffer: &mut Option<wgpu::Buffer>, label: &str, needed: u64| {
            if buffer.as_ref().is_none_or(|b| b.size() < needed) {
                *buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: needed,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                }));
            }
        };
        let cells = (grid.dims.as_u64vec3() + glam::U64Vec3::ONE).element_product();
        grow(&mut self.cell_map, "surface::cell_map", cells * 4);
        let [words, rows] = bit_threads(grid.dims, 2);
        grow(
            &mut self.inside_bits,
            "surface::inside_bits",
            words * rows * 4,
        );
    }

    /// Writes the extraction parameters for `grid` at `iso_value`.
    pub(crate) fn write_params(&self, queue: &wgpu::Queue, grid: &VoxelGrid, iso_value: f32) {
        let params = IsoParams {
            dims: grid.dims.to_array(),
            vertex_capacity: self.vertex_capacity,
            box_min: grid.box_min.to_array(),
            iso_value,
            voxel_size: grid.voxel_size().to_array(),
            index_capacity: self.index_capacity,
            active_capacity: self.active_capacity,
            pad: [0; 3],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }
}

/// Bind group layout shared by the extraction passes (group 1, bindings 0..=9 of
/// shaders/utils/iso_grid.wgsl), plus `extra` read-only storage bindings from 10 on.
fn extraction_layout(device: &wgpu::Device, label: &str, extra: u32) -> wgpu::BindGroupLayout {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        },
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
    [
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
    ]
    .into_iter()
    .enumerate()
    .map(|(i, buffer)| wgpu::BindGroupEntry {
        binding: i as u32,
        resource: buffer.as_entire_binding(),
    })
    .collect()
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
/// shaders/utils/iso_grid.wgsl). Both methods share this skeleton: pack the inside bits, list
/// the active cells, then two passes over the active cells only and one that writes the draw
/// arguments.
pub(crate) struct ExtractionPipelines {
    /// The method's name, the prefix of every label ("marching_tets").
    name: &'static str,
    /// The method's layout of group 1 (see [`extraction_layout`]).
    layout: wgpu::BindGroupLayout,
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
    /// `inside_bits_pass`, `classify`, `dispatch_active`, the two `per_active` ones and
    /// `finalize`; `extra` bindings from 10 on belong to the method.
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
        record_dispatches(encoder, &label, &bind_group, &before, timestamps, 0);
        encoder.copy_buffer_to_buffer(
            &buffers.indirect,
            ACTIVE_DISPATCH_OFFSET,
            &buffers.dispatch,
            0,
            DISPATCH_SIZE,
        );
        record_dispatches(encoder, &label, &bind_group, &after, timestamps, 3);
    }
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
/// with ACTIVE_WORKGROUP and ACTIVE_ROW in shaders/utils/iso_grid.wgsl).
const FLAT_WORKGROUP: u64 = 64;
const FLAT_ROW: u64 = 32768;

/// Words of 32 along x and rows (y, z) of a grid padded to dims + `pad` on each axis.
fn bit_threads(dims: UVec3, pad: u32) -> [u64; 2] {
    let side = (dims + UVec3::splat(pad)).as_u64vec3();
    let words = (u64::from(dims.x) + 2).div_ceil(32);
    [words, side.y * side.z]
}

/// Workgroups (x, y) covering `threads` threads of a one-dimensional pass.
fn flat_workgroups(threads: u64) -> [u32; 2] {
    let groups = threads.div_ceil(FLAT_WORKGROUP);
    let x = groups.min(FLAT_ROW);
    [x as u32, groups.div_ceil(FLAT_ROW) as u32]
}

/// Identifies the extracted surface: a change re-extracts it.
#[derive(Clone, Debug, PartialEq)]
struct CacheKey {
    method: SurfaceMethod,
    iso_bits: u32,
    density: wgpu::Buffer,
    hp_mean: wgpu::Buffer,
    dims: UVec3,
    box_bits: [u32; 6],
}

impl CacheKey {
    fn new(grid: &VoxelGrid, settings: &SurfaceSettings) -> Self {
        let (a, b) = (grid.box_min, grid.box_max);
        Self {
            method: settings.method,
            iso_bits: settings.iso_value.to_bits(),
            density: grid.density.clone(),
            hp_mean: grid.hp_mean.clone(),
            dims: grid.dims,
            box_bits: [a.x, a.y, a.z, b.x, b.y, b.z].map(f32::to_bits),
        }
    }
}

const MAP_PENDING: u8 = 0;
const MAP_DONE: u8 = 1;
const MAP_FAILED: u8 = 2;

/// Where the counters' read-back stands.
enum Readback {
    Idle,
    /// A copy into the staging buffer was recorded; it is mapped on the next frame, after the
    /// frame that holds the copy has been submitted.
    Copied {
        generation: u64,
    },
    Mapping {
        generation: u64,
        flag: Arc<AtomicU8>,
    },
}

struct SurfaceState {
    buffers: Option<MeshBuffers>,
    key: Option<CacheKey>,
    /// Counts extractions; a read-back only speaks for the extraction it copied.
    generation: u64,
    counts_unchecked: bool,
    readback: Readback,
    staging: wgpu::Buffer,
    counts: Option<SurfaceCounts>,
    error: Option<String>,
}

/// Extraction and drawing of the Surface view, built once per device.
pub struct SurfacePass {
    device: wgpu::Device,
    pub marching_tets: MarchingTetsPass,
    pub dual_contour: DualContourPass,
    pipeline: wgpu::RenderPipeline,
    style: wgpu::Buffer,
    style_bind_group: wgpu::BindGroup,
    initial_capacity: (u32, u32),
    state: Mutex<SurfaceState>,
    /// Per-pass GPU timestamps of blocking extractions (benchmarks), when enabled.
    timing: Option<PassTiming>,
}

/// Timestamp queries around each extraction pass, resolved and copied for reading.
struct PassTiming {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
}

const TIMESTAMPS: u32 = 2 * EXTRACTION_PASSES as u32;

impl SurfacePass {
    /// Initial room: 1 Mi vertices (32 MiB) and 3 Mi indices; buffers grow as surfaces need.
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        Self::with_capacity(device, frame, 1 << 20, 3 << 20)
    }

    /// As [`SurfacePass::new`] with the given initial capacities (tests use small ones).
    pub fn with_capacity(
        device: &wgpu::Device,
        frame: &FrameBinding,
        vertices: u32,
        indices: u32,
    ) -> Self {
        let module = shaders::module(device, "mesh", &shaders::mesh());
        let style_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mesh::style_layout"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let style = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mesh::style"),
            size: std::mem::size_of::<MeshStyle>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let style_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mesh::style_bind_group"),
            layout: &style_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: style.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&style_layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x3],
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mesh::pipeline"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(vertex_layout)],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_state(true)),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("surface::counters_staging"),
            size: COUNTERS_SIZE,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Self {
            device: device.clone(),
            marching_tets: MarchingTetsPass::new(device),
            dual_contour: DualContourPass::new(device),
            pipeline,
            style,
            style_bind_group,
            initial_capacity: (vertices, indices),
            state: Mutex::new(SurfaceState {
                buffers: None,
                key: None,
                generation: 0,
                counts_unchecked: false,
                readback: Readback::Idle,
                staging,
                counts: None,
                error: None,
            }),
            timing: None,
        }
    }

    /// Makes [`SurfacePass::extract_blocking`] time each pass with GPU timestamps, for
    /// [`SurfacePass::pass_times_ms`]; false (and nothing changes) when the device has no
    /// timestamp queries. Splits the extraction into one compute pass per dispatch.
    pub fn enable_pass_timing(&mut self, queue: &wgpu::Queue) -> bool {
        if !self
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            return false;
        }
        let buffer = |label, usage| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(TIMESTAMPS) * 8,
                usage,
                mapped_at_creation: false,
            })
        };
        self.timing = Some(PassTiming {
            set: self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("surface::pass_timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: TIMESTAMPS,
            }),
            resolve: buffer(
                "surface::pass_timestamps_resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "surface::pass_timestamps_read",
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            ),
            period: f64::from(queue.get_timestamp_period()),
        });
        true
    }

    /// The GPU time of each pass of the last blocking extraction, in milliseconds, by name
    /// (None unless [`SurfacePass::enable_pass_timing`] succeeded).
    pub fn pass_times_ms(
        &self,
        method: SurfaceMethod,
    ) -> Result<Option<Vec<(&'static str, f64)>>, SurfaceError> {
        let Some(timing) = &self.timing else {
            return Ok(None);
        };
        let bytes = map_buffer(&self.device, &timing.read)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
        let names = match method {
            SurfaceMethod::MarchingTetrahedra => self.marching_tets.pass_names(),
            SurfaceMethod::DualContouring => self.dual_contour.pass_names(),
        };
        Ok(Some(
            names
                .iter()
                .zip(ticks.chunks_exact(2))
                .map(|(&name, t)| (name, t[1].wrapping_sub(t[0]) as f64 * timing.period / 1e6))
                .collect(),
        ))
    }

    fn lock(&self) -> MutexGuard<'_, SurfaceState> {
        // A panic elsewhere while holding the lock leaves plain data; carry on with it.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The counts of the last extraction whose read-back arrived (None before the first).
    pub fn counts(&self) -> Option<SurfaceCounts> {
        self.lock().counts
    }

    /// Why the surface is incomplete, when it is (it needs more room than the GPU has).
    pub fn error(&self) -> Option<String> {
        self.lock().error.clone()
    }

    /// True while a read-back or a re-extraction is pending: the window should draw again.
    pub fn needs_another_frame(&self) -> bool {
        let state = self.lock();
        state.key.is_none() || state.counts_unchecked || !matches!(state.readback, Readback::Idle)
    }

    /// The largest number of `element_size`-byte elements one buffer binding may hold.
    fn element_limit(&self, element_size: u64) -> u64 {
        let limits = self.device.limits();
        let bytes = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        (bytes / element_size).min(u64::from(u32::MAX))
    }

    /// Grows the buffers to hold `counts`; an error when the device cannot.
    fn grow(&self, state: &mut SurfaceState, counts: &SurfaceCounts) -> Result<(), SurfaceError> {
        let grow_to = |needed: u32, capacity: u32, what: &'static str, size: u64, max: u64| {
            if needed <= capacity {
                return Ok(capacity);
            }
            let limit = self.element_limit(size).min(max);
            let wanted = u64::from(needed).next_power_of_two().min(limit);
            if wanted < u64::from(needed) {
                return Err(SurfaceError::TooLarge {
                    what,
                    needed: u64::from(needed),
                    limit,
                });
            }
            Ok(wanted as u32)
        };
        // Marching tetrahedra's cell map cannot address more vertices.
        let max_vertices = match counts.method {
            SurfaceMethod::MarchingTetrahedra => MAX_MAPPED_VERTICES,
            SurfaceMethod::DualContouring => u64::MAX,
        };
        let vertices = grow_to(
            counts.vertices_needed,
            counts.vertex_capacity,
            "vertices",
            std::mem::size_of::<MeshVertex>() as u64,
            max_vertices,
        )?;
        let indices = grow_to(
            counts.indices_needed,
            counts.index_capacity,
            "indices",
            4,
            u64::MAX,
        )?;
        log::info!("surface buffers grow to {vertices} vertices, {indices} indices");
        state.buffers = Some(MeshBuffers::new(&self.device, vertices, indices));
        state.key = None;
        Ok(())
    }

    fn record_extraction(
        &self,
        state: &mut SurfaceState,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        grid: &VoxelGrid,
        settings: &SurfaceSettings,
    ) {
        let (v, i) = self.initial_capacity;
        let buffers = state
            .buffers
            .get_or_insert_with(|| MeshBuffers::new(&self.device, v, i));
        let timestamps = self.timing.as_ref().map(|t| &t.set);
        match settings.method {
            SurfaceMethod::MarchingTetrahedra => self.marching_tets.record(
                &self.device,
                queue,
                encoder,
                grid,
                buffers,
                settings.iso_value,
                timestamps,
            ),
            SurfaceMethod::DualContouring => self.dual_contour.record(
                &self.device,
                queue,
                encoder,
                grid,
                buffers,
                settings.iso_value,
                timestamps,
            ),
        }
        state.key = Some(CacheKey::new(grid, settings));
        state.generation += 1;
        state.counts_unchecked = true;
    }

    /// Reads a finished counters read-back, if one has arrived, and grows the buffers when the
    /// surface did not fit. Never waits.
    fn poll_counts(&self, state: &mut SurfaceState) {
        match &state.readback {
            Readback::Idle => return,
            Readback::Copied { generation } => {
                let generation = *generation;
                let flag = Arc::new(AtomicU8::new(MAP_PENDING));
                let callback_flag = flag.clone();
                state
                    .staging
                    .slice(..)
                    .map_async(wgpu::MapMode::Read, move |result| {
                        let value = if result.is_ok() { MAP_DONE } else { MAP_FAILED };
                        callback_flag.store(value, Ordering::Release);
                    });
                state.readback = Readback::Mapping { generation, flag };
            }
            Readback::Mapping { .. } => {}
        }
        let _ = self.device.poll(wgpu::PollType::Poll);
        let Readback::Mapping { generation, flag } = &state.readback else {
            return;
        };
        let generation = *generation;
        let raw = match flag.load(Ordering::Acquire) {
            MAP_PENDING => return,
            MAP_FAILED => None,
            _ => state
                .staging
                .slice(..)
                .get_mapped_range()
                .ok()
                .map(|bytes| bytemuck::pod_read_unaligned::<[u32; 4]>(&bytes[..16])),
        };
        if raw.is_some() {
            state.staging.unmap();
        }
        state.readback = Readback::Idle;
        let Some(raw) = raw else {
            // Try again on a later frame.
            state.counts_unchecked = true;
            return;
        };
        if generation != state.generation {
            return;
        }
        let (Some(buffers), Some(key)) = (&state.buffers, &state.key) else {
            return;
        };
        let counts = SurfaceCounts {
            method: key.method,
            vertices_needed: raw[0],
            indices_needed: raw[1],
            vertex_capacity: buffers.vertex_capacity,
            index_capacity: buffers.index_capacity,
        };
        state.counts = Some(counts);
        state.error = None;
        if !counts.fits()
            && let Err(e) = self.grow(state, &counts)
        {
            log::warn!("{e}");
            state.error = Some(e.to_string());
        }
    }

    /// Interactive path: records the extraction when the method, isovalue or grid changed, and
    /// the non-blocking read-back of its size. Call once per frame before the render pass.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        grid: Option<&VoxelGrid>,
        settings: &SurfaceSettings,
    ) {
        let style = MeshStyle {
            lit: u32::from(settings.lit),
            pad: [0; 3],
        };
        queue.write_buffer(&self.style, 0, bytemuck::bytes_of(&style));
        let mut state = self.lock();
        self.poll_counts(&mut state);
        let Some(grid) = grid else {
            return;
        };
        if state.key.as_ref() != Some(&CacheKey::new(grid, settings)) {
            self.record_extraction(&mut state, queue, encoder, grid, settings);
        }
        if state.counts_unchecked
            && matches!(state.readback, Readback::Idle)
            && let Some(buffers) = &state.buffers
        {
            encoder.copy_buffer_to_buffer(&buffers.counters, 0, &state.staging, 0, COUNTERS_SIZE);
            state.readback = Readback::Copied {
                generation: state.generation,
            };
            state.counts_unchecked = false;
        }
    }

    /// Extracts the surface and waits for it, growing the buffers until it fits (headless
    /// rendering, export, tests, benchmarks). Afterwards [`SurfacePass::draw`] draws it and
    /// [`SurfacePass::read_mesh`] reads it.
    pub fn extract_blocking(
        &self,
        queue: &wgpu::Queue,
        grid: &VoxelGrid,
        settings: &SurfaceSettings,
    ) -> Result<SurfaceCounts, SurfaceError> {
        let mut state = self.lock();
        loop {
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("surface::extract_blocking"),
                });
            self.record_extraction(&mut state, queue, &mut encoder, grid, settings);
            state.counts_unchecked = false;
            let Some(buffers) = &state.buffers else {
                return Err(SurfaceError::NotExtracted);
            };
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("surface::counters_readback"),
                size: COUNTERS_SIZE,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            encoder.copy_buffer_to_buffer(&buffers.counters, 0, &staging, 0, COUNTERS_SIZE);
            if let Some(timing) = &self.timing {
                encoder.resolve_query_set(&timing.set, 0..TIMESTAMPS, &timing.resolve, 0);
                encoder.copy_buffer_to_buffer(&timing.resolve, 0, &timing.read, 0, None);
            }
            queue.submit([encoder.finish()]);
            let bytes = map_buffer(&self.device, &staging)
                .map_err(|e| SurfaceError::Readback(e.to_string()))?;
            let raw: [u32; 4] = bytemuck::pod_read_unaligned(&bytes[..16]);
            let counts = SurfaceCounts {
                method: settings.method,
                vertices_needed: raw[0],
                indices_needed: raw[1],
                vertex_capacity: buffers.vertex_capacity,
                index_capacity: buffers.index_capacity,
            };
            state.counts = Some(counts);
            if counts.fits() {
                state.error = None;
                return Ok(counts);
            }
            if let Err(e) = self.grow(&mut state, &counts) {
                state.error = Some(e.to_string());
                return Err(e);
            }
        }
    }

    /// Reads the last extracted surface back to the CPU (waits for the GPU).
    pub fn read_mesh(&self, queue: &wgpu::Queue) -> Result<CpuMesh, SurfaceError> {
        let state = self.lock();
        let (Some(buffers), Some(counts)) = (&state.buffers, state.counts) else {
            return Err(SurfaceError::NotExtracted);
        };
        let read = |buffer: &wgpu::Buffer, bytes: u64| -> Result<Vec<u8>, SurfaceError> {
            if bytes == 0 {
                return Ok(Vec::new());
            }
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("surface::mesh_readback"),
                size: bytes,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("surface::mesh_readback"),
                });
            encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
            queue.submit([encoder.finish()]);
            map_buffer(&self.device, &staging).map_err(|e| SurfaceError::Readback(e.to_string()))
        };
        let vertex_count = counts.vertices_needed.min(buffers.vertex_capacity);
        let vertex_bytes = read(
            &buffers.vertices,
            u64::from(vertex_count) * std::mem::size_of::<MeshVertex>() as u64,
        )?;
        let vertices: Vec<MeshVertex> = bytemuck::pod_collect_to_vec(&vertex_bytes);
        // Whole triangles (marching tetrahedra) or quads (dual contouring) only.
        let whole = match counts.method {
            SurfaceMethod::MarchingTetrahedra => 3,
            SurfaceMethod::DualContouring => 6,
        };
        let count = counts
            .indices_needed
            .min(buffers.index_capacity - buffers.index_capacity % whole);
        let bytes = read(&buffers.indices, u64::from(count) * 4)?;
        let indices = bytemuck::pod_collect_to_vec(&bytes);
        Ok(CpuMesh {
            positions: vertices.iter().map(|v| Vec3::from(v.position)).collect(),
            normals: vertices.iter().map(|v| Vec3::from(v.normal)).collect(),
            hp: vertices.iter().map(|v| v.hp).collect(),
            indices,
        })
    }

    /// Draws the extracted surface with the indirect arguments the GPU wrote.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &FrameBinding) {
        let state = self.lock();
        let (Some(buffers), Some(_)) = (&state.buffers, &state.key) else {
            return;
        };
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_bind_group(1, &self.style_bind_group, &[]);
        pass.set_vertex_buffer(0, buffers.vertices.slice(..));
        pass.set_index_buffer(buffers.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed_indirect(&buffers.indirect, INDEXED_ARGS_OFFSET);
    }
}

/// A song-like analytic field for benchmarks, golden images and the scikit-image comparison:
/// (density, hp) on a `dims` grid over [-1, 1]^3, in [`VoxelGrid`] order (x fastest).
/// x is time: a 4/4 pulse of percussive hits (hp near 0) over sustained harmonic partials
/// (hp near 1); y is log amplitude: energy sits on a ridge that falls with frequency and rises
/// on each hit; z is frequency: partials make stripes. bench/bench_surface.py reads the same
/// field from the .npy file `loudscape bench --fields-dir` writes.
pub fn song_like_field(dims: UVec3) -> (Vec<f32>, Vec<f32>) {
    let n = (dims.x * dims.y * dims.z) as usize;
    let mut density = Vec::with_capacity(n);
    let mut hp = Vec::with_capacity(n);
    let size = Vec3::splat(2.0) / dims.as_vec3();
    for k in 0..dims.z {
        for j in 0..dims.y {
            for i in 0..dims.x {
                let p = Vec3::new(-1.0, -1.0, -1.0) + (UVec3::new(i, j, k).as_vec3() + 0.5) * size;
                let (d, h) = song_like_sample(p);
                density.push(d);
                hp.push(h);
            }
        }
    }
    (density, hp)
}

fn song_like_sample(p: Vec3) -> (f32, f32) {
    let (x, y, z) = (p.x, p.y, p.z);
    let freq = (z + 1.0) * 0.5;
    // Percussive hits: 8 beats across the song, each decaying quickly.
    let beat_phase = ((x + 1.0) * 4.0).fract();
    let hit = (-beat_phase * 9.0).exp();
    // Sections: a quieter intro and a louder chorus in the second half.
    let section = 0.75 + 0.25 * (1.0 / (1.0 + (-(x - 0.1) * 8.0).exp()));
    // The spectral ridge: loud lows, quieter highs; hits lift and widen it.
    let ridge = 0.25 - 0.9 * freq + 0.35 * hit;
    let width = 0.16 + 0.12 * hit;
    let level = (-((y - ridge) / width).powi(2)).exp();
    // Harmonic partials: stripes in frequency, strongest in the lows and mids.
    let partials = 0.6 + 0.4 * (z * 28.0).cos().powi(2) * (1.0 - freq);
    let density = (level * section * (partials * (1.0 - 0.5 * hit) + 0.8 * hit)).clamp(0.0, 1.0);
    let hp = (0.85 - 0.8 * hit + 0.1 * (z * 28.0).cos()).clamp(0.0, 1.0);
    (density, hp)
}
