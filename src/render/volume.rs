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
//!
//! One pipeline per [`VolumeVariant`] (full march or not, shading, hp tint), each compiled from
//! the shader with its variant's constants, built on first use: lavapipe runs both sides of a
//! branch under a lane mask, so one shader branching on uniforms paid every variant's loads in
//! every step.

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
    /// x: preset, w: most steps (y, z unused: the variant's).
    options: [u32; 4],
    /// x: density scale, y: opacity scale times base opacity, z: step in voxels, w: emission.
    controls: [f32; 4],
    /// xyz: bricks per axis, w: brick size in voxels.
    bricks: [u32; 4],
    /// Unused (the variant's full march).
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

/// What a volume pipeline's shader is compiled for (the constants at the top of
/// shaders/volume.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VolumeVariant {
    /// Every step sampled and gradients from six samples (`FULL_MARCH`).
    pub full_march: bool,
    /// Lit by the density gradient (`SHADING`).
    pub shading: bool,
    /// Coloured by the mean hp (`HP_TINT`).
    pub hp_tint: bool,
}

impl VolumeVariant {
    /// Every variant, in the order of [`Self::index`].
    pub const ALL: [VolumeVariant; 8] = {
        let mut all = [VolumeVariant {
            full_march: false,
            shading: false,
            hp_tint: false,
        }; 8];
        let mut i = 0;
        while i < 8 {
            all[i] = VolumeVariant {
                full_march: i & 1 != 0,
                shading: i & 2 != 0,
                hp_tint: i & 4 != 0,
            };
            i += 1;
        }
        all
    };

    pub fn of(settings: &VolumeSettings) -> Self {
        Self {
            full_march: settings.full_march,
            shading: settings.shading,
            hp_tint: settings.hp_tint,
        }
    }

    fn index(self) -> usize {
        usize::from(self.full_march)
            | usize::from(self.shading) << 1
            | usize::from(self.hp_tint) << 2
    }

    /// The composed volume shader with this variant's constants in place of the defaults that
    /// shaders/volume.wgsl declares ([`VARIANT_DEFAULTS`]; a unit test holds the two together).
    pub fn source(self) -> String {
        let mut source = shaders::volume();
        for ((name, default), value) in
            VARIANT_DEFAULTS
                .into_iter()
                .zip([self.full_march, self.shading, self.hp_tint])
        {
            source = source.replace(
                &format!("const {name}: bool = {default};"),
                &format!("const {name}: bool = {value};"),
            );
        }
        source
    }
}

/// The variant's constants as shaders/volume.wgsl declares them, in the order of
/// [`VolumeVariant`]'s fields.
const VARIANT_DEFAULTS: [(&str, bool); 3] =
    [("FULL_MARCH", false), ("SHADING", true), ("HP_TINT", false)];

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
    /// The pipeline of the variant the last [`VolumePass::prepare`] asked for.
    pipeline: std::sync::Mutex<Option<wgpu::RenderPipeline>>,
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
            pipeline: std::sync::Mutex::new(None),
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
    device: wgpu::Device,
    layout: wgpu::PipelineLayout,
    /// One pipeline per [`VolumeVariant`] (by its index), built on first use: each is a shader
    /// compile, which lavapipe does in LLVM.
    pipelines: std::sync::Mutex<[Option<wgpu::RenderPipeline>; 8]>,
    grid_layout: wgpu::BindGroupLayout,
    grids: VolumeGridsPass,
    gradient_sampler: wgpu::Sampler,
}

impl VolumePass {
    pub fn new(device: &wgpu::Device, frame: &FrameBinding) -> Self {
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
            device: device.clone(),
            layout,
            pipelines: std::sync::Mutex::new(Default::default()),
            grid_layout,
            grids: VolumeGridsPass::new(device),
            gradient_sampler,
        }
    }

    /// The pipeline of `variant`, compiled the first time it is asked for.
    fn pipeline(&self, variant: VolumeVariant) -> wgpu::RenderPipeline {
        let mut pipelines = self
            .pipelines
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        pipelines[variant.index()]
            .get_or_insert_with(|| {
                let module = shaders::module(&self.device, "volume", &variant.source());
                DrawPipeline {
                    label: "volume::pipeline",
                    layout: &self.layout,
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
                    // Opaque geometry's depth writes, but a ray that never passes half opacity
                    // writes the far plane, which must pass over the cleared depth: less or
                    // equal.
                    depth: wgpu::DepthStencilState {
                        depth_compare: Some(wgpu::CompareFunction::LessEqual),
                        ..depth_opaque()
                    },
                }
                .build(&self.device)
            })
            .clone()
    }

    /// Writes this frame's parameters, picks the pipeline of the settings' variant (compiling
    /// it on first use), and on a grid's first frame submits the commands that
    /// build its derived grids; call before the render pass that draws.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        volume: &VolumeGpu,
        settings: &VolumeSettings,
        moving: bool,
    ) {
        volume.grids.submit_once(queue);
        *volume
            .pipeline
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) =
            Some(self.pipeline(VolumeVariant::of(settings)));
        let step = settings.step(moving);
        let diagonal = volume.dims.as_vec3().length();
        let params = VolumeParams {
            dims: volume.dims.extend(0).into(),
            box_min: volume.box_min.extend(0.0).into(),
            box_max: volume.box_max.extend(0.0).into(),
            options: [
                settings.preset.index(),
                0,
                0,
                (diagonal / step).ceil() as u32 + 2,
            ],
            controls: [
                settings.density_scale(),
                settings.opacity_per_voxel(),
                step,
                EMISSION_GAIN,
            ],
            bricks: volume.grids.bricks.extend(BRICK).into(),
            modes: [0; 4],
            skip: [
                skip_below(settings, step),
                MIN_DENSITY,
                MIN_STEP_OPACITY,
                0.0,
            ],
        };
        queue.write_buffer(&volume.params, 0, bytemuck::bytes_of(&params));
    }

    /// Draws with the pipeline [`Self::prepare`] picked for `volume`; nothing before a prepare.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, frame: &FrameBinding, volume: &VolumeGpu) {
        let pipeline = volume
            .pipeline
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone();
        let Some(pipeline) = pipeline else {
            return;
        };
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &frame.bind_group, &[]);
        pass.set_bind_group(1, &volume.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each variant's shader declares its own constants, once each: a rename in
    /// shaders/volume.wgsl that the replacement misses would compile every variant alike.
    #[test]
    fn each_variant_compiles_its_own_constants() {
        let plain = shaders::volume();
        for (name, default) in VARIANT_DEFAULTS {
            let line = format!("const {name}: bool = {default};");
            assert_eq!(
                plain.matches(&line).count(),
                1,
                "shaders/volume.wgsl: `{line}`"
            );
        }
        let mut indices = std::collections::HashSet::new();
        for variant in VolumeVariant::ALL {
            assert!(indices.insert(variant.index()), "{variant:?}: index taken");
            let source = variant.source();
            for (name, value) in [
                ("FULL_MARCH", variant.full_march),
                ("SHADING", variant.shading),
                ("HP_TINT", variant.hp_tint),
            ] {
                let line = format!("const {name}: bool = {value};");
                assert_eq!(source.matches(&line).count(), 1, "{variant:?}: `{line}`");
                assert!(!source.contains(&format!("const {name}: bool = {};", !value)));
            }
        }
    }

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
