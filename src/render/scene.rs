//! The scene: one cloud's GPU data plus the passes that draw it, in the order the view needs.
//!
//! [`Renderer`] is built once per device and owns every pass; [`SceneData`] is built once per
//! loaded cloud. [`Renderer::render`] records one frame into a [`RenderTarget`].

use glam::{Mat4, Vec3};

use crate::cloud::{DataMode, PointCloud};
use crate::render::frame::{FrameBinding, FrameView};
use crate::render::grid::VoxelGrid;
use crate::render::lines::{LinesGpu, LinesPass, box_with_ticks};
use crate::render::markers::{MarkerBox, MarkersPass};
use crate::render::mesh::{SurfacePass, SurfaceSettings};
use crate::render::points::{PointStyle, PointsGpu, PointsPass};
use crate::render::target::{BACKGROUND, RenderTarget};

/// What the 3D view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ViewKind {
    Points,
    Surface,
    Volume,
}

impl ViewKind {
    pub const ALL: [ViewKind; 3] = [ViewKind::Points, ViewKind::Surface, ViewKind::Volume];

    pub fn name(self) -> &'static str {
        match self {
            ViewKind::Points => "Points",
            ViewKind::Surface => "Surface",
            ViewKind::Volume => "Volume",
        }
    }

    /// Whether this build can draw the view; the others are shown as not yet available.
    pub fn available(self) -> bool {
        matches!(self, ViewKind::Points | ViewKind::Surface)
    }

    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|v| v.name().eq_ignore_ascii_case(name))
    }
}

/// Everything the user can set about how the scene is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub view: ViewKind,
    pub points: PointStyle,
    pub show_box: bool,
    /// Translucent boxes and planes over the data: the playhead, a loop range, a timeline song.
    pub markers: Vec<MarkerBox>,
    // Surface view.
    pub surface: SurfaceSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            view: ViewKind::Points,
            points: PointStyle::default(),
            show_box: true,
            markers: Vec::new(),
            surface: SurfaceSettings::default(),
        }
    }
}

/// World space from data space for a data mode: stretches the cloud's normalized cube into a
/// shape that reads well (time is the long axis; a timeline is longer still).
pub fn world_from_data(mode: DataMode) -> Mat4 {
    let scale = match mode {
        DataMode::Song => Vec3::new(1.6, 0.8, 1.0),
        DataMode::Timeline => Vec3::new(3.0, 0.8, 1.0),
        DataMode::Generic => Vec3::ONE,
    };
    Mat4::from_scale(scale)
}

/// A loaded cloud's GPU resources.
pub struct SceneData {
    pub points: PointsGpu,
    pub box_lines: LinesGpu,
    /// The box drawn around the data, in data space.
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub world_from_data: Mat4,
    /// The voxelized fields the Surface (and Volume) views are built from; None until set.
    pub grid: Option<VoxelGrid>,
}

impl SceneData {
    pub fn new(device: &wgpu::Device, renderer: &Renderer, cloud: &PointCloud) -> Self {
        Self::with_chunk_limit(device, renderer, cloud, PointsGpu::chunk_limit(device))
    }

    /// As [`SceneData::new`], with the points split into chunks of at most `max_chunk_bytes`.
    pub fn with_chunk_limit(
        device: &wgpu::Device,
        renderer: &Renderer,
        cloud: &PointCloud,
        max_chunk_bytes: u64,
    ) -> Self {
        let points = PointsGpu::upload(device, &renderer.points, &cloud.points, max_chunk_bytes);
        let (box_min, box_max) = data_box(cloud);
        let axes = &cloud.meta.axes;
        let tick_positions =
            |axis: &crate::axes::Axis| -> Vec<f32> { axis.ticks(8).iter().map(|t| t.at).collect() };
        let (tx, ty, tz) = (
            tick_positions(&axes.x),
            tick_positions(&axes.y),
            tick_positions(&axes.z),
        );
        let lines = box_with_ticks(box_min, box_max, [&tx, &ty, &tz], [0.55, 0.6, 0.68, 0.8]);
        Self {
            points,
            box_lines: LinesGpu::upload(device, "scene::box_lines", &lines),
            box_min,
            box_max,
            world_from_data: world_from_data(cloud.meta.mode),
            grid: None,
        }
    }

    /// The data box in world space, for fitting the camera.
    pub fn world_box(&self) -> (Vec3, Vec3) {
        let a = self.world_from_data.transform_point3(self.box_min);
        let b = self.world_from_data.transform_point3(self.box_max);
        (a.min(b), a.max(b))
    }
}

/// The box the axes are drawn on: the full normalized cube, where tick positions live.
pub fn data_box(_cloud: &PointCloud) -> (Vec3, Vec3) {
    (Vec3::splat(-1.0), Vec3::splat(1.0))
}

/// Every pass, built once per device.
pub struct Renderer {
    pub frame: FrameBinding,
    pub points: PointsPass,
    pub lines: LinesPass,
    pub markers: MarkersPass,
    pub surface: SurfacePass,
}

impl Renderer {
    pub fn new(device: &wgpu::Device) -> Self {
        let frame = FrameBinding::new(device);
        Self {
            points: PointsPass::new(device, &frame),
            lines: LinesPass::new(device, &frame),
            markers: MarkersPass::new(device, &frame),
            surface: SurfacePass::new(device, &frame),
            frame,
        }
    }

    /// Records one frame of `data` seen from `view` into `target`.
    pub fn render(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &RenderTarget,
        data: Option<&SceneData>,
        view: &FrameView,
        settings: &RenderSettings,
    ) {
        self.frame.write(queue, view);
        self.markers.prepare(queue, &settings.markers);
        if let Some(data) = data {
            self.points
                .prepare(queue, &data.points, &settings.points, view.moving);
            if settings.view == ViewKind::Surface {
                self.surface
                    .prepare(queue, encoder, data.grid.as_ref(), &settings.surface);
            }
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene::main_pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.color_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: BACKGROUND[0],
                        g: BACKGROUND[1],
                        b: BACKGROUND[2],
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let Some(data) = data else {
            return;
        };
        match settings.view {
            ViewKind::Surface => self.surface.draw(&mut pass, &self.frame),
            ViewKind::Points | ViewKind::Volume => {
                self.points.draw(
                    &mut pass,
                    &self.frame,
                    &data.points,
                    &settings.points,
                    view.moving,
                );
            }
        }
        if settings.show_box {
            self.lines.draw(&mut pass, &self.frame, &data.box_lines);
        }
        // Last, so translucent markers blend over everything drawn before them.
        self.markers
            .draw(&mut pass, &self.frame, settings.markers.len());
    }
}
