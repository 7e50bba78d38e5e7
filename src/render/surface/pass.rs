//! [`SurfacePass`]: extraction and drawing of the Surface view, built once per device.

use std::sync::{Mutex, OnceLock};

use glam::Vec3;

use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::uniform_entry;
use crate::render::gpu::pipeline::{DrawPipeline, depth_opaque, opaque_target, primitives};
use crate::render::gpu::readback::read_buffer;
use crate::render::gpu::timing::Timestamps;
use crate::render::grid::VoxelGrid;
use crate::render::shaders;
use crate::render::surface::background::{BackgroundExtractor, CoarseJob, Job, Worker, share_grid};
use crate::render::surface::buffers::{INDEXED_ARGS_OFFSET, MeshVertex};
use crate::render::surface::cpu::{Phases, SurfaceEngine};
use crate::render::surface::cpu_mesh::CpuMesh;
use crate::render::surface::draw::SurfaceStyle;
use crate::render::surface::driver::{Methods, Submit, TIMESTAMPS, extract_until_fits};
use crate::render::surface::lod::{Level, SurfaceDetail};
use crate::render::surface::state::{CacheKey, ExtractedSurface};
use crate::render::surface::{SurfaceCounts, SurfaceError, SurfaceMethod, SurfaceSettings};

/// Extraction and drawing of the Surface view, built once per device.
pub struct SurfacePass {
    device: wgpu::Device,
    /// The methods of blocking extractions, built on first use (the window extracts on the
    /// background thread, which builds its own).
    methods: OnceLock<Methods>,
    /// The window's extraction thread, started by the first [`SurfacePass::prepare`] (None
    /// inside when the thread could not start: then prepare extracts in place).
    background: OnceLock<Option<BackgroundExtractor>>,
    /// What [`SurfacePass::prepare`] extracts with in place when the thread could not start.
    fallback: Mutex<Option<Worker>>,
    pipeline: wgpu::RenderPipeline,
    style: wgpu::Buffer,
    style_bind_group: wgpu::BindGroup,
    initial_capacity: (u32, u32),
    /// Per-pass GPU timestamps of blocking extractions (benchmarks), when enabled.
    timing: Option<Timestamps>,
    /// Where surfaces are extracted ([`SurfaceEngine::preferred`] for the device unless set).
    engine: SurfaceEngine,
}

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
        let pipeline = DrawPipeline {
            label: "surface::draw_pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[Some(vertex_layout)],
            target: opaque_target(),
            primitive: primitives(wgpu::PrimitiveTopology::TriangleList),
            depth: depth_opaque(),
        }
        .build(device);
        Self {
            device: device.clone(),
            methods: OnceLock::new(),
            background: OnceLock::new(),
            fallback: Mutex::new(None),
            pipeline,
            style,
            style_bind_group,
            initial_capacity: (vertices, indices),
            timing: None,
            engine: SurfaceEngine::preferred(device),
        }
    }

    /// The same pass extracting with `engine` (tests and benchmarks compare the two).
    pub fn with_engine(mut self, engine: SurfaceEngine) -> Self {
        self.engine = engine;
        self.methods = OnceLock::new();
        self.background = OnceLock::new();
        *self.fallback.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        self
    }

    /// Where this pass extracts surfaces.
    pub fn engine(&self) -> SurfaceEngine {
        self.engine
    }

    /// The phases of the last blocking extraction on the CPU engine (empty before one).
    pub fn cpu_phases(&self) -> Phases {
        self.methods()
            .cpu_phases
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
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
        self.methods
            .get_or_init(|| Methods::new(&self.device, self.engine))
    }

    /// Interactive path: when the method, isovalue or grid changed, asks the background thread
    /// for the new surface (the last mesh is drawn until it is ready, and a newer request
    /// replaces one still waiting); installs a finished one. Never waits for the GPU. Call once
    /// per frame before the render pass.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
        grid: Option<&VoxelGrid>,
        settings: &SurfaceSettings,
    ) {
        self.write_style(queue, settings);
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
            // The coarse grid has a quarter of the cells per level, and its surface about a
            // quarter of the triangles: start there, then keep the room it needed.
            let (v, i) = self.initial_capacity;
            let shrink = 2 * crate::render::surface::lod::COARSE_LEVELS;
            let coarse_capacity = state
                .coarse
                .as_ref()
                .map_or((v >> shrink, i >> shrink), |c| {
                    (c.buffers.vertex_capacity, c.buffers.index_capacity)
                });
            Job {
                key: wanted,
                grid: share_grid(grid),
                settings: *settings,
                spare: state.spare.take(),
                capacity,
                mailbox: surface.mailbox.clone(),
                coarse: Some(CoarseJob {
                    spare: state.coarse_spare.take(),
                    capacity: coarse_capacity,
                }),
            }
        };
        let background = self.background.get_or_init(|| {
            BackgroundExtractor::spawn(self.device.clone(), queue.clone(), self.engine)
                .inspect_err(|e| log::warn!("no surface extraction thread: {e}"))
                .ok()
        });
        match background {
            Some(background) => background.submit(job),
            // No thread: extract here (waits), as before there was one.
            None => {
                let mut fallback = self.fallback.lock().unwrap_or_else(|e| e.into_inner());
                let worker = fallback.get_or_insert_with(|| Worker::new(&self.device, self.engine));
                crate::render::surface::background::run_job(
                    &self.device,
                    queue,
                    worker,
                    job,
                    &|| false,
                );
                surface.install_finished();
            }
        }
    }

    /// Writes the draw's style (lit or flat) from `settings`: [`SurfacePass::prepare`] does,
    /// and whoever draws with [`SurfacePass::draw_mesh`] calls it before the render pass.
    pub fn write_style(&self, queue: &wgpu::Queue, settings: &SurfaceSettings) {
        let style = SurfaceStyle {
            lit: u32::from(settings.lit),
            pad: [0; 3],
        };
        queue.write_buffer(&self.style, 0, bytemuck::bytes_of(&style));
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
            Submit::Blocking,
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

    /// As [`SurfacePass::extract_blocking`], but the way the window's worker thread extracts:
    /// one submission per pass, each waited for by polling, so other submissions to the queue
    /// run between them. Returns the counts and how many submissions it took (tests compare
    /// the mesh with [`SurfacePass::extract_blocking`]'s).
    pub fn extract_in_slices(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
        grid: &VoxelGrid,
        settings: &SurfaceSettings,
    ) -> Result<(SurfaceCounts, usize), SurfaceError> {
        let mut state = surface.lock();
        state.requested = None;
        let mut submissions = 0;
        let counts = extract_until_fits(
            Submit::Worker {
                sliced: true,
                submissions: &mut submissions,
                superseded: &|| false,
            },
            &self.device,
            queue,
            self.methods(),
            self.initial_capacity,
            None,
            &mut state,
            grid,
            settings,
        )?;
        Ok((counts, submissions))
    }

    /// Reads the last extracted surface back to the CPU (waits for the GPU).
    pub fn read_mesh(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
    ) -> Result<CpuMesh, SurfaceError> {
        self.read_level(queue, surface, Level::Full)
    }

    /// Reads one of the surface's meshes back to the CPU: the full one ([`SurfacePass::read_mesh`])
    /// or the coarse one of the level of detail (waits for the GPU).
    pub fn read_level(
        &self,
        queue: &wgpu::Queue,
        surface: &ExtractedSurface,
        level: Level,
    ) -> Result<CpuMesh, SurfaceError> {
        let state = surface.lock();
        let mesh = match level {
            Level::Full => state.buffers.as_ref().zip(state.counts),
            Level::Coarse => state
                .coarse
                .as_ref()
                .and_then(|c| Some(&c.buffers).zip(c.counts)),
        };
        let Some((buffers, counts)) = mesh else {
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

    /// Draws the extracted surface with the indirect arguments the GPU wrote: the full mesh or
    /// the coarse one, as `detail` asks of what is ready (see
    /// [`crate::render::surface::lod::choose_mesh`]), `grid` and `settings` being the current
    /// ones.
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        surface: &ExtractedSurface,
        current: Option<(&VoxelGrid, &SurfaceSettings)>,
        detail: SurfaceDetail,
    ) {
        let state = surface.lock();
        let wanted = current.map(|(grid, settings)| CacheKey::new(grid, settings));
        let buffers = match ExtractedSurface::level_to_draw(&state, detail, wanted.as_ref()) {
            Some(Level::Full) => state.buffers.as_ref(),
            Some(Level::Coarse) => state.coarse.as_ref().map(|c| &c.buffers),
            None => None,
        };
        let Some(buffers) = buffers else {
            return;
        };
        self.bind(pass, frame, &buffers.vertices, &buffers.indices);
        pass.draw_indexed_indirect(&buffers.indirect, INDEXED_ARGS_OFFSET);
    }

    /// Draws the first `index_count` indices of a mesh held in plain vertex and index buffers
    /// ([`MeshVertex`] records, `u32` indices) with an ordinary indexed draw: where the device
    /// has no indirect draws nor storage buffers (the web page on WebGL2, whose surface the CPU
    /// extracts: src/web/gl_surface.rs). The same pipeline, so the same look.
    pub fn draw_mesh(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        vertices: &wgpu::Buffer,
        indices: &wgpu::Buffer,
        index_count: u32,
    ) {
        if index_count == 0 {
            return;
        }
        self.bind(pass, frame, vertices, indices);
        pass.draw_indexed(0..index_count, 0, 0..1);
    }

    /// The pipeline, the frame's and the style's bind groups and the mesh's buffers.
    fn bind(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameBinding,
        vertices: &wgpu::Buffer,
        indices: &wgpu::Buffer,
    ) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_bind_group(1, &self.style_bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
    }
}
