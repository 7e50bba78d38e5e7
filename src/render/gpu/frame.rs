//! Per-frame uniforms shared by every pass (bind group 0), built from a [`FrameView`].

use glam::Vec3;

use crate::render::gpu::layouts::uniform_entry;
use crate::view::frame_view::FrameView;

/// Keep in sync with `Frame` in shaders/utils/frame.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub clip_from_data: [[f32; 4]; 4],
    pub data_from_clip: [[f32; 4]; 4],
    pub eye_position: [f32; 4],
    pub viewport: [f32; 4],
    pub light_direction: [f32; 4],
    pub flags: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 192);

impl FrameView {
    pub fn uniforms(&self) -> FrameUniforms {
        let clip_from_data = self.clip_from_data();
        let data_from_world = self.world_from_data.inverse();
        let eye = data_from_world.transform_point3(self.camera.eye());
        // Light from above and slightly behind the viewer, in world space, then into data space.
        let light_world = (Vec3::Y * 2.0 + self.camera.back()).normalize();
        let light = data_from_world.transform_vector3(light_world).normalize();
        let (w, h) = (self.width.max(1) as f32, self.height.max(1) as f32);
        FrameUniforms {
            clip_from_data: clip_from_data.to_cols_array_2d(),
            data_from_clip: clip_from_data.inverse().to_cols_array_2d(),
            eye_position: [eye.x, eye.y, eye.z, 1.0],
            viewport: [w, h, 1.0 / w, 1.0 / h],
            light_direction: [light.x, light.y, light.z, 0.0],
            flags: [self.frame_index, u32::from(self.moving), 0, 0],
        }
    }
}

/// The uniform buffers and bind group (group 0): [`FrameUniforms`] at binding 0, the palette
/// (`crate::render::colormap::PaletteUniforms`) at binding 1.
pub struct FrameBinding {
    pub buffer: wgpu::Buffer,
    pub palette: wgpu::Buffer,
    pub layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
}

impl FrameBinding {
    pub fn new(device: &wgpu::Device) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame::uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame::layout"),
            entries: &[
                uniform_entry(
                    0,
                    wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
                ),
                uniform_entry(1, wgpu::ShaderStages::VERTEX_FRAGMENT),
            ],
        });
        let palette = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame::palette"),
            size: crate::render::colormap::PALETTE_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame::bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: palette.as_entire_binding(),
                },
            ],
        });
        Self {
            buffer,
            palette,
            layout,
            bind_group,
        }
    }

    pub fn write(&self, queue: &wgpu::Queue, view: &FrameView) {
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(&view.uniforms()));
    }

    /// Writes the colour maps and background every pass reads (see `render::colormap`).
    pub fn write_palette(
        &self,
        queue: &wgpu::Queue,
        palette: &crate::render::colormap::PaletteUniforms,
    ) {
        queue.write_buffer(&self.palette, 0, &palette.bytes());
    }
}
