//! The offscreen colour and depth textures every pass draws into, and reading the colour back.
//!
//! The window composites the colour texture into egui's frame; the headless renderer reads it
//! back to an RGBA image. Colours are gamma-encoded (`Rgba8Unorm`), as egui's are, so what the
//! passes write is what lands on screen and in the PNG.

use crate::render::gpu::readback::{ReadbackError, map_buffer_after};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The background the scene is cleared to (gamma-encoded RGB).
pub const BACKGROUND: [f64; 3] = [0.055, 0.063, 0.078];

pub struct RenderTarget {
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub depth: wgpu::Texture,
    pub depth_view: wgpu::TextureView,
    pub width: u32,
    pub height: u32,
}

impl RenderTarget {
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let size = wgpu::Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: 1,
        };
        let color = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("target::color"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOR_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("target::depth"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            // Copies: the window's progressive points keep their own target (ui/progressive.rs).
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        Self {
            color_view: color.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            color,
            depth,
            width: size.width,
            height: size.height,
        }
    }

    /// True when the target already has this size.
    pub fn has_size(&self, width: u32, height: u32) -> bool {
        self.width == width.max(1) && self.height == height.max(1)
    }

    /// Records a copy of this target's colour and depth into `to` (of the same size): a picture
    /// drawn once, to draw more over it (the window's refined points, a video's still view).
    pub fn copy_into(&self, encoder: &mut wgpu::CommandEncoder, to: &RenderTarget) {
        let size = wgpu::Extent3d {
            width: self.width,
            height: self.height,
            depth_or_array_layers: 1,
        };
        for (from, to) in [(&self.color, &to.color), (&self.depth, &to.depth)] {
            encoder.copy_texture_to_texture(from.as_image_copy(), to.as_image_copy(), size);
        }
    }

    /// Copies the colour texture to the CPU as tightly packed RGBA8 rows, top row first.
    pub fn read_rgba(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<image::RgbaImage, ReadbackError> {
        let mut pixels = vec![0; self.width as usize * self.height as usize * 4];
        TargetReader::new(device, self).read_into(device, queue, self, &mut pixels)?;
        image::RgbaImage::from_raw(self.width, self.height, pixels).ok_or_else(|| {
            ReadbackError::Map {
                what: "the rendered image".into(),
                reason: "its size does not match the target's".into(),
            }
        })
    }
}

/// A staging buffer that reads a target of one size back, kept from frame to frame (a video
/// reads thousands of frames: a new buffer and image each time cost more than the copy).
pub struct TargetReader {
    buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    padded_row: u32,
}

impl TargetReader {
    pub fn new(device: &wgpu::Device, target: &RenderTarget) -> Self {
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row = (target.width * 4).div_ceil(align) * align;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("target::readback"),
            size: u64::from(padded_row) * u64::from(target.height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Self {
            buffer,
            width: target.width,
            height: target.height,
            padded_row,
        }
    }

    /// Submits the copy of `target`'s colour (of this reader's size) into the staging buffer
    /// and returns at once with the submission's index; [`TargetReader::finish_into`] reads it.
    /// Between the two the caller may submit more work (a video's next frame): with two
    /// readers, frame k is read while frame k+1 draws.
    pub fn submit_copy(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &RenderTarget,
    ) -> Result<wgpu::SubmissionIndex, ReadbackError> {
        if !target.has_size(self.width, self.height) {
            return Err(ReadbackError::Map {
                what: "the rendered image".into(),
                reason: "its size does not match the target's".into(),
            });
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("target::readback"),
        });
        self.record_copy(&mut encoder, target);
        Ok(queue.submit([encoder.finish()]))
    }

    /// Waits for the copy submitted as `index` ([`TargetReader::submit_copy`]), not for work
    /// submitted after it, and writes it into `out` as tightly packed RGBA8 rows, top row
    /// first; `out` holds exactly width x height x 4 bytes.
    pub fn finish_into(
        &self,
        device: &wgpu::Device,
        index: wgpu::SubmissionIndex,
        out: &mut [u8],
    ) -> Result<(), ReadbackError> {
        let row = self.width as usize * 4;
        if out.len() != row * self.height as usize {
            return Err(ReadbackError::Map {
                what: "the rendered image".into(),
                reason: "its size does not match the target's".into(),
            });
        }
        map_buffer_after(
            device,
            &self.buffer,
            Some(index),
            "the rendered image",
            |bytes| self.unpad(bytes, out),
        )
    }

    fn record_copy(&self, encoder: &mut wgpu::CommandEncoder, target: &RenderTarget) {
        encoder.copy_texture_to_buffer(
            target.color.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// The staging buffer's padded rows into `out`, packed.
    fn unpad(&self, bytes: &[u8], out: &mut [u8]) {
        let row = self.width as usize * 4;
        for (dst, src) in out
            .chunks_exact_mut(row)
            .zip(bytes.chunks_exact(self.padded_row as usize))
        {
            dst.copy_from_slice(&src[..row]);
        }
    }

    /// Copies `target`'s colour (of this reader's size) into `out` as tightly packed RGBA8
    /// rows, top row first; `out` holds exactly width x height x 4 bytes.
    pub fn read_into(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &RenderTarget,
        out: &mut [u8],
    ) -> Result<(), ReadbackError> {
        if out.len() != self.width as usize * 4 * self.height as usize {
            return Err(ReadbackError::Map {
                what: "the rendered image".into(),
                reason: "its size does not match the target's".into(),
            });
        }
        let index = self.submit_copy(device, queue, target)?;
        self.finish_into(device, index, out)
    }
}
