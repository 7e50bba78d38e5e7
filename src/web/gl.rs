//! The page's view on a downlevel adapter (WebGL2, where the browser has no WebGPU): no compute
//! passes, no storage buffers in any stage and no indirect draws, so neither
//! [`Renderer`](crate::render::scene::Renderer) (whose points read storage buffers and whose grid,
//! surface and volume passes are compute or read storage buffers) nor its scene can be built
//! there.
//!
//! Reads: the page's cloud, the surface the CPU extracted ([`GlSurface`]) and the frame's
//! settings. Writes: the offscreen target the page composites, as
//! [`Renderer::render`](crate::render::scene::Renderer::render) does for the Points and Surface
//! views: the same frame uniforms and palette, the points as vertex attributes
//! ([`crate::render::points_attributes`]: the same discs and colours from the same records), the
//! surface through the window's surface draw pipeline (vertex attributes already) with a plain
//! indexed draw, the box with its ticks and the playhead marker of the window's passes, which
//! need no storage. The Volume view stays off: its ray march reads the grid, its bricks' maxima
//! and its gradients from storage buffers that compute passes fill.

use glam::Vec3;

use crate::data::cloud::PointCloud;
use crate::render::colormap::PaletteUniforms;
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::target::RenderTarget;
use crate::render::lines::{LinesGpu, LinesPass};
use crate::render::markers::MarkersPass;
use crate::render::points::PointStyle;
use crate::render::points_attributes::{AttributePointsGpu, AttributePointsPass};
use crate::render::scene::{RenderSettings, ViewKind, begin_main_pass, box_lines, data_box};
use crate::render::surface::pass::SurfacePass;
use crate::view::frame_view::FrameView;

use super::gl_surface::GlSurface;

/// Whether `adapter` runs every pass of the page (WebGPU); else the Points and Surface views of
/// this module, and the reason why the Volume view is off.
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
            "this browser draws with WebGL2, which has no compute passes and no storage \
             buffers: the volume's ray march reads the voxel grid from storage buffers"
                .to_string(),
        );
    }
    crate::render::gpu::context::check_limits(limits)
        .map_err(|reason| format!("the browser's GPU is too small for the grid's passes: {reason}"))
}

/// The Points and Surface views' passes and the cloud's buffers on a downlevel adapter.
pub(super) struct GlRenderer {
    frame: FrameBinding,
    points_pass: AttributePointsPass,
    surface_pass: SurfacePass,
    lines: LinesPass,
    markers: crate::render::markers::MarkersPass,
    points: AttributePointsGpu,
    /// The surface extracted on the CPU (built when the Surface view is first shown).
    pub(super) surface: GlSurface,
    box_lines: LinesGpu,
}

impl GlRenderer {
    pub(super) fn new(device: &wgpu::Device, cloud: &PointCloud, style: &PointStyle) -> Self {
        let frame = FrameBinding::new(device);
        let points_pass = AttributePointsPass::new(device, &frame);
        let points = AttributePointsGpu::upload(device, &points_pass, &cloud.points, style);
        let (box_min, box_max): (Vec3, Vec3) = data_box();
        Self {
            surface_pass: SurfacePass::new(device, &frame),
            surface: GlSurface::default(),
            lines: LinesPass::new(device, &frame),
            markers: MarkersPass::new(device, &frame),
            box_lines: box_lines(device, &cloud.meta.axes, box_min, box_max),
            points_pass,
            points,
            frame,
        }
    }

    /// Records one frame seen from `view` into `target`: the surface in the Surface view once
    /// one is extracted, the points otherwise.
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
        let surface = match settings.view {
            ViewKind::Surface => self.surface.mesh(),
            ViewKind::Points | ViewKind::Volume => None,
        };
        if surface.is_some() {
            self.surface_pass.write_style(queue, &settings.surface);
        } else {
            self.points_pass
                .prepare(queue, &self.points, &settings.points);
        }
        let [r, g, b] = settings.colours.background.rgb().map(f64::from);
        let mut pass = begin_main_pass(encoder, target, Some(wgpu::Color { r, g, b, a: 1.0 }));
        match surface {
            Some((vertices, indices, count)) => {
                self.surface_pass
                    .draw_mesh(&mut pass, &self.frame, vertices, indices, count);
            }
            None => {
                self.points_pass
                    .draw(&mut pass, &self.frame, &self.points, view.moving);
            }
        }
        if settings.show_box {
            self.lines.draw(&mut pass, &self.frame, &self.box_lines);
        }
        self.markers
            .draw(&mut pass, &self.frame, settings.markers.len());
    }
}
