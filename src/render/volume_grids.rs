//! The volume view's derived grids, built once per voxel grid (not per frame).
//!
//! Reads: a [`VoxelGrid`]'s density buffer. Writes: the density gradient at every voxel centre
//! (central differences, one voxel apart, clamped to the grid) and the density itself into an
//! rgba16float 3D texture that the ray march samples once a step with linear filtering, instead
//! of eight loads for the density and six trilinear samples for the gradient; and the largest density of each brick of [`BRICK`] voxels a side, with the
//! one-voxel apron a trilinear sample inside the brick can read, which the march uses to skip
//! bricks that the transfer function leaves transparent. How: two compute entry points of
//! shaders/volume_grids.wgsl, one invocation per voxel and one per brick, recorded into a
//! command buffer that [`crate::render::volume::VolumePass::prepare`] submits before the first
//! frame that draws the grid.

use wgpu::util::DeviceExt;

use crate::render::gpu::layouts::{storage_entry, uniform_entry};
use crate::render::grid::VoxelGrid;
use crate::render::shaders;

/// Bricks are this many voxels a side: 16^3 bricks for a song's 128^3 grid, 28^3 for a
/// timeline's 224^3. Smaller bricks fit the field's edges closer but cost more look-ups (one per
/// brick a ray crosses): under Classic, 60 % of the demo's 8^3 bricks hold opacity, 55 % of
/// its 4^3 and 67 % of its 16^3 ones.
pub const BRICK: u32 = 8;
/// The gradient and density texture's format: filterable without an optional feature, and its
/// 11-bit mantissa keeps the picture of the full-precision march (PSNR above 60 dB on the demo,
/// tests/it/volume_skip.rs).
pub const GRADIENT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Keep in sync with `@workgroup_size` in shaders/volume_grids.wgsl.
const WORKGROUP: u32 = 4;

/// Keep in sync with `GridParams` in shaders/volume_grids.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GridParams {
    dims: [u32; 4],
    /// xyz: bricks per axis, w: brick size in voxels.
    bricks: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<GridParams>() == 32);

/// Bricks per axis of a grid of `dims` voxels.
pub fn brick_counts(dims: glam::UVec3) -> glam::UVec3 {
    (dims + glam::UVec3::splat(BRICK - 1)) / BRICK
}

/// The derived grids of one voxel grid, and the commands that fill them until they are submitted.
pub struct VolumeGrids {
    pub gradient: wgpu::TextureView,
    pub brick_max: wgpu::Buffer,
    pub bricks: glam::UVec3,
    pending: std::sync::Mutex<Option<wgpu::CommandBuffer>>,
}

impl VolumeGrids {
    /// Submits the commands that fill the grids, once; later calls do nothing.
    pub fn submit_once(&self, queue: &wgpu::Queue) {
        let pending = self
            .pending
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take();
        if let Some(commands) = pending {
            queue.submit([commands]);
        }
    }
}

/// The two compute pipelines, built once.
pub struct VolumeGridsPass {
    layout: wgpu::BindGroupLayout,
    gradients: wgpu::ComputePipeline,
    brick_maxima: wgpu::ComputePipeline,
}

impl VolumeGridsPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = shaders::module(device, "volume_grids", &shaders::volume_grids());
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume_grids::layout"),
            entries: &[
                uniform_entry(0, compute),
                storage_entry(1, compute, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: compute,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: GRADIENT_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D3,
                    },
                    count: None,
                },
                storage_entry(3, compute, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume_grids::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str, label: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            gradients: pipeline("gradients", "volume_grids::gradients"),
            brick_maxima: pipeline("brick_maxima", "volume_grids::brick_maxima"),
            layout,
        }
    }

    /// Allocates the derived grids of `grid` and records the commands that fill them.
    pub fn build(&self, device: &wgpu::Device, grid: &VoxelGrid) -> VolumeGrids {
        let dims = grid.dims;
        let bricks = brick_counts(dims);
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("volume_grids::params"),
            contents: bytemuck::bytes_of(&GridParams {
                dims: dims.extend(0).into(),
                bricks: bricks.extend(BRICK).into(),
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let gradient = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("volume_grids::gradient"),
            size: wgpu::Extent3d {
                width: dims.x,
                height: dims.y,
                depth_or_array_layers: dims.z,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: GRADIENT_FORMAT,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let gradient = gradient.create_view(&Default::default());
        let brick_max = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("volume_grids::brick_max"),
            size: u64::from(bricks.x * bricks.y * bricks.z) * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume_grids::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: grid.density.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&gradient),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: brick_max.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("volume_grids::encoder"),
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("volume_grids::pass"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &bind_group, &[]);
            let groups = |n: glam::UVec3| (n + glam::UVec3::splat(WORKGROUP - 1)) / WORKGROUP;
            pass.set_pipeline(&self.gradients);
            let g = groups(dims);
            pass.dispatch_workgroups(g.x, g.y, g.z);
            pass.set_pipeline(&self.brick_maxima);
            let g = groups(bricks);
            pass.dispatch_workgroups(g.x, g.y, g.z);
        }
        VolumeGrids {
            gradient,
            brick_max,
            bricks,
            pending: std::sync::Mutex::new(Some(encoder.finish())),
        }
    }
}
