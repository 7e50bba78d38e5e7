//! Voxelization: turns a cloud's points into the [`VoxelGrid`] that the volume and surface views
//! read (paper sections 3.1 and 3.4).
//!
//! Reads: the points (uploaded here in chunks, or the points view's buffers through
//! [`VoxelizePass::prepare_from_buffers`]; five f32 per point, the PLY record). Writes: a
//! `VoxelGrid` with a normalized loudness density in [0, 1] and the mean hp per voxel. How:
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
//! ([`VoxelizePass::voxelize_with`], src/data/freq_axis.rs) `accumulate` first remaps each
//! point's z as the points shader does, and the box is that of the remapped points.

use glam::{UVec3, Vec3};
use thiserror::Error;
use wgpu::util::DeviceExt;

use crate::data::cloud::{DataMode, Point};
use crate::data::freq_axis::{FreqMapping, FreqParams, HIDDEN};
use crate::render::gpu::context::storage_binding_limit;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry, whole_buffer_entries};
use crate::render::gpu::readback::{ReadbackError, read_buffer};
use crate::render::grid::VoxelGrid;
use crate::render::shaders;

/// Default grid resolution (voxels per side) for a song (paper 3.1).
pub const SONG_RESOLUTION: u32 = 128;
/// Default grid resolution for a timeline (paper 3.1).
pub const TIMELINE_RESOLUTION: u32 = 224;
pub const MIN_RESOLUTION: u32 = 64;
pub const MAX_RESOLUTION: u32 = 384;
/// Fixed-point units per 1.0 of scalar or hp. One point adds at most 2^20 to a 64-bit sum, so no
/// cloud that fits a GPU buffer can overflow it; the rounding error is at most 2^-21 per point.
pub const FIXED_POINT_SCALE: u32 = 1 << 20;
/// Fixed-point units per 1.0 of hp, in a 64-bit sum of its own (the count has its own u32).
pub const HP_FIXED_POINT_SCALE: u32 = 1 << 16;
/// Most points per voxelization: the per-voxel count is a u32. A cloud this large would take
/// 86 GB at 20 bytes a point, so no cloud a machine holds reaches it.
pub const MAX_POINTS: usize = u32::MAX as usize;
/// The density is normalized by this percentile of the voxels with a positive loudness sum.
pub const PERCENTILE: f64 = 0.99;
pub const HISTOGRAM_BINS: u32 = 1024;
/// log2 of the lowest histogram bin edge: one point of scalar 2^-20 (one fixed-point unit).
pub const HISTOGRAM_LOG2_MIN: f32 = -20.0;
/// Bins per doubling of the sum: bins are 2.9 % wide; 1024 bins reach sums of 2^22.6.
pub const HISTOGRAM_BINS_PER_OCTAVE: f32 = 24.0;
/// Largest Gaussian sigma, in voxels.
pub const MAX_SMOOTHING_SIGMA: f32 = 10.0;
const MAX_KERNEL_RADIUS: usize = 31;
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

/// How the grid is built. Changing these rebuilds the grid; nothing else does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelSettings {
    /// Voxels per side; `None` picks by data mode (128 song, 224 timeline).
    pub resolution: Option<u32>,
    /// Gaussian smoothing of the loudness sums, sigma in voxels; 0 turns it off.
    pub smoothing_sigma: f32,
}

impl Default for VoxelSettings {
    fn default() -> Self {
        Self {
            resolution: None,
            smoothing_sigma: 1.0,
        }
    }
}

impl VoxelSettings {
    pub fn resolution_for(&self, mode: DataMode) -> u32 {
        self.resolution.unwrap_or(default_resolution(mode))
    }
}

pub fn default_resolution(mode: DataMode) -> u32 {
    match mode {
        DataMode::Timeline => TIMELINE_RESOLUTION,
        DataMode::Song | DataMode::Generic => SONG_RESOLUTION,
    }
}

#[derive(Debug, Error)]
pub enum VoxelizeError {
    #[error(
        "grid resolution {0} is out of range: choose {MIN_RESOLUTION} to {MAX_RESOLUTION} voxels per side"
    )]
    Resolution(u32),
    #[error("smoothing sigma {0} is out of range: choose 0 (off) to {MAX_SMOOTHING_SIGMA} voxels")]
    Smoothing(f32),
    #[error(
        "a {resolution}^3 grid needs {needed_mib} MiB in one GPU buffer but this GPU allows \
         {limit_mib} MiB; choose a resolution of {largest} or less"
    )]
    TooLarge {
        resolution: u32,
        needed_mib: u64,
        limit_mib: u64,
        largest: u32,
    },
    #[error("the cloud has {0} points; at most 4294967295 can be voxelized at once")]
    TooManyPoints(usize),
    #[error("voxelization: {0}")]
    Readback(#[from] ReadbackError),
}

/// What the normalization found, read back after a build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelStats {
    /// Voxels with a positive (smoothed) loudness sum.
    pub nonempty: u32,
    /// The loudness sum that maps to density 1 (the 99th-percentile histogram bin's upper edge,
    /// capped at the largest sum).
    pub reference_sum: f32,
    /// Voxels whose sum exceeded the reference and were clamped to 1.
    pub clamped: u32,
}

/// The grid box for a cloud: its bounding box, each side grown by 1 % so that no point lies on
/// the box's faces, and at least 5 % of the largest side (or 0.02 data units) thick, so a flat
/// cloud or a single point still gets a box with volume. An empty cloud gets the data cube.
pub fn grid_box(points: &[Point]) -> (Vec3, Vec3) {
    let mut min = Vec3::splat(f32::INFINITY);
    let mut max = Vec3::splat(f32::NEG_INFINITY);
    for p in points {
        let q = Vec3::from(p.position);
        if q.is_finite() {
            min = min.min(q);
            max = max.max(q);
        }
    }
    grid_box_of_bounds(min, max)
}

/// The chunks of points already on the device, owned (a buffer handle is a reference count),
/// empty ones left out.
fn owned_chunks<'a>(
    chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
) -> Vec<(wgpu::Buffer, u32)> {
    chunks
        .into_iter()
        .filter(|(_, count)| *count > 0)
        .map(|(b, count)| (b.clone(), count))
        .collect()
}

/// [`grid_box`] from the points' bounding box `[min, max]` (not finite: no points).
pub fn grid_box_of_bounds(min: Vec3, max: Vec3) -> (Vec3, Vec3) {
    if !min.is_finite() || !max.is_finite() {
        return (Vec3::splat(-1.0), Vec3::splat(1.0));
    }
    let centre = (min + max) * 0.5;
    let extent = max - min;
    let thinnest = (extent.max_element() * 0.05).max(0.02);
    let extent = extent.max(Vec3::splat(thinnest)) * 1.02;
    (centre - extent * 0.5, centre + extent * 0.5)
}

/// The grid box of the points as the frequency axis `mapping` shows them (z remapped, points it
/// leaves out ignored): [`grid_box`] of [`FreqMapping::view_points`], without the copy.
pub fn grid_box_mapped(points: &[Point], mapping: Option<&FreqMapping>) -> (Vec3, Vec3) {
    let Some(mapping) = mapping.filter(|m| !m.is_identity()) else {
        return grid_box(points);
    };
    let mut min = Vec3::splat(f32::INFINITY);
    let mut max = Vec3::splat(f32::NEG_INFINITY);
    for (i, p) in points.iter().enumerate() {
        let Some(z) = mapping.view_z(p.position[2], i as u32) else {
            continue;
        };
        let q = Vec3::new(p.position[0], p.position[1], z);
        if q.is_finite() {
            min = min.min(q);
            max = max.max(q);
        }
    }
    if !min.is_finite() || !max.is_finite() {
        return grid_box(&[]);
    }
    // The box of the two corners is the box of the points.
    let corner = |q: Vec3| Point {
        position: q.into(),
        scalar: 0.0,
        hp: 0.0,
    };
    grid_box(&[corner(min), corner(max)])
}

/// Voxel coordinates per data unit along each axis.
pub fn voxels_per_unit(dims: UVec3, box_min: Vec3, box_max: Vec3) -> Vec3 {
    dims.as_vec3() / (box_max - box_min)
}

/// The voxel (i, j, k) holding `p`. Keep in sync with `voxel_of` in shaders/grid/voxelize.wgsl: the
/// same f32 operations, so the CPU reference puts points on voxel faces where the GPU does.
pub fn voxel_of(p: Vec3, box_min: Vec3, per_unit: Vec3, dims: UVec3) -> UVec3 {
    let u = ((p - box_min) * per_unit).floor();
    let top = dims.as_vec3() - Vec3::ONE;
    u.clamp(Vec3::ZERO, top).as_uvec3()
}

/// The histogram bin of a positive sum. Keep in sync with `histogram_bin` in voxelize.wgsl.
pub fn histogram_bin(sum: f32) -> u32 {
    if sum <= 0.0 {
        return 0;
    }
    let t = (sum.log2() - HISTOGRAM_LOG2_MIN) * HISTOGRAM_BINS_PER_OCTAVE;
    t.floor().clamp(0.0, (HISTOGRAM_BINS - 1) as f32) as u32
}

/// The upper edge of a histogram bin.
pub fn bin_upper_edge(bin: u32) -> f32 {
    (HISTOGRAM_LOG2_MIN + (bin + 1) as f32 / HISTOGRAM_BINS_PER_OCTAVE).exp2()
}

/// The reference sum for normalization, as the GPU computes it: the upper edge of the histogram
/// bin holding rank ceil(0.99 n) of the n positive sums, capped at the largest sum (1 when there
/// are none).
/// Keep in sync with `percentile` in voxelize.wgsl.
pub fn reference_sum(sums: impl IntoIterator<Item = f32>) -> f32 {
    let mut histogram = vec![0u32; HISTOGRAM_BINS as usize];
    let mut n = 0u32;
    let mut largest = 0.0f32;
    for s in sums {
        if s > 0.0 {
            histogram[histogram_bin(s) as usize] += 1;
            n += 1;
            largest = largest.max(s);
        }
    }
    if n == 0 {
        return 1.0;
    }
    let p = (PERCENTILE * 1e6).round() as f32 / 1e6;
    let rank = ((p * n as f32).ceil() as u32).max(1);
    let mut seen = 0;
    for (bin, count) in histogram.iter().enumerate() {
        seen += count;
        if seen >= rank {
            return bin_upper_edge(bin as u32).min(largest);
        }
    }
    largest
}

/// Normalized Gaussian weights for offsets 0..=radius (radius = ceil(3 sigma), at most 31).
pub fn gaussian_weights(sigma: f32) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let radius = ((3.0 * sigma).ceil() as usize).clamp(1, MAX_KERNEL_RADIUS);
    (0..=radius)
        .map(|o| (-(o as f32).powi(2) / (2.0 * sigma * sigma)).exp())
        .collect()
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
    loudness_sums: wgpu::Buffer,
    hp_sums: wgpu::Buffer,
    point_counts: wgpu::Buffer,
    stats: wgpu::Buffer,
    density: wgpu::Buffer,
    hp_mean: wgpu::Buffer,
    _reference: wgpu::Buffer,
    smoothing: Option<(wgpu::Buffer, [wgpu::BindGroup; 3])>,
    resolve_group: wgpu::BindGroup,
}

impl VoxelizeJob {
    pub fn voxel_count(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }
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
        }
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

    /// Uploads `points` and allocates a build's buffers for a `resolution`^3 grid.
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        points: &[Point],
        resolution: u32,
        smoothing_sigma: f32,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        self.prepare_with(device, points, resolution, smoothing_sigma, None, None)
    }

    /// The general form of [`VoxelizePass::prepare`]: the frequency axis `mapping` and a grid
    /// box (`None`: the mapped cloud's own).
    pub fn prepare_with(
        &self,
        device: &wgpu::Device,
        points: &[Point],
        resolution: u32,
        smoothing_sigma: f32,
        mapping: Option<&FreqMapping>,
        grid_box_override: Option<(Vec3, Vec3)>,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        Self::check_resolution(device, resolution)?;
        if !(0.0..=MAX_SMOOTHING_SIGMA).contains(&smoothing_sigma) {
            return Err(VoxelizeError::Smoothing(smoothing_sigma));
        }
        if points.len() > MAX_POINTS {
            return Err(VoxelizeError::TooManyPoints(points.len()));
        }
        let (box_min, box_max) =
            grid_box_override.unwrap_or_else(|| grid_box_mapped(points, mapping));
        let per_chunk = (storage_binding_limit(device) / std::mem::size_of::<Point>() as u64)
            .clamp(1, u64::from(u32::MAX / 5)) as usize;
        let buffers: Vec<(wgpu::Buffer, u32)> = points
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
            .collect();
        self.prepare_job(
            device,
            buffers,
            (box_min, box_max),
            resolution,
            smoothing_sigma,
            mapping,
        )
    }

    /// As [`VoxelizePass::prepare`], reading points already on the GPU: `chunks` are storage
    /// buffers of five f32 a point (the PLY record; each at most one storage binding and fewer
    /// than `u32::MAX / 5` points) with their point counts, and `bounds` is the points' bounding
    /// box (`PointCloud::bounds`). Nothing is uploaded: the points view's buffers
    /// (`PointsGpu::chunk_buffers`) serve, so the cloud is on the device once.
    pub fn prepare_from_buffers<'a>(
        &self,
        device: &wgpu::Device,
        chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
        bounds: (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        let buffers = owned_chunks(chunks);
        let total: usize = buffers.iter().map(|(_, c)| *c as usize).sum();
        let (min, max) = if total == 0 {
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY))
        } else {
            bounds
        };
        let box_ = grid_box_of_bounds(min, max);
        self.prepare_job(device, buffers, box_, resolution, smoothing_sigma, None)
    }

    /// As [`VoxelizePass::prepare_from_buffers`], on the frequency axis `mapping` and in the
    /// grid box `grid_box` (for a remapped axis, [`grid_box_mapped`] of the host's points).
    pub fn prepare_from_buffers_in_box<'a>(
        &self,
        device: &wgpu::Device,
        chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
        grid_box: (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
        mapping: Option<&FreqMapping>,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        let buffers = owned_chunks(chunks);
        self.prepare_job(
            device,
            buffers,
            grid_box,
            resolution,
            smoothing_sigma,
            mapping,
        )
    }

    fn prepare_job(
        &self,
        device: &wgpu::Device,
        mut buffers: Vec<(wgpu::Buffer, u32)>,
        (box_min, box_max): (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
        mapping: Option<&FreqMapping>,
    ) -> Result<VoxelizeJob, VoxelizeError> {
        Self::check_resolution(device, resolution)?;
        if !(0.0..=MAX_SMOOTHING_SIGMA).contains(&smoothing_sigma) {
            return Err(VoxelizeError::Smoothing(smoothing_sigma));
        }
        let point_count: usize = buffers.iter().map(|(_, c)| *c as usize).sum();
        if point_count > MAX_POINTS {
            return Err(VoxelizeError::TooManyPoints(point_count));
        }
        let dims = UVec3::splat(resolution);
        let per_unit = voxels_per_unit(dims, box_min, box_max);
        let voxels = u64::from(dims.x * dims.y * dims.z);
        let freq = mapping.map_or(FreqParams::IDENTITY, FreqMapping::params);
        let freq_table = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize::freq_table"),
            contents: bytemuck::cast_slice(
                &mapping.map_or_else(|| vec![HIDDEN], |m| m.gpu_table()),
            ),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        // Every per-voxel buffer is padded to whole groups of four voxels (16 bytes of f32, 32 of
        // sums): the per-voxel passes read and write four voxels at a time. The padding stays
        // zero (an empty voxel) and is never part of the grid.
        let group4_count = voxels.div_ceil(4);
        let loudness_sums = storage("voxelize::loudness_sums", group4_count * 32, copy);
        let hp_sums = storage("voxelize::hp_sums", group4_count * 32, copy);
        let point_counts = storage("voxelize::point_counts", group4_count * 16, copy);
        let stats = storage("voxelize::stats", STATS_WORDS as u64 * 4, copy);
        let reference = storage("voxelize::reference_sum", 16, copy);
        let density = storage("voxelize::density_grid", group4_count * 16, copy);
        let hp_mean = storage("voxelize::hp_mean_grid", group4_count * 16, copy);

        // An empty cloud still binds one (zero) point, with a count of 0.
        if buffers.is_empty() {
            let zero = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("voxelize::points_empty"),
                contents: &[0u8; std::mem::size_of::<Point>()],
                usage: wgpu::BufferUsages::STORAGE,
            });
            buffers.push((zero, 0));
        }
        let mut chunks = Vec::new();
        // Each chunk's first point's index in the cloud: the frequency jitter's seed.
        let mut first = 0u32;
        for (i, (points_buffer, count)) in buffers.into_iter().enumerate() {
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
            let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("voxelize::params_{i}")),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let buffers = [
                &params_buffer,
                &points_buffer,
                &loudness_sums,
                &hp_sums,
                &stats,
                &density,
                &hp_mean,
                &reference,
                &point_counts,
                &freq_table,
            ];
            let entries = whole_buffer_entries(&buffers);
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&format!("voxelize::bind_group_{i}")),
                layout: &self.main_layout,
                entries: &entries,
            });
            first += count;
            chunks.push(Chunk {
                count,
                bind_group,
                _points: points_buffer,
                _params: params_buffer,
            });
        }

        let resolve_buffers = [
            &chunks[0]._params,
            &loudness_sums,
            &hp_sums,
            &density,
            &hp_mean,
            &point_counts,
        ];
        let resolve_entries = whole_buffer_entries(&resolve_buffers);
        let resolve_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("voxelize::resolve_bind_group"),
            layout: &self.resolve_layout,
            entries: &resolve_entries,
        });

        let smoothing = (smoothing_sigma > 0.0).then(|| {
            let scratch = storage("voxelize::smooth_scratch", voxels * 4, copy);
            let weights = gaussian_weights(smoothing_sigma);
            let mut packed = [[0.0f32; 4]; 8];
            for (o, w) in weights.iter().enumerate() {
                packed[o / 4][o % 4] = *w;
            }
            // x: density -> scratch, y: scratch -> density, z: density -> scratch.
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
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: params.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: input.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: output.as_entire_binding(),
                        },
                    ],
                })
            };
            let groups = [
                bind_group(0, &density, &scratch),
                bind_group(1, &scratch, &density),
                bind_group(2, &density, &scratch),
            ];
            (scratch, groups)
        });

        Ok(VoxelizeJob {
            dims,
            box_min,
            box_max,
            point_count,
            chunks,
            loudness_sums,
            hp_sums,
            point_counts,
            stats,
            density,
            hp_mean,
            _reference: reference,
            smoothing,
            resolve_group,
        })
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
            &job.loudness_sums,
            &job.hp_sums,
            &job.point_counts,
            &job.stats,
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
            encoder.copy_buffer_to_buffer(scratch, 0, &job.density, 0, None);
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
        let bytes = read_buffer(device, queue, "voxelize::stats_readback", &job.stats, 16)?;
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
            density: job.density,
            hp_mean: job.hp_mean,
        }
    }

    /// Builds the grid of `points` at `resolution`^3: upload, all passes, wait, statistics.
    pub fn voxelize(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        points: &[Point],
        resolution: u32,
        smoothing_sigma: f32,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        self.voxelize_with(
            device,
            queue,
            points,
            resolution,
            smoothing_sigma,
            None,
            None,
        )
    }

    /// As [`VoxelizePass::voxelize`], in a given grid box (`None`: the cloud's own, [`grid_box`]; an A/B compare builds both grids in one box, and
    /// points outside it count in the nearest border voxel).
    pub fn voxelize_in_box(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        points: &[Point],
        resolution: u32,
        smoothing_sigma: f32,
        grid_box_override: Option<(Vec3, Vec3)>,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        self.voxelize_with(
            device,
            queue,
            points,
            resolution,
            smoothing_sigma,
            None,
            grid_box_override,
        )
    }

    /// The general form of [`VoxelizePass::voxelize`] (see [`VoxelizePass::prepare_with`]).
    #[allow(clippy::too_many_arguments)]
    pub fn voxelize_with(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        points: &[Point],
        resolution: u32,
        smoothing_sigma: f32,
        mapping: Option<&FreqMapping>,
        grid_box_override: Option<(Vec3, Vec3)>,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        let job = self.prepare_with(
            device,
            points,
            resolution,
            smoothing_sigma,
            mapping,
            grid_box_override,
        )?;
        self.build(device, queue, job)
    }

    /// As [`VoxelizePass::voxelize`], from points already on the GPU (see
    /// [`VoxelizePass::prepare_from_buffers`]).
    pub fn voxelize_buffers<'a>(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
        bounds: (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        let job = self.prepare_from_buffers(device, chunks, bounds, resolution, smoothing_sigma)?;
        self.build(device, queue, job)
    }

    /// As [`VoxelizePass::voxelize_buffers`], on the frequency axis `mapping` in `grid_box`
    /// (see [`VoxelizePass::prepare_from_buffers_in_box`]).
    #[allow(clippy::too_many_arguments)]
    pub fn voxelize_buffers_in_box<'a>(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        chunks: impl IntoIterator<Item = (&'a wgpu::Buffer, u32)>,
        grid_box: (Vec3, Vec3),
        resolution: u32,
        smoothing_sigma: f32,
        mapping: Option<&FreqMapping>,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        let job = self.prepare_from_buffers_in_box(
            device,
            chunks,
            grid_box,
            resolution,
            smoothing_sigma,
            mapping,
        )?;
        self.build(device, queue, job)
    }

    fn build(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        job: VoxelizeJob,
    ) -> Result<(VoxelGrid, VoxelStats), VoxelizeError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("voxelize::build"),
        });
        self.encode(&mut encoder, &job, None);
        queue.submit([encoder.finish()]);
        let stats = self.read_stats(device, queue, &job)?;
        Ok((Self::finish(job), stats))
    }
}
