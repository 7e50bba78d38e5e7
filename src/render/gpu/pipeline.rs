//! The pipeline states the scene's draw passes share, once (re_renderer's shared pipeline
//! constants): the depth tests of opaque geometry and of what is drawn over it, the colour
//! target with and without alpha blending, the primitive states, and the render pipeline built
//! from them ([`DrawPipeline`]). A pass names only what is its own: its shader, its bindings,
//! its vertex layout and which of these states it takes.
//!
//! Every draw pass renders into the scene's [`RenderTarget`](super::target::RenderTarget):
//! colour [`COLOR_FORMAT`], depth [`DEPTH_FORMAT`], one sample.

use crate::render::gpu::target::{COLOR_FORMAT, DEPTH_FORMAT};

/// The depth test of `compare`, writing depth or not.
fn depth(write: bool, compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// Opaque geometry (points, the surface): nearer wins and writes its depth.
pub fn depth_opaque() -> wgpu::DepthStencilState {
    depth(true, wgpu::CompareFunction::Less)
}

/// What is drawn over the opaque geometry (the box, the markers): hidden behind it, shown where
/// it lies on it (equal depth passes), writing no depth of its own.
pub fn depth_over() -> wgpu::DepthStencilState {
    depth(false, wgpu::CompareFunction::LessEqual)
}

/// The colour target of opaque geometry: written as is.
pub fn opaque_target() -> wgpu::ColorTargetState {
    COLOR_FORMAT.into()
}

/// The colour target of translucent lines and boxes: straight alpha over what is there.
pub fn alpha_blended_target() -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format: COLOR_FORMAT,
        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// Primitives of `topology`, counter-clockwise front faces, no culling (wgpu's defaults).
pub fn primitives(topology: wgpu::PrimitiveTopology) -> wgpu::PrimitiveState {
    wgpu::PrimitiveState {
        topology,
        ..Default::default()
    }
}

/// A render pipeline of the scene: the pass's own shader, layout and vertex buffers with the
/// shared states above; the fragment entry point is `fs_main`.
pub struct DrawPipeline<'a> {
    /// The pipeline's label, `"pass::what"`.
    pub label: &'a str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'a str,
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub target: wgpu::ColorTargetState,
    pub primitive: wgpu::PrimitiveState,
    pub depth: wgpu::DepthStencilState,
}

impl DrawPipeline<'_> {
    pub fn build(self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.module,
                entry_point: Some(self.vertex_entry),
                compilation_options: Default::default(),
                buffers: self.vertex_buffers,
            },
            fragment: Some(wgpu::FragmentState {
                module: self.module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(self.target)],
            }),
            primitive: self.primitive,
            depth_stencil: Some(self.depth),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        })
    }
}
