//! [`SurfacePass`]: extraction and drawing of the Surface view, built once per device.

use std::sync::OnceLock;

use glam::Vec3;

use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::uniform_entry;
use crate::render::gpu::readback::{map_buffer, read_buffer};
use crate::render::gpu::target::COLOR_FORMAT;
use crate::render::gpu::timing::Timestamps;
use crate::render::grid::VoxelGrid;
use crate::render::points::depth_state;
use crate::render::shaders;
use crate::render::surface::background::{BackgroundExtractor, Job, share_grid};
use crate::render::surface::buffers::{
    COUNTERS_SIZE, INDEXED_ARGS_OFFSET, MAX_MAPPED_VERTICES, MeshBuffers, MeshVertex,
};
use crate::render::surface::cpu_mesh::CpuMesh;
use crate::render::surface::draw::SurfaceStyle;
use crate::render::surface::dual_contour::DualContourPass;
use crate::render::surface::extraction::EXTRACTION_PASSES;
use crate::render::surface::marching_tets::MarchingTetsPass;
use crate::render::surface::state::{CacheKey, ExtractedSurface, SurfaceState};
use crate::render::surface::{SurfaceCounts, SurfaceError, SurfaceMethod, SurfaceSettings};

/// The pipelines of both extraction methods.
pub(crate) struct Methods {
    pub(crate) marching_tets: MarchingTetsPass,
    pub(crate) dual_contour: DualContourPass,
}

impl Methods {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self {
            marching_tets: MarchingTetsPass::new(device),
            dual_contour: DualContourPass::new(device),
        }
    }
}

/// Extraction and drawing of the Surface view, built once per device.
pub struct SurfacePass {
    device: wgpu::Device,
    /// The methods of blocking extractions, built on first use (the window extracts on the
    /// background thread, which builds its own).
    methods: OnceLock<Methods>,
    /// The window's extraction thread, started by the first [`SurfacePass::prepare`] (None
    /// inside when the thread could not start: then prepare extracts in place).
    background: OnceLock<Option<BackgroundExtractor>>,
    pipeline: wgpu::RenderPipeline,
    style: wgpu::Buffer,
    style_bind_group: wgpu::BindGroup,
    initial_capacity: (u32, u32),
    /// Per-pass GPU timestamps of blocking extractions (benchmarks), when enabled.
    timing: Option<Timestamps>,
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
        let module = shaders::module(device, "surface_draw", &shaders::surface_draw());
        let style_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("surface::style_layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::FRAGMENT)],
        });
        let style = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("surface::style"),
            size: std::mem::size_of::<SurfaceStyle>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let style_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("surface::style_bind_group"),
            layout: &style_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: style.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("surface::draw_pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&style_layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x3],
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("surface::draw_pipeline"),
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
        Self {
            device: device.clone(),
            methods: OnceLock::new(),
            background: OnceLock::new(),
            pipeline,
            style,
            style_bind_group,
            initial_capacity: (vertices, indices),
            timing: None,
        }
    }

    /// Makes [`SurfacePass::extract_blocking`] time each pass with GPU timestamps, for
    /// [`SurfacePass::pass_times_ms`]; false (and nothing changes) when the device has no
    /// timestamp queries. Splits the extraction into one compute pass per dispatch.
    pub fn enable_pass_timing(&mut self, queue: &wgpu::Queue) -> bool {
        self.timing = Timestamps::new(
            &self.device,
            queue,
            "surface::pass_timestamps",
            TIMESTAMPS,
            wgpu::Features::TIMESTAMP_QUERY,
        );
        self.timing.is_some()
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
        let ticks = timing
            .read_ticks(&self.device)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        let names = match method {
            SurfaceMethod::MarchingTetrahedra => self.methods().marching_tets.pass_names(),
            SurfaceMethod::DualContouring => self.methods().dual_contour.pass_names(),
        };
        Ok(Some(
            names
                .iter()
                .zip(ticks.chunks_exact(2))
                .map(|(&name, t)| (name, timing.ms(t[0], t[1])))
                .collect(),
        ))
    }

    fn methods(&self) -> &Methods {
        self.methods.get_or_init(|| Methods::new(&self.device))
    }

    /// Interactive path: when the method, isovalue or grid changed, asks the background thread
    /// for the new surface (the last mesh is drawn until it is ready, and a newer request
    /// replaces one still waiting); installs a finished one. Never waits for the GPU. Call once
    /// per frame before the render pass.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        _encoder: &mut wgpu::CommandEncoder,
        surface: &ExtractedSurface,
        grid: Option<&VoxelGrid>,
        settings: &SurfaceSettings,
    ) {
        let style = SurfaceStyle {
            lit: u32::from(settings.lit),
            pad: [0; 3],
        };
        queue.write_buffer(&self.style, 0, bytemuck::bytes_of(&style));
        surface.install_finished();
        let Some(grid) = grid else {
            return;
        };
        let wanted = CacheKey::new(grid, settings);
        let job = {
            let mut state = surface.lock();
            let current = state.requested.as_ref().or(state.key.as_ref());
            if current == Some(&wanted) {
                return;
            }
            state.requested = Some(wanted.clone());
            let capacity = state.buffers.as_ref().map_or(self.initial_capacity, |b| {
                (b.vertex_capacity, b.index_capacity)
            });
            Job {
                key: wanted,
                grid: share_grid(grid),
                settings: *settings,
                spare: state.spare.take(),
                capacity,
                mailbox: surface.mailbox.clone(),
            }
        };
        let background = self.background.get_or_init(|| {
            BackgroundExtractor::spawn(self.device.clone(), queue.clone())
                .inspect_err(|e| log::warn!("no surface extraction thread: {e}"))
                .ok()
        });
        match background {
            Some(background) => background.submit(job),
            // No thread: extract here (waits), as before there was one.
            None => {
                crate::render::surface::background::run_job(
                    &self.device,
                    queue,
                    self.methods(),
                    job,
                );
                surface.install_finished();
            }
        }
    }

    /// Extracts the surface and waits for it, growing the buffers until it fits (headless
    /// rendering, export, tests, benchmarks). Afterwards [`SurfacePass::draw`] draws it and
    /// [`SurfacePass::read_mesh`] reads it.
    pub fn extract_blocking(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
        grid: &VoxelGrid,
        settings: &SurfaceSettings,
    ) -> Result<SurfaceCounts, SurfaceError> {
        let mut state = surface.lock();
        state.requested = None;
        extract_until_fits(
            false,
            &self.device,
            queue,
            self.methods(),
            self.initial_capacity,
            self.timing.as_ref(),
            &mut state,
            grid,
            settings,
        )
    }

    /// Reads the last extracted surface back to the CPU (waits for the GPU).
    pub fn read_mesh(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
    ) -> Result<CpuMesh, SurfaceError> {
        let state = surface.lock();
        let (Some(buffers), Some(counts)) = (&state.buffers, state.counts) else {
            return Err(SurfaceError::NotExtracted);
        };
        let read = |buffer: &wgpu::Buffer, bytes: u64| -> Result<Vec<u8>, SurfaceError> {
            read_buffer(&self.device, queue, "surface::mesh_readback", buffer, bytes)
                .map_err(|e| SurfaceError::Readback(e.to_string()))
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
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        surface: &ExtractedSurface,
    ) {
        let state = surface.lock();
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

/// The largest number of `element_size`-byte elements one buffer binding may hold.
fn element_limit(device: &wgpu::Device, element_size: u64) -> u64 {
    (storage_binding_limit(device) / element_size).min(u64::from(u32::MAX))
}

/// Grows the buffers to hold `counts`; an error when the device cannot.
fn grow(
    device: &wgpu::Device,
    state: &mut SurfaceState,
    counts: &SurfaceCounts,
) -> Result<(), SurfaceError> {
    let grow_to = |needed: u32, capacity: u32, what: &'static str, size: u64, max: u64| {
        if needed <= capacity {
            return Ok(capacity);
        }
        let limit = element_limit(device, size).min(max);
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
    state.buffers = Some(MeshBuffers::new(device, vertices, indices));
    state.key = None;
    Ok(())
}

/// Maps a MAP_READ buffer by polling the device without blocking it, a millisecond apart. A
/// blocking poll holds the device's fence while it waits, so every `queue.submit` of the
/// window's frames (which needs that fence) would wait for the whole extraction.
fn map_polling(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, SurfaceError> {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU8, Ordering};
    let state = Arc::new(AtomicU8::new(0));
    let callback_state = state.clone();
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, move |result| {
        callback_state.store(if result.is_ok() { 1 } else { 2 }, Ordering::Release);
    });
    loop {
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| SurfaceError::Readback(e.to_string()))?;
        match state.load(Ordering::Acquire) {
            0 => std::thread::sleep(std::time::Duration::from_millis(1)),
            1 => break,
            _ => return Err(SurfaceError::Readback("mapping the counters failed".into())),
        }
    }
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| SurfaceError::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// Extracts the surface into `state`'s buffers and waits for its size, growing the buffers and
/// extracting again until it fits (or cannot fit: then the error, with the counts kept).
/// `background`: waits by polling (see [`map_polling`]), so other threads can submit meanwhile.
#[allow(clippy::too_many_arguments)]
pub(crate) fn extract_until_fits(
    background: bool,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    methods: &Methods,
    initial_capacity: (u32, u32),
    timing: Option<&Timestamps>,
    state: &mut SurfaceState,
    grid: &VoxelGrid,
    settings: &SurfaceSettings,
) -> Result<SurfaceCounts, SurfaceError> {
    loop {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("surface::extract"),
        });
        let (v, i) = initial_capacity;
        let buffers = state
            .buffers
            .get_or_insert_with(|| MeshBuffers::new(device, v, i));
        let timestamps = timing.map(|t| &t.set);
        match settings.method {
            SurfaceMethod::MarchingTetrahedra => methods.marching_tets.record(
                device,
                queue,
                &mut encoder,
                grid,
                buffers,
                settings.iso_value,
                timestamps,
            ),
            SurfaceMethod::DualContouring => methods.dual_contour.record(
                device,
                queue,
                &mut encoder,
                grid,
                buffers,
                settings.iso_value,
                timestamps,
            ),
        }
        state.key = Some(CacheKey::new(grid, settings));
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("surface::counters_readback"),
            size: COUNTERS_SIZE,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_buffer_to_buffer(&buffers.counters, 0, &staging, 0, COUNTERS_SIZE);
        if let Some(timing) = timing {
            timing.resolve(&mut encoder, TIMESTAMPS);
        }
        let (vertex_capacity, index_capacity) = (buffers.vertex_capacity, buffers.index_capacity);
        queue.submit([encoder.finish()]);
        let bytes = if background {
            map_polling(device, &staging)?
        } else {
            map_buffer(device, &staging).map_err(|e| SurfaceError::Readback(e.to_string()))?
        };
        let raw: [u32; 4] = bytemuck::pod_read_unaligned(&bytes[..16]);
        let counts = SurfaceCounts {
            method: settings.method,
            vertices_needed: raw[0],
            indices_needed: raw[1],
            vertex_capacity,
            index_capacity,
        };
        state.counts = Some(counts);
        if counts.fits() {
            state.error = None;
            return Ok(counts);
        }
        if let Err(e) = grow(device, state, &counts) {
            // The truncated surface stays drawable, with the reason beside it.
            state.key = Some(CacheKey::new(grid, settings));
            state.error = Some(e.to_string());
            return Err(e);
        }
    }
}
