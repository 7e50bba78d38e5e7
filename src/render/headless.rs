//! Rendering without a window: the same passes into an offscreen target, read back as an image.

use crate::render::gpu::context::GpuContext;
use crate::render::gpu::readback::ReadbackError;
use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

/// Renders one frame at rest (full quality) and returns it with the target still holding it, so
/// callers can draw more (labels) over it before reading back.
pub fn render_frame(
    gpu: &GpuContext,
    renderer: &Renderer,
    data: Option<&SceneData>,
    view: &FrameView,
    settings: &RenderSettings,
) -> RenderTarget {
    let target = RenderTarget::new(&gpu.device, view.width, view.height);
    render_into(gpu, renderer, data, view, settings, &target);
    target
}

/// Renders one frame into `target` (of the view's size), kept from frame to frame.
pub fn render_into(
    gpu: &GpuContext,
    renderer: &Renderer,
    data: Option<&SceneData>,
    view: &FrameView,
    settings: &RenderSettings,
    target: &RenderTarget,
) {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("headless::frame"),
        });
    renderer.render(&gpu.queue, &mut encoder, target, data, view, settings);
    gpu.queue.submit([encoder.finish()]);
}

/// Renders one frame and reads it back.
pub fn render_image(
    gpu: &GpuContext,
    renderer: &Renderer,
    data: Option<&SceneData>,
    view: &FrameView,
    settings: &RenderSettings,
) -> Result<image::RgbaImage, ReadbackError> {
    let target = render_frame(gpu, renderer, data, view, settings);
    target.read_rgba(&gpu.device, &gpu.queue)
}
