//! Volume view: ray marching through the voxel grid (paper section 3.3).
//!
//! Reads: a [`VoxelGrid`]'s density and hp_mean buffers (bound once per grid by
//! [`VolumeGpu::new`]) and the frame uniforms. Writes: colour (premultiplied, blended over the
//! cleared background) and depth. How: one full-screen triangle; each fragment intersects its
//! pixel's ray with the grid box, marches it in fixed steps measured in voxels (one voxel by
//! default, coarser while the camera moves) from a jittered start, samples the density
//! trilinearly, maps it through a transfer function ([`TransferPreset`], mirrored in
//! `transfer.rs`), optionally shades it by the density gradient and tints it by the mean hp, and
//! composites front to back until the opacity passes 0.99. Depth is written where the opacity
//! first passes one half, so lines drawn afterwards hide behind dense volume only.

use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry};
use crate::render::gpu::target::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::grid::VoxelGrid;
use crate::render::shaders;
pub use crate::render::transfer::TransferPreset;

/// Opacity per voxel of ray length at transfer-function opacity 1 and opacity scale 1: a ray
/// through ten voxels of the densest region becomes about 95 % opaque.
pub const BASE_OPACITY: f32 = 0.3;
/// Emitted light per unit of absorbed opacity: above 1 the field glows rather than fogs.
pub const EMISSION_GAIN: f32 = 1.6;

/// Keep in sync with `VolumeParams` in shaders/volume.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct VolumeParams {
    dims: [u32; 4],
    box_min: [f32; 4],
    box_max: [f32; 4],
    /// x: preset, y: hp tint, z: shading, w: most steps.
    options: [u32; 4],
    /// x: density scale, y: opacity scale times base opacity, z: step in voxels, w: emission.
    controls: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<VolumeParams>() == 80);

/// How the volume is drawn. None of these rebuild the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSettings {
    pub preset: TransferPreset,
    /// Multiplies the density before the transfer function (0.1 to 8).
    pub density_scale: f32,
    /// Multiplies the opacity (0.05 to 10).
    pub opacity_scale: f32,
    /// Colours by the mean hp of the voxels (the points' red-to-blue palette).
    pub hp_tint: bool,
    /// Lights the volume by its density gradient.
    pub shading: bool,
    /// Ray step in voxels at rest (0.25 to 4); smaller is finer and slower.
    pub step_voxels: f32,
    /// The step is this many times longer while the camera moves.
    pub moving_step_factor: f32,
}

impl Default for VolumeSettings {
    fn default() -> Self {
        Self {
            preset: TransferPreset::Classic,
            density_scale: 1.0,
            opacity_scale: 1.0,
            hp_tint: false,
            shading: true,
            step_voxels: 1.0,
            moving_step_factor: 2.5,
        }
    }
}

impl VolumeSettings {
    pub const DENSITY_RANGE: std::ops::RangeInclusive<f32> = 0.1..=8.0;
    pub const OPACITY_RANGE: std::ops::RangeInclusive<f32> = 0.05..=10.0;
    pub const STEP_RANGE: std::ops::RangeInclusive<f32> = 0.25..=4.0;

    /// The step used for a frame.
    pub fn step(&self, moving: bool) -> f32 {
        let step = self
            .step_voxels
            .clamp(*Self::STEP_RANGE.start(), *Self::STEP_RANGE.end());
        if moving {
            step * self.moving_step_factor.max(1.0)
        } else {
            step
        }
    }
}

/// A grid bound for drawing, built when the grid is (not per frame).
pub struct VolumeGpu {
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    dims: glam::UVec3,
    box_min: glam::Vec3,
    box_max: glam::Vec3,
}

impl VolumeGpu {
    pub fn new(device: &wgpu::Device, pass: &VolumePass, grid: &VoxelGrid) -> Self {
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("volume::params"),
            size: std::mem::size_of::<VolumeParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume::grid_bind_group"),
            layout: &pass.grid_layout,
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
                    resource: grid.hp_mean.as_entire_binding(),
                },
            ],
        });
        Self {
            params,
            bind_group,
            dims: grid.dims,
            box_min: grid.box_min,
            box_max: grid.box_max,
        }
    }
}

/// The ray-marching pipeline, built once.
pub struct VolumePass {
    pipeline: wgpu::RenderPipeline,
    grid_layout: wgpu::BindGroupLayout,
}

impl VolumePass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
        let module = shaders::module(device, "volume", &shaders::volume());
        let storage = |binding| storage_entry(binding, wgpu::ShaderStages::FRAGMENT, true);
        let grid_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume::grid_layout"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                storage(1),
                storage(2),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&grid_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("volume::pipeline"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        Self {
            pipeline,
            grid_layout,
        }
    }

    /// Writes this frame's parameters; call before the render pass that draws.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        volume: &VolumeGpu,
        settings: &VolumeSettings,
        moving: bool,
    ) {
        let step = settings.step(moving);
        let diagonal = volume.dims.as_vec3().length();
        let params = VolumeParams {
            dims: volume.dims.extend(0).into(),
            box_min: volume.box_min.extend(0.0).into(),
            box_max: volume.box_max.extend(0.0).into(),
            options: [
                settings.preset.index(),
                u32::from(settings.hp_tint),
                u32::from(settings.shading),
                (diagonal / step).ceil() as u32 + 2,
            ],
            controls: [
                settings.density_scale.clamp(
                    *VolumeSettings::DENSITY_RANGE.start(),
                    *VolumeSettings::DENSITY_RANGE.end(),
                ),
                settings.opacity_scale.clamp(
                    *VolumeSettings::OPACITY_RANGE.start(),
                    *VolumeSettings::OPACITY_RANGE.end(),
                ) * BASE_OPACITY,
                step,
                EMISSION_GAIN,
            ],
        };
        queue.write_buffer(&volume.params, 0, bytemuck::bytes_of(&params));
    }

    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &FrameBinding, volume: &VolumeGpu) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_bind_group(1, &volume.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
