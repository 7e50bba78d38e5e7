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
//!
//! Two shortcuts that leave the picture as it was (tests/it/volume_skip.rs holds them to the full
//! march): bricks whose largest density the transfer function maps to no opacity are stepped
//! over in whole steps ([`skip_below`]), looked up once per brick a ray crosses; and the density
//! and its gradient come from one filtered sample of a texture computed once per grid, instead of
//! eight loads and six more trilinear samples; both derived grids come from
//! [`crate::render::volume_grids`].

pub mod progressive;

use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::layouts::{storage_entry, uniform_entry};
use crate::render::gpu::pipeline::{DrawPipeline, depth_opaque, primitives};
use crate::render::gpu::target::COLOR_FORMAT;
use crate::render::grid::VoxelGrid;
use crate::render::shaders;
pub use crate::render::transfer::TransferPreset;
use crate::render::volume_grids::{BRICK, VolumeGrids, VolumeGridsPass};

/// Opacity per voxel of ray length at transfer-function opacity 1 and opacity scale 1: a ray
/// through ten voxels of the densest region becomes about 95 % opaque.
pub const BASE_OPACITY: f32 = 0.3;
/// Emitted light per unit of absorbed opacity: above 1 the field glows rather than fogs.
pub const EMISSION_GAIN: f32 = 1.6;
/// A sample counts only where its scaled density passes this ...
pub const MIN_DENSITY: f32 = 0.002;
/// ... and its opacity per step passes this (below 1/2000 nothing shows in 8 bits).
pub const MIN_STEP_OPACITY: f32 = 0.0005;

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
    /// xyz: bricks per axis, w: brick size in voxels.
    bricks: [u32; 4],
    /// x: skip transparent bricks, y: gradient from the texture (both 0: the full march).
    modes: [u32; 4],
    /// x: [`skip_below`], y: [`MIN_DENSITY`], z: [`MIN_STEP_OPACITY`].
    skip: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<VolumeParams>() == 128);

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
    /// Every step sampled and gradients from six samples a step: the reference that the
    /// skipping of transparent bricks and the gradient texture are compared with (tests,
    /// benchmarks); the picture is the same either way.
    pub full_march: bool,
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
            full_march: false,
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

    fn opacity_per_voxel(&self) -> f32 {
        self.opacity_scale
            .clamp(*Self::OPACITY_RANGE.start(), *Self::OPACITY_RANGE.end())
            * BASE_OPACITY
    }

    fn density_scale(&self) -> f32 {
        self.density_scale
            .clamp(*Self::DENSITY_RANGE.start(), *Self::DENSITY_RANGE.end())
    }
}

/// Whether a sample of scaled density `value` adds to its pixel, as the shader decides it
/// (keep in sync with the march in shaders/volume.wgsl).
fn sample_counts(preset: TransferPreset, value: f32, opacity: f32, step: f32) -> bool {
    let alpha = preset.shape(value).1;
    let a = 1.0 - (1.0 - (alpha * opacity).clamp(0.0, 0.999)).powf(step);
    value > MIN_DENSITY && a > MIN_STEP_OPACITY
}

/// The grid density (before the density scale) below which no sample adds to the picture under
/// `settings` at `step`: every preset's opacity rises with density, so a brick whose largest
/// density is below it holds only transparent samples (a trilinear sample never exceeds the
/// voxels it reads). Found by bisection on the shader's own test, then lowered by 1 % so that
/// rounding on the GPU (its `pow`) cannot skip a sample the full march would count. Infinite
/// when no density counts.
pub fn skip_below(settings: &VolumeSettings, step: f32) -> f32 {
    let (preset, opacity) = (settings.preset, settings.opacity_per_voxel());
    let counts = |value: f32| sample_counts(preset, value, opacity, step);
    // The transfer function saturates at 1: what does not count there never counts.
    if !counts(1.0) {
        return f32::INFINITY;
    }
    let (mut transparent, mut counted) = (0.0_f32, 1.0_f32);
    for _ in 0..40 {
        let mid = 0.5 * (transparent + counted);
        if counts(mid) {
            counted = mid;
        } else {
            transparent = mid;
        }
    }
    transparent * 0.99 / settings.density_scale()
}

/// A grid bound for drawing, built when the grid is (not per frame).
pub struct VolumeGpu {
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    grids: VolumeGrids,
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
        let grids = pass.grids.build(device, grid);
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
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: grids.brick_max.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&grids.gradient),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Sampler(&pass.gradient_sampler),
                },
            ],
        });
        Self {
            params,
            bind_group,
            grids,
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
    grids: VolumeGridsPass,
    gradient_sampler: wgpu::Sampler,
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
                storage(3),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume::pipeline_layout"),
            bind_group_layouts: &[Some(&frame.layout), Some(&grid_layout)],
            immediate_size: 0,
        });
        let pipeline = DrawPipeline {
            label: "volume::pipeline",
            layout: &layout,
            module: &module,
            vertex_entry: "vs_main",
            vertex_buffers: &[],
            // Premultiplied colour over the cleared background.
            target: wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            },
            primitive: primitives(wgpu::PrimitiveTopology::TriangleList),
            // Opaque geometry's depth writes, but a ray that never passes half opacity writes
            // the far plane, which must pass over the cleared depth: less or equal.
            depth: wgpu::DepthStencilState {
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                ..depth_opaque()
            },
        }
        .build(device);
        // Clamped to the edge, as the march clamps its trilinear samples to the grid.
        let gradient_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("volume::gradient_sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self {
            pipeline,
            grid_layout,
            grids: VolumeGridsPass::new(device),
            gradient_sampler,
        }
    }

    /// Writes this frame's parameters, and on a grid's first frame submits the commands that
    /// build its derived grids; call before the render pass that draws.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        volume: &VolumeGpu,
        settings: &VolumeSettings,
        moving: bool,
    ) {
        volume.grids.submit_once(queue);
        let step = settings.step(moving);
        let fast = !settings.full_march;
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
                settings.density_scale(),
                settings.opacity_per_voxel(),
                step,
                EMISSION_GAIN,
            ],
            bricks: volume.grids.bricks.extend(BRICK).into(),
            modes: [u32::from(fast), u32::from(fast), 0, 0],
            skip: [
                skip_below(settings, step),
                MIN_DENSITY,
                MIN_STEP_OPACITY,
                0.0,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// No density under the threshold counts, and just above it (past the 1 % margin) one does.
    #[test]
    fn skip_below_is_the_shaders_own_threshold() {
        for preset in TransferPreset::ALL {
            for (density_scale, opacity_scale, step) in [
                (1.0, 1.0, 1.0),
                (3.0, 1.0, 1.0),
                (0.5, 0.2, 2.5),
                (1.0, 10.0, 0.25),
            ] {
                let settings = VolumeSettings {
                    preset,
                    density_scale,
                    opacity_scale,
                    ..Default::default()
                };
                let threshold = skip_below(&settings, step);
                assert!(threshold.is_finite() && threshold > 0.0, "{settings:?}");
                let opacity = settings.opacity_per_voxel();
                let counts =
                    |density: f32| sample_counts(preset, density * density_scale, opacity, step);
                for i in 0..=1000 {
                    let density = threshold * i as f32 / 1000.0;
                    assert!(!counts(density), "{settings:?}: {density} counts");
                }
                assert!(
                    counts(threshold * 1.02),
                    "{settings:?}: the threshold is too low"
                );
            }
        }
        // Glacial is transparent up to a scaled density of 0.2: at density scale 0.1 no density
        // of a normalized grid (at most 1) counts, and every brick is skipped.
        let faint = VolumeSettings {
            preset: TransferPreset::Glacial,
            density_scale: 0.1,
            ..Default::default()
        };
        assert!(skip_below(&faint, 1.0) > 1.0);
    }
}
