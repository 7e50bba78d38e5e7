//! Voxelization: turns a cloud's points into the [`VoxelGrid`] that the volume and surface views
//! read (paper sections 3.1 and 3.4).
//!
//! Reads: the points of a [`VoxelizeRequest`] (uploaded here in chunks, or the points view's
//! buffers, [`PointSource::Device`]; five f32 per point, the PLY record). Writes: a `VoxelGrid`
//! with a normalized loudness density in [0, 1] and the mean hp per voxel. How:
//! shaders/grid/voxelize.wgsl, one compute pass per stage. `accumulate` adds each point's scalar
//! and hp to its voxel as 64-bit fixed-point sums (u32 atomics with a manual carry; scale
//! [`FIXED_POINT_SCALE`] for loudness, [`HP_FIXED_POINT_SCALE`] for hp) and counts it in a u32 of
//! its own (so any cloud up to [`MAX_POINTS`]; portable to every adapter, no float atomics).
//! `resolve` turns the sums into an f32 loudness sum and a mean hp; `smooth_axis` optionally
//! blurs the sums with a separable Gaussian; `histogram` bins the positive sums on a log2 scale,
//! `percentile` finds the bin holding the 99th percentile, and `normalize_density` divides by
//! that reference sum and clamps to 1, so one hot voxel cannot flatten the rest of the field. The
//! grid box is the cloud's bounding box, padded ([`grid_box`]); the grid is rebuilt only when the
//! cloud or the settings change (see `SceneData::ensure_grid`). With a frequency axis
//! ([`VoxelizeRequest::mapping`], src/data/freq_axis.rs) `accumulate` first remaps each point's z
//! as the points shader does, and the box is that of the remapped points. The CPU side of the
//! shader's arithmetic (box, voxel, histogram, weights) is in [`voxelize_cpu`].
//!
//! [`voxelize_cpu`]: crate::render::grid::voxelize_cpu

use glam::{UVec3, Vec3};
use wgpu::util::DeviceExt;

use crate::data::cloud::Point;
use crate::data::freq_axis::{FreqMapping, FreqParams, HIDDEN};
use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry, whole_buffer_entries};
use crate::render::gpu::readback::read_buffer;
use crate::render::grid::VoxelGrid;
pub use crate::render::grid::settings::{
    MAX_POINTS, MAX_RESOLUTION, MAX_SMOOTHING_SIGMA, MIN_RESOLUTION, SONG_RESOLUTION,
    SONG_SMOOTHING, TIMELINE_RESOLUTION, TIMELINE_SMOOTHING, VoxelSettings, VoxelizeError,
    default_resolution, default_smoothing,
};
pub use crate::render::grid::voxelize_cpu::{FIXED_POINT_SCALE, HP_FIXED_POINT_SCALE, VoxelStats};
use crate::render::grid::voxelize_cpu::{
    HISTOGRAM_BINS, HISTOGRAM_BINS_PER_OCTAVE, HISTOGRAM_LOG2_MIN, PERCENTILE, gaussian_weights,
    grid_box, grid_box_mapped, grid_box_of_bounds, voxels_per_unit,
};
use crate::render::grid::voxelize_host;
use crate::render::shaders;

const STATS_HISTOGRAM: usize = 4;
const STATS_WORDS: usize = STATS_HISTOGRAM + HISTOGRAM_BINS as usize;
const WORKGROUP: u32 = 256;
/// Workgroups of the grid-stride passes that build a histogram (each merges its workgroup
/// histogram once).
const GRID_STRIDE_GROUPS: u32 = 512;
/// Most compute passes one build records (accumulate, resolve, 3 smoothing, histogram,
/// percentile, normalize).
pub const MAX_PASSES: usize = 8;

/// Keep in sync with `VoxelParams` in shaders/grid/voxelize.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct VoxelParams {
    dims: [u32; 4],
    box_min: [f32; 4],
    voxels_per_unit: [f32; 4],
    /// x: points in the chunk, z: percentile in parts per million.
    counts: [u32; 4],
    /// x: loudness fixed-point scale, y: histogram log2 minimum, z: bins per octave,
    /// w: hp fixed-point scale.
    scales: [f32; 4],
    /// The frequency axis (shaders/utils/freq_axis.wgsl); `mode[2]` is the chunk's first point.
    freq: FreqParams,
}
const _: () = assert!(std::mem::size_of::<VoxelParams>() == 112);

/// Keep in sync with `SmoothParams` in shaders/grid/voxelize.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SmoothParams {
    dims: [u32; 4],
    /// x: axis, y: kernel radius.
    axis: [u32; 4],
    weights: [[f32; 4]; 8],
}
const _: () = assert!(std::mem::size_of::<SmoothParams>() == 160);

/// Where a build's points come from.
pub enum PointSource<'a> {
    /// On the host: uploaded in chunks of at most one storage binding.
    Host(&'a [Point]),
    /// Already on the device, so nothing is uploaded and the cloud is on the device once (the
    /// points view's `PointsGpu::chunk_buffers`): storage buffers of five f32 a point (the PLY
    /// record; each at most one storage binding and fewer than `u32::MAX / 5` points) with their
    /// point counts, and `bounds`, the points' bounding box (`PointCloud::bounds`). On a
    /// remapped frequency axis `bounds` would not be the box the grid sees: give the request a
    /// `grid_box` ([`grid_box_mapped`] of the host's points).
    Device {
        chunks: Vec<(&'a wgpu::Buffer, u32)>,
        bounds: (Vec3, Vec3),
    },
}

impl PointSource<'_> {
    /// How many points the source holds.
    pub fn len(&self) -> usize {
        match self {
            PointSource::Host(points) => points.len(),
            PointSource::Device { chunks, .. } => chunks.iter().map(|(_, c)| *c as usize).sum(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One voxelization: the points, the grid's resolution and smoothing, the frequency axis and
/// the box. [`VoxelizePass::prepare`] allocates its buffers (the benchmark records them many
/// times); [`VoxelizePass::voxelize`] builds it and waits.
pub struct VoxelizeRequest<'a> {
    pub points: PointSource<'a>,
    /// Voxels per side ([`MIN_RESOLUTION`] to [`MAX_RESOLUTION`]).
    pub resolution: u32,
    /// Gaussian smoothing of the loudness sums, sigma in voxels (0: off).
    pub smoothing_sigma: f32,
    /// The frequency axis the points are shown on (src/data/freq_axis.rs): `accumulate` remaps
    /// each point's z as the points shader does. `None`: the axis as stored.
    pub mapping: Option<&'a FreqMapping>,
    /// The grid's box. `None`: the points' own ([`grid_box_mapped`] of host points, the padded
    /// `bounds` of device points). An A/B compare builds both grids in one box; points outside
    /// it count in the nearest border voxel.
    pub grid_box: Option<(Vec3, Vec3)>,
    /// Points on the device, the same on the host ([`VoxelizeRequest::with_host`]): a device
    /// that is the CPU builds the grid from these.
    pub host: Option<&'a [Point]>,
}

impl<'a> VoxelizeRequest<'a> {
    /// The host's `points` at `resolution`^3, on the stored axis, in their own box.
    pub fn new(points: &'a [Point], resolution: u32, smoothing_sigma: f32) -> Self {
        Self {
            points: PointSource::Host(points),
            resolution,
            smoothing_sigma,
            mapping: None,
            grid_box: None,
            host: None,
        }
    }

    /// Points already on the device (see [`PointSource::Device`]).
    pub fn on_device(
        chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
        bounds: (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
    ) -> Self {
        Self {
            points: PointSource::Device {
                chunks: chunks.into_iter().collect(),
                bounds,
            },
            ..Self::new(&[], resolution, smoothing_sigma)
        }
    }

    /// The same request in the box `grid_box` (`None`: the points' own).
    pub fn in_box(self, grid_box: Option<(Vec3, Vec3)>) -> Self {
        Self { grid_box, ..self }
    }

    /// The same request with the device's points also on the host (`points`, the cloud the
    /// device's were uploaded from; ignored unless it holds as many).
    pub fn with_host(self, points: &'a [Point]) -> Self {
        Self {
            host: Some(points),
            ..self
        }
    }

    /// The points on the host, when the request has them all.
    pub fn host_points(&self) -> Option<&'a [Point]> {
        match &self.points {
            PointSource::Host(points) => Some(points),
            PointSource::Device { .. } => self.host.filter(|h| h.len() == self.points.len()),
        }
    }

    /// The same request on the frequency axis `mapping`.
    pub fn mapped(self, mapping: Option<&'a FreqMapping>) -> Self {
        Self { mapping, ..self }
    }

    /// Checks the resolution (against this device too), the smoothing and the point count.
    pub fn check(&self, device: &wgpu::Device) -> Result<(), VoxelizeError> {
        VoxelizePass::check_resolution(device, self.resolution)?;
        if !(0.0..=MAX_SMOOTHING_SIGMA).contains(&self.smoothing_sigma) {
            return Err(VoxelizeError::Smoothing(self.smoothing_sigma));
        }
        let count = self.points.len();
        if count > MAX_POINTS {
            return Err(VoxelizeError::TooManyPoints(count));
        }
        Ok(())
    }

    /// The box the grid covers (see [`VoxelizeRequest::grid_box`]).
    pub fn resolved_box(&self) -> (Vec3, Vec3) {
        if let Some(grid_box) = self.grid_box {
            return grid_box;
        }
        match &self.points {
            PointSource::Host(points) => grid_box_mapped(points, self.mapping),
            PointSource::Device { .. } if self.points.is_empty() => grid_box(&[]),
            PointSource::Device { bounds, .. } => grid_box_of_bounds(bounds.0, bounds.1),
        }
    }
}

/// Workgroups for `invocations` threads of a 256-wide workgroup, split over x and y so no
/// dimension exceeds 65535 (the shaders rebuild the linear index).
fn dispatch_size(invocations: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(WORKGROUP);
    let x = groups.clamp(1, 65535);
    (x, groups.div_ceil(x))
}

struct Chunk {
    count: u32,
    bind_group: wgpu::BindGroup,
    _points: wgpu::Buffer,
    _params: wgpu::Buffer,
}

/// One build's buffers, prepared by [`VoxelizePass::prepare`] and recorded by
/// [`VoxelizePass::encode`] (the benchmark records the same job many times).
pub struct VoxelizeJob {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub point_count: usize,
    chunks: Vec<Chunk>,
    fields: Fields,
    smoothing: Option<(wgpu::Buffer, [wgpu::BindGroup; 3])>,
    resolve_group: wgpu::BindGroup,
}

impl VoxelizeJob {
    pub fn voxel_count(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }
}

/// A build's storage buffer (STORAGE, COPY_SRC, COPY_DST).
fn storage_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A build's sums, statistics and fields.
struct Fields {
    loudness_sums: wgpu::Buffer,
    hp_sums: wgpu::Buffer,
    point_counts: wgpu::Buffer,
    stats: wgpu::Buffer,
    reference: wgpu::Buffer,
    density: wgpu::Buffer,
    hp_mean: wgpu::Buffer,
}

impl Fields {
    /// Every per-voxel buffer is padded to whole groups of four voxels (16 bytes of f32, 32 of
    /// sums): the per-voxel passes read and write four voxels at a time. The padding stays zero
    /// (an empty voxel) and is never part of the grid.
    fn new(device: &wgpu::Device, voxels: u64) -> Self {
        let group4_count = voxels.div_ceil(4);
        Self {
            loudness_sums: storage_buffer(device, "voxelize::loudness_sums", group4_count * 32),
            hp_sums: storage_buffer(device, "voxelize::hp_sums", group4_count * 32),
            point_counts: storage_buffer(device, "voxelize::point_counts", group4_count * 16),
            stats: storage_buffer(device, "voxelize::stats", STATS_WORDS as u64 * 4),
            reference: storage_buffer(device, "voxelize::reference_sum", 16),
            density: storage_buffer(device, "voxelize::density_grid", group4_count * 16),
            hp_mean: storage_buffer(device, "voxelize::hp_mean_grid", group4_count * 16),
        }
    }
}

/// The source's points as device buffers with their counts, empty chunks left out: uploaded in
/// chunks of at most one storage binding, or the device's own (a buffer handle is a reference
/// count). An empty cloud still binds one (zero) point, with a count of 0.
fn point_buffers(device: &wgpu::Device, source: &PointSource) -> Vec<(wgpu::Buffer, u32)> {
    let mut buffers: Vec<(wgpu::Buffer, u32)> = match source {
        PointSource::Host(points) => {
            let per_chunk = (storage_binding_limit(device) / std::mem::size_of::<Point>() as u64)
                .clamp(1, u64::from(u32::MAX / 5)) as usize;
            points
                .chunks(per_chunk)
                .enumerate()
                .map(|(i, slice)| {
                    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(&format!("voxelize::points_{i}")),
                        contents: bytemuck::cast_slice(slice),
                        usage: wgpu::BufferUsages::STORAGE,
                    });
                    (buffer, slice.len() as u32)
                })
                .collect()
        }
        PointSource::Device { chunks, .. } => chunks
            .iter()
            .filter(|(_, count)| *count > 0)
            .map(|(buffer, count)| ((*buffer).clone(), *count))
            .collect(),
    };
    if buffers.is_empty() {
        let zero = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize::points_empty"),
            contents: &[0u8; std::mem::size_of::<Point>()],
            usage: wgpu::BufferUsages::STORAGE,
        });
        buffers.push((zero, 0));
    }
    buffers
}

/// The voxelization pipelines, built once per device.
pub struct VoxelizePass {
    main_layout: wgpu::BindGroupLayout,
    smooth_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    accumulate: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    smooth: wgpu::ComputePipeline,
    histogram: wgpu::ComputePipeline,
    percentile: wgpu::ComputePipeline,
    normalize: wgpu::ComputePipeline,
    frame_bind_group: wgpu::BindGroup,
    /// Whether [`VoxelizePass::voxelize`] builds grids of host points on the CPU
    /// (`voxelize_host.rs`): on a device that is the CPU.
    on_cpu: bool,
}

const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;

impl VoxelizePass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "voxelize", &shaders::voxelize());
        let main_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("voxelize::main_layout"),
            entries: &[
                uniform_entry(0, COMPUTE),
                storage_entry(1, COMPUTE, true),
                storage_entry(2, COMPUTE, false),
                storage_entry(3, COMPUTE, false),
                storage_entry(4, COMPUTE, false),
                storage_entry(5, COMPUTE, false),
                storage_entry(6, COMPUTE, false),
                storage_entry(7, COMPUTE, false),
                storage_entry(8, COMPUTE, false),
                storage_entry(9, COMPUTE, true),
            ],
        });
        let smooth_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("voxelize::smooth_layout"),
            entries: &[
                uniform_entry(0, COMPUTE),
                storage_entry(1, COMPUTE, true),
                storage_entry(2, COMPUTE, false),
            ],
        });
        let resolve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("voxelize::resolve_layout"),
            entries: &[
                uniform_entry(0, COMPUTE),
                storage_entry(1, COMPUTE, true),
                storage_entry(2, COMPUTE, true),
                storage_entry(3, COMPUTE, false),
                storage_entry(4, COMPUTE, false),
                storage_entry(5, COMPUTE, true),
            ],
        });
        let resolve_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("voxelize::resolve_pipeline_layout"),
                bind_group_layouts: &[Some(&frame.layout), None, None, Some(&resolve_layout)],
                immediate_size: 0,
            });
        let main_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("voxelize::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&main_layout)],
            immediate_size: 0,
        });
        let smooth_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("voxelize::smooth_pipeline_layout"),
                bind_group_layouts: &[Some(&frame.layout), None, Some(&smooth_layout)],
                immediate_size: 0,
            });
        let pipeline = |entry: &str, layout: &wgpu::PipelineLayout| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&format!("voxelize::{entry}")),
                layout: Some(layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            accumulate: pipeline("accumulate", &main_pipeline_layout),
            resolve: pipeline("resolve", &resolve_pipeline_layout),
            smooth: pipeline("smooth_axis", &smooth_pipeline_layout),
            histogram: pipeline("histogram", &main_pipeline_layout),
            percentile: pipeline("percentile", &main_pipeline_layout),
            normalize: pipeline("normalize_density", &main_pipeline_layout),
            main_layout,
            smooth_layout,
            resolve_layout,
            frame_bind_group: frame.bind_group.clone(),
            on_cpu: device.adapter_info().device_type == wgpu::DeviceType::Cpu,
        }
    }

    /// Whether grids of host points are built on the CPU (a device that is the CPU).
    pub fn on_cpu(&self) -> bool {
        self.on_cpu
    }

    /// The same pass building grids on the CPU (`true`) or with the compute passes (`false`)
    /// whatever the device (the tests compare the two).
    pub fn with_cpu_engine(self, on_cpu: bool) -> Self {
        Self { on_cpu, ..self }
    }

    /// Checks a resolution against the allowed range and this device's buffer limits.
    pub fn check_resolution(device: &wgpu::Device, resolution: u32) -> Result<(), VoxelizeError> {
        if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&resolution) {
            return Err(VoxelizeError::Resolution(resolution));
        }
        // The largest buffers hold 8 bytes per voxel.
        let needed = u64::from(resolution).pow(3) * 8;
        let limit = storage_binding_limit(device);
        if needed > limit {
            let largest = ((limit / 8) as f64).cbrt().floor() as u32;
            return Err(VoxelizeError::TooLarge {
                resolution,
                needed_mib: needed.div_ceil(1 << 20),
                limit_mib: limit >> 20,
                largest,
            });
        }
        Ok(())
    }

    /// Uploads the request's points (unless they are on the device) and allocates its build's
    /// buffers; nothing is recorded or submitted (see [`VoxelizePass::encode`]).
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        request: &VoxelizeRequest,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        request.check(device)?;
        let (box_min, box_max) = request.resolved_box();
        let dims = UVec3::splat(request.resolution);
        let per_unit = voxels_per_unit(dims, box_min, box_max);
        let fields = Fields::new(device, u64::from(dims.x * dims.y * dims.z));
        let mapping = request.mapping;
        let freq = mapping.map_or(FreqParams::IDENTITY, FreqMapping::params);
        let freq_table = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize::freq_table"),
            contents: bytemuck::cast_slice(
                &mapping.map_or_else(|| vec![HIDDEN], |m| m.gpu_table()),
            ),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let mut chunks = Vec::new();
        // Each chunk's first point's index in the cloud: the frequency jitter's seed.
        let mut first = 0u32;
        for (i, (points, count)) in point_buffers(device, &request.points)
            .into_iter()
            .enumerate()
        {
            let params = VoxelParams {
                dims: [dims.x, dims.y, dims.z, 0],
                box_min: box_min.extend(0.0).into(),
                voxels_per_unit: per_unit.extend(0.0).into(),
                counts: [count, 0, (PERCENTILE * 1e6).round() as u32, 0],
                scales: [
                    FIXED_POINT_SCALE as f32,
                    HISTOGRAM_LOG2_MIN,
                    HISTOGRAM_BINS_PER_OCTAVE,
                    HP_FIXED_POINT_SCALE as f32,
                ],
                freq: freq.for_chunk(first),
            };
            chunks.push(self.chunk(device, i, points, count, &params, &fields, &freq_table));
            first += count;
        }
        let resolve_entries = whole_buffer_entries(&[
            &chunks[0]._params,
            &fields.loudness_sums,
            &fields.hp_sums,
            &fields.density,
            &fields.hp_mean,
            &fields.point_counts,
        ]);
        let resolve_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("voxelize::resolve_bind_group"),
            layout: &self.resolve_layout,
            entries: &resolve_entries,
        });
        let smoothing = (request.smoothing_sigma > 0.0)
            .then(|| self.smoothing(device, dims, request.smoothing_sigma, &fields.density));
        Ok(VoxelizeJob {
            dims,
            box_min,
            box_max,
            point_count: chunks.iter().map(|c| c.count as usize).sum(),
            chunks,
            fields,
            smoothing,
            resolve_group,
        })
    }

    /// One chunk of points: its uniform and its bind group over the build's buffers.
    #[allow(clippy::too_many_arguments)]
    fn chunk(
        &self,
        device: &wgpu::Device,
        index: usize,
        points: wgpu::Buffer,
        count: u32,
        params: &VoxelParams,
        fields: &Fields,
        freq_table: &wgpu::Buffer,
    ) -> Chunk {
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("voxelize::params_{index}")),
            contents: bytemuck::bytes_of(params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let entries = whole_buffer_entries(&[
            &params,
            &points,
            &fields.loudness_sums,
            &fields.hp_sums,
            &fields.stats,
            &fields.density,
            &fields.hp_mean,
            &fields.reference,
            &fields.point_counts,
            freq_table,
        ]);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&format!("voxelize::bind_group_{index}")),
            layout: &self.main_layout,
            entries: &entries,
        });
        Chunk {
            count,
            bind_group,
            _points: points,
            _params: params,
        }
    }

    /// The separable Gaussian's scratch buffer and its three passes' bind groups: x density ->
    /// scratch, y scratch -> density, z density -> scratch.
    fn smoothing(
        &self,
        device: &wgpu::Device,
        dims: UVec3,
        sigma: f32,
        density: &wgpu::Buffer,
    ) -> (wgpu::Buffer, [wgpu::BindGroup; 3]) {
        let voxels = u64::from(dims.x * dims.y * dims.z);
        let scratch = storage_buffer(device, "voxelize::smooth_scratch", voxels * 4);
        let weights = gaussian_weights(sigma);
        let mut packed = [[0.0f32; 4]; 8];
        for (o, w) in weights.iter().enumerate() {
            packed[o / 4][o % 4] = *w;
        }
        let bind_group = |axis: u32, input: &wgpu::Buffer, output: &wgpu::Buffer| {
            let params = SmoothParams {
                dims: [dims.x, dims.y, dims.z, 0],
                axis: [axis, weights.len() as u32 - 1, 0, 0],
                weights: packed,
            };
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("voxelize::smooth_params_{axis}")),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&format!("voxelize::smooth_bind_group_{axis}")),
                layout: &self.smooth_layout,
                entries: &whole_buffer_entries(&[&params, input, output]),
            })
        };
        let groups = [
            bind_group(0, density, &scratch),
            bind_group(1, &scratch, density),
            bind_group(2, density, &scratch),
        ];
        (scratch, groups)
    }

    /// Records the whole build and returns the names of its compute passes, in order. With
    /// `timestamps` (a query set of at least [`MAX_PASSES`] * 2 timestamps), pass `i` writes its
    /// start and end to queries `2 i` and `2 i + 1` (the benchmark's per-stage timings).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        job: &VoxelizeJob,
        timestamps: Option<&wgpu::QuerySet>,
    ) -> Vec<&'static str> {
        for buffer in [
            &job.fields.loudness_sums,
            &job.fields.hp_sums,
            &job.fields.point_counts,
            &job.fields.stats,
        ] {
            encoder.clear_buffer(buffer, 0, None);
        }
        let voxels = dispatch_size(job.voxel_count());
        let group4_count = dispatch_size(job.voxel_count().div_ceil(4));
        let main_group = &job.chunks[0].bind_group;
        let mut names: Vec<&'static str> = Vec::new();
        let mut begin_pass = |encoder: &mut wgpu::CommandEncoder, label: &'static str| {
            let index = 2 * names.len() as u32;
            names.push(label);
            encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(label),
                    timestamp_writes: timestamps.map(|set| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(index),
                        end_of_pass_write_index: Some(index + 1),
                    }),
                })
                .forget_lifetime()
        };
        {
            let mut pass = begin_pass(encoder, "voxelize::accumulate");
            pass.set_pipeline(&self.accumulate);
            pass.set_bind_group(0, &self.frame_bind_group, &[]);
            for chunk in &job.chunks {
                if chunk.count == 0 {
                    continue;
                }
                let (x, y) = dispatch_size(chunk.count);
                pass.set_bind_group(1, &chunk.bind_group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        {
            let mut pass = begin_pass(encoder, "voxelize::resolve");
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &self.frame_bind_group, &[]);
            pass.set_bind_group(3, &job.resolve_group, &[]);
            pass.dispatch_workgroups(group4_count.0, group4_count.1, 1);
        }
        if let Some((scratch, groups)) = &job.smoothing {
            for (axis, group) in groups.iter().enumerate() {
                let label = [
                    "voxelize::smooth_x",
                    "voxelize::smooth_y",
                    "voxelize::smooth_z",
                ][axis];
                let mut pass = begin_pass(encoder, label);
                pass.set_pipeline(&self.smooth);
                pass.set_bind_group(0, &self.frame_bind_group, &[]);
                pass.set_bind_group(2, group, &[]);
                pass.dispatch_workgroups(voxels.0, voxels.1, 1);
            }
            encoder.copy_buffer_to_buffer(scratch, 0, &job.fields.density, 0, None);
        }
        let stages = [
            (
                "voxelize::histogram",
                &self.histogram,
                (voxels.0.min(GRID_STRIDE_GROUPS), 1),
            ),
            ("voxelize::percentile", &self.percentile, (1, 1)),
            ("voxelize::normalize_density", &self.normalize, group4_count),
        ];
        for (label, pipeline, (x, y)) in stages {
            let mut pass = begin_pass(encoder, label);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.frame_bind_group, &[]);
            pass.set_bind_group(1, main_group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        names
    }

    /// Reads the normalization statistics of the last recorded build (waits for the GPU).
    pub fn read_stats(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        job: &VoxelizeJob,
    ) -> Result<VoxelStats, VoxelizeError> {
        let bytes = read_buffer(
            device,
            queue,
            "voxelize::stats_readback",
            &job.fields.stats,
            16,
        )?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(VoxelStats {
            nonempty: words[0],
            reference_sum: f32::from_bits(words[1]),
            clamped: words[2],
        })
    }

    /// Hands the finished fields over as a grid; the sums and points are freed.
    pub fn finish(job: VoxelizeJob) -> VoxelGrid {
        VoxelGrid {
            dims: job.dims,
            box_min: job.box_min,
            box_max: job.box_max,
            density: job.fields.density,
            hp_mean: job.fields.hp_mean,
        }
    }

    /// Builds the request's grid: upload, all passes, wait, statistics. On a device that is the
    /// CPU, a request whose points are on the host is built on the CPU instead
    /// (`voxelize_host.rs`: the same grid, many times sooner there) and uploaded.
    pub fn voxelize(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        request: &VoxelizeRequest,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        if self.on_cpu
            && let Some(points) = request.host_points()
        {
            request.check(device)?;
            let dims = UVec3::splat(request.resolution);
            let grid_box = request.resolved_box();
            let built = voxelize_host::build(
                points,
                request.mapping,
                dims,
                grid_box,
                request.smoothing_sigma,
            );
            let grid = VoxelGrid::from_fields(
                device,
                dims,
                grid_box.0,
                grid_box.1,
                &built.density,
                &built.hp_mean,
            );
            return Ok((grid, built.stats));
        }
        let job = self.prepare(device, request)?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("voxelize::build"),
        });
        self.encode(&mut encoder, &job, None);
        queue.submit([encoder.finish()]);
        let stats = self.read_stats(device, queue, &job)?;
        Ok((Self::finish(job), stats))
    }
}
