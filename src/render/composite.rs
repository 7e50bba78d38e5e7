//! Composite: draws the offscreen scene texture into another render pass (the window's frame).
//!
//! Reads: a [`RenderTarget`]'s colour texture. Writes: the colour attachment of the pass it is
//! recorded into, whose format is given at creation. If that format is sRGB, the shader's
//! gamma-encoded values are decoded first so the screen shows what the PNGs show.

use crate::render::gpu::target::RenderTarget;
use crate::render::shaders;

pub struct CompositePass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    bind_group: Option<wgpu::BindGroup>,
}

impl CompositePass {
    pub fn new(device: &wgpu::Device, output_format: wgpu::TextureFormat) -> Self {
        let module = shaders::module(device, "composite", &shaders::composite());
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("composite::layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("composite::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let entry = if output_format.is_srgb() {
            "fs_decode_srgb"
        } else {
            "fs_main"
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("composite::pipeline"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[Some(output_format.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("composite::sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self {
            pipeline,
            layout,
            sampler,
            bind_group: None,
        }
    }

    /// Points the pass at a (new) target; call whenever the target is recreated.
    pub fn set_source(&mut self, device: &wgpu::Device, target: &RenderTarget) {
        self.bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("composite::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&target.color_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        }));
    }

    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(bind_group) = &self.bind_group {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

/// An offscreen render target sized to a view and the pass that composites it into egui's
/// frame: the window's 3D view and each half of its compare, the web page's view and halves.
pub struct Offscreen {
    target: Option<RenderTarget>,
    composite: CompositePass,
}

impl Offscreen {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        Self {
            target: None,
            composite: CompositePass::new(device, format),
        }
    }

    /// Makes the target `width` x `height`; true when it was made anew (what it held is gone).
    pub fn ensure_size(&mut self, device: &wgpu::Device, width: u32, height: u32) -> bool {
        if self
            .target
            .as_ref()
            .is_some_and(|t| t.has_size(width, height))
        {
            return false;
        }
        let target = RenderTarget::new(device, width, height);
        self.composite.set_source(device, &target);
        self.target = Some(target);
        true
    }

    pub fn target(&self) -> Option<&RenderTarget> {
        self.target.as_ref()
    }

    /// Composites the target into the callback's viewport.
    pub fn draw(&self, render_pass: &mut wgpu::RenderPass<'_>) {
        self.composite.draw(render_pass);
    }
}
