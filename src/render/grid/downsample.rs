//! The coarse grid of the Surface view's level of detail: a grid downsampled by 2 on each axis
//! on the GPU (shaders/grid/downsample.wgsl), in the same box.
//!
//! Reads: a [`VoxelGrid`]. Writes: a grid of [`coarse_dims`] voxels whose voxel stands for a
//! 2x2x2 block of the fine one (cut at the far border where a fine dimension is odd):
//! density the block's mean, hp_mean its density-weighted mean (the plain mean where the block
//! has no density). [`reference_downsample`] is the CPU mirror the tests compare with.

use glam::UVec3;
use wgpu::util::DeviceExt;

use crate::render::gpu::layouts::{storage_entry, uniform_entry, whole_buffer_entries};
use crate::render::grid::VoxelGrid;
use crate::render::shaders;

const WORKGROUP: u32 = 256;
const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;

/// Keep in sync with `DownsampleParams` in shaders/grid/downsample.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DownsampleParams {
    fine: [u32; 4],
    coarse: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<DownsampleParams>() == 32);

/// The dims of a grid downsampled from `dims`: half of each, rounded up (at least 1).
pub fn coarse_dims(dims: UVec3) -> UVec3 {
    ((dims + UVec3::ONE) / 2).max(UVec3::ONE)
}

/// CPU mirror of shaders/grid/downsample.wgsl (same order of sums, in f32): the coarse dims,
/// density and hp_mean of the fine grid `dims`, `density`, `hp_mean`.
pub fn reference_downsample(
    dims: UVec3,
    density: &[f32],
    hp_mean: &[f32],
) -> (UVec3, Vec<f32>, Vec<f32>) {
    let coarse = coarse_dims(dims);
    let n = (coarse.x * coarse.y * coarse.z) as usize;
    let (mut out_density, mut out_hp) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for k in 0..coarse.z {
        for j in 0..coarse.y {
            for i in 0..coarse.x {
                let (mut count, mut density_sum, mut weighted, mut hp_sum) =
                    (0u32, 0f32, 0f32, 0f32);
                for dz in 0..2 {
                    for dy in 0..2 {
                        for dx in 0..2 {
                            let q = UVec3::new(2 * i + dx, 2 * j + dy, 2 * k + dz);
                            if q.cmpge(dims).any() {
                                continue;
                            }
                            let index = (q.x + dims.x * (q.y + dims.y * q.z)) as usize;
                            let (d, h) = (density[index], hp_mean[index]);
                            count += 1;
                            density_sum += d;
                            weighted += d * h;
                            hp_sum += h;
                        }
                    }
                }
                let n = count as f32;
                out_density.push(density_sum / n);
                let hp = if density_sum > 0.0 {
                    weighted / density_sum
                } else {
                    hp_sum / n
                };
                out_hp.push(hp.clamp(0.0, 1.0));
            }
        }
    }
    (coarse, out_density, out_hp)
}

/// The downsample pipeline, built once per device (or thread that downsamples).
pub struct DownsamplePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl DownsamplePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "downsample", &shaders::downsample());
        let entries = [
            uniform_entry(0, COMPUTE),
            storage_entry(1, COMPUTE, true),
            storage_entry(2, COMPUTE, true),
            storage_entry(3, COMPUTE, false),
            storage_entry(4, COMPUTE, false),
        ];
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("downsample::layout"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("downsample::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("downsample::downsample"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("downsample"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { layout, pipeline }
    }

    /// Records the downsample of `grid` into `encoder` and returns the coarse grid (filled once
    /// the encoder's work has run; the caller submits).
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        grid: &VoxelGrid,
    ) -> VoxelGrid {
        let coarse = coarse_dims(grid.dims);
        let voxels = coarse.x * coarse.y * coarse.z;
        let params = DownsampleParams {
            fine: grid.dims.extend(0).to_array(),
            coarse: coarse.extend(0).to_array(),
        };
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("downsample::params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let field = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(voxels) * 4,
                usage,
                mapped_at_creation: false,
            })
        };
        let out = VoxelGrid {
            dims: coarse,
            box_min: grid.box_min,
            box_max: grid.box_max,
            density: field("grid::coarse_density"),
            hp_mean: field("grid::coarse_hp_mean"),
        };
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("downsample::bind_group"),
            layout: &self.layout,
            entries: &whole_buffer_entries(&[
                &params,
                &grid.density,
                &grid.hp_mean,
                &out.density,
                &out.hp_mean,
            ]),
        });
        let groups = voxels.div_ceil(WORKGROUP);
        let x = groups.clamp(1, 65535);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("downsample"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
        drop(pass);
        out
    }

    /// Downsamples `grid` `levels` times (each halves every axis), submits the work and returns
    /// the coarsest grid; does not wait.
    pub fn downsample(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &VoxelGrid,
        levels: u32,
    ) -> VoxelGrid {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("downsample"),
        });
        let mut out = self.record(device, &mut encoder, grid);
        for _ in 1..levels {
            out = self.record(device, &mut encoder, &out);
        }
        queue.submit([encoder.finish()]);
        out
    }
}
