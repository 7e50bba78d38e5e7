//! The page's view on a downlevel adapter (WebGL2, where the browser has no WebGPU): no compute
//! passes and no storage buffers in any stage, so neither [`Renderer`](crate::render::scene::Renderer)
//! (whose points read storage buffers and whose grid, surface and volume passes are compute or
//! read storage buffers) nor its scene can be built there.
//!
//! Reads: the page's cloud and the frame's settings. Writes: the offscreen target the page
//! composites, as [`Renderer::render`](crate::render::scene::Renderer::render) does for the
//! Points view: the same frame uniforms and palette, the points as vertex attributes
//! ([`crate::render::points_attributes`]: the same discs and colours from the same records), the
//! box with its ticks and the playhead marker of the window's passes, which need no storage.

use glam::Vec3;

use crate::data::cloud::PointCloud;
use crate::render::colormap::PaletteUniforms;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::target::RenderTarget;
use crate::render::lines::{LinesGpu, LinesPass};
use crate::render::markers::MarkersPass;
use crate::render::points::PointStyle;
use crate::render::points_attributes::{AttributePointsGpu, AttributePointsPass};
use crate::render::scene::{RenderSettings, begin_main_pass, box_lines, data_box};
use crate::view::frame_view::FrameView;

/// Whether `adapter` runs every pass of the page (WebGPU); else only the Points view of this
/// module, and the reason why.
pub(super) fn full_view_or_reason(
    adapter: &wgpu::Adapter,
    limits: &wgpu::Limits,
) -> Result<(), String> {
    let needed = wgpu::DownlevelFlags::COMPUTE_SHADERS
        | wgpu::DownlevelFlags::VERTEX_STORAGE
        | wgpu::DownlevelFlags::FRAGMENT_STORAGE;
    if adapter.get_info().backend == wgpu::Backend::Gl
        || !adapter.get_downlevel_capabilities().flags.contains(needed)
    {
        return Err(
            "this browser draws with WebGL2, which has no compute passes and no \
                    storage buffers: the voxel grid is built by compute passes and the volume \
                    reads it from storage buffers"
                .to_string(),
        );
    }
    crate::render::gpu::context::check_limits(limits)
        .map_err(|reason| format!("the browser's GPU is too small for the grid's passes: {reason}"))
}

/// The Points view's passes and the cloud's buffers on a downlevel adapter.
pub(super) struct PointsRenderer {
    frame: FrameBinding,
    points_pass: AttributePointsPass,
    lines: LinesPass,
    markers: crate::render::markers::MarkersPass,
    points: AttributePointsGpu,
    box_lines: LinesGpu,
}

impl PointsRenderer {
    pub(super) fn new(device: &wgpu::Device, cloud: &PointCloud, style: &PointStyle) -> Self {
        let frame = FrameBinding::new(device);
        let points_pass = AttributePointsPass::new(device, &frame);
        let points = AttributePointsGpu::upload(device, &points_pass, &cloud.points, style);
        let (box_min, box_max): (Vec3, Vec3) = data_box();
        Self {
            lines: LinesPass::new(device, &frame),
            markers: MarkersPass::new(device, &frame),
            box_lines: box_lines(device, &cloud.meta.axes, box_min, box_max),
            points_pass,
            points,
            frame,
        }
    }

    /// Records one frame of the points seen from `view` into `target`.
    pub(super) fn render(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &RenderTarget,
        view: &FrameView,
        settings: &RenderSettings,
    ) {
        self.frame.write(queue, view);
        self.frame.write_palette(
            queue,
            &PaletteUniforms::new(&settings.colours, settings.volume.preset),
        );
        self.markers.prepare(queue, &settings.markers);
        self.points_pass
            .prepare(queue, &self.points, &settings.points);
        let [r, g, b] = settings.colours.background.rgb().map(f64::from);
        let mut pass = begin_main_pass(encoder, target, Some(wgpu::Color { r, g, b, a: 1.0 }));
        self.points_pass
            .draw(&mut pass, &self.frame, &self.points, view.moving);
        if settings.show_box {
            self.lines.draw(&mut pass, &self.frame, &self.box_lines);
        }
        self.markers
            .draw(&mut pass, &self.frame, settings.markers.len());
    }
}
