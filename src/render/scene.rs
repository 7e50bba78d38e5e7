//! The scene: one cloud's GPU data plus the passes that draw it, in the order the view needs.
//!
//! [`Renderer`] is built once per device and owns every pass; [`SceneData`] is built once per
//! loaded cloud. [`Renderer::render`] records one frame into a [`RenderTarget`]; a progressive
//! points frame is recorded slice by slice ([`Renderer::render_points_slice`]) and finished by
//! [`Renderer::render_overlay`]. All three start the frame alike ([`Renderer::begin_frame`]:
//! the frame's uniforms, the markers, the render pass) and draw in one order: the view's
//! opaque geometry, then what is drawn over it ([`Renderer::draw_over`]: the box, then the
//! translucent markers).

use glam::{Mat4, Vec3};

use crate::data::axes::Axes;
use crate::data::cloud::{DataMode, PointCloud};
use crate::data::freq_axis::{FreqAxis, FreqMapping};
use crate::render::colormap::{Background, Colours, PaletteUniforms};
use crate::render::gpu::frame::FrameBinding;
use crate::render::gpu::target::RenderTarget;
use crate::render::lines::{LinesGpu, LinesPass, box_with_ticks};
use crate::render::markers::{MarkerBox, MarkersPass};
use crate::render::points::{PointStyle, PointsGpu, PointsPass};
use crate::render::surface::SurfaceSettings;
use crate::render::surface::lod::SurfaceDetail;
use crate::render::surface::pass::SurfacePass;
use crate::render::surface::state::ExtractedSurface;
use crate::view::frame_view::FrameView;
// Volume view and voxel grid.
use crate::render::grid::VoxelGrid;
use crate::render::grid::difference::DifferencePass;
use crate::render::grid::voxelize::{
    VoxelSettings, VoxelStats, VoxelizeError, VoxelizePass, VoxelizeRequest,
};
use crate::render::grid::voxelize_cpu::grid_box_mapped;
use crate::render::volume::{VolumeGpu, VolumePass, VolumeSettings};

/// Staging per piece when [`SceneData::upload`] sends a cloud's points.
pub const UPLOAD_STAGING_BYTES: u64 = 32 << 20;

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

    pub fn parse(name: &str) -> Option<Self> {
        crate::parse_value(name)
    }
}

command_line_names!(ViewKind, |view| view.name().to_lowercase());

/// Everything the user can set about how the scene is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub view: ViewKind,
    pub points: PointStyle,
    pub show_box: bool,
    /// Translucent boxes and planes over the data: the playhead, a loop range, a timeline song.
    pub markers: Vec<MarkerBox>,
    /// How the voxel grid is built (volume and surface views).
    pub voxels: VoxelSettings,
    /// How the volume view draws the grid.
    pub volume: VolumeSettings,
    /// How the surface view extracts and lights the isosurface.
    pub surface: SurfaceSettings,
    /// Colour maps (hp, density) and the background (`render::colormap`).
    pub colours: Colours,
    /// Which of the surface's meshes the Surface view draws (level of detail: the window asks
    /// for the coarse one while moving on a slow device; `render::surface::lod`).
    pub surface_detail: SurfaceDetail,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            view: ViewKind::Points,
            points: PointStyle::default(),
            show_box: true,
            markers: Vec::new(),
            voxels: VoxelSettings::default(),
            volume: VolumeSettings::default(),
            surface: SurfaceSettings::default(),
            colours: Colours::default(),
            surface_detail: SurfaceDetail::Full,
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
    /// The voxel grid, built on demand by [`SceneData::ensure_grid`].
    pub grid: Option<VoxelGrid>,
    pub grid_stats: Option<VoxelStats>,
    grid_key: Option<(u32, u32, FreqAxis)>,
    /// The frequency axis shown ([`SceneData::set_freq_axis`]); `None`: z as stored.
    pub freq: Option<FreqMapping>,
    /// The cloud's axes as the view shows them (z on the frequency axis shown).
    pub axes: Axes,
    volume: Option<VolumeGpu>,
    /// The isosurface of the grid, extracted by [`Renderer::surface`] when the Surface view
    /// draws (each cloud keeps its own).
    pub surface: ExtractedSurface,
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
        Self::with_points(device, cloud, points)
    }

    /// As [`SceneData::new`], the points' buffers made beforehand (on another thread,
    /// `PointsGpu::buffers` of `cloud`'s points with [`PointsGpu::chunk_limit`]).
    pub fn from_buffers(
        device: &wgpu::Device,
        renderer: &Renderer,
        cloud: &PointCloud,
        buffers: crate::render::points::PointBuffers,
    ) -> Self {
        let points = PointsGpu::from_buffers(device, &renderer.points, buffers);
        Self::with_points(device, cloud, points)
    }

    /// As [`SceneData::new`], the points sent through the queue in pieces of
    /// [`UPLOAD_STAGING_BYTES`] (see `PointsGpu::upload_bounded`): what the window and the
    /// `render` command use, so a cloud's upload costs the host one piece of staging, not a
    /// second copy of the cloud. Once this returns (and [`SceneData::ensure_grid`] builds grids
    /// from the GPU copy), `cloud.points` is needed only for picking.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        cloud: &PointCloud,
    ) -> Self {
        let points = PointsGpu::upload_bounded(
            device,
            queue,
            &renderer.points,
            &cloud.points,
            PointsGpu::chunk_limit(device),
            UPLOAD_STAGING_BYTES,
        );
        Self::with_points(device, cloud, points)
    }

    /// As [`SceneData::upload`], taking the host's points as they are sent
    /// (`PointsGpu::upload_draining`): for a caller that never picks (the `render` command).
    /// `cloud.points` is empty afterwards; its bounds, metadata and path stay.
    pub fn upload_draining(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        cloud: &mut PointCloud,
    ) -> Self {
        let points = PointsGpu::upload_draining(
            device,
            queue,
            &renderer.points,
            &mut cloud.points,
            PointsGpu::chunk_limit(device),
            UPLOAD_STAGING_BYTES,
        );
        Self::with_points(device, cloud, points)
    }

    fn with_points(device: &wgpu::Device, cloud: &PointCloud, points: PointsGpu) -> Self {
        let (box_min, box_max) = data_box();
        let axes = cloud.meta.axes.clone();
        Self {
            points,
            box_lines: box_lines(device, &axes, box_min, box_max),
            box_min,
            box_max,
            world_from_data: world_from_data(cloud.meta.mode),
            grid: None,
            grid_stats: None,
            grid_key: None,
            freq: None,
            axes,
            volume: None,
            surface: ExtractedSurface::new(),
        }
    }

    /// Shows `cloud` (the cloud this data was made from) on the frequency axis `axis`: the
    /// points, the box's ticks and [`SceneData::axes`] follow at once, the grid at the next
    /// [`SceneData::ensure_grid`]. A cloud without a frequency axis (a timeline) takes only
    /// `Linear` (as stored); anything else is an error naming the reason.
    pub fn set_freq_axis(
        &mut self,
        device: &wgpu::Device,
        renderer: &Renderer,
        cloud: &PointCloud,
        axis: FreqAxis,
    ) -> Result<(), String> {
        let mapping = match FreqMapping::new(&cloud.meta, axis) {
            Ok(mapping) => Some(mapping).filter(|m| !m.is_identity()),
            Err(_) if axis == FreqAxis::Linear => None,
            Err(reason) => return Err(format!("{}: {reason}", cloud.path.display())),
        };
        self.points
            .set_freq(device, &renderer.points, mapping.as_ref());
        self.axes = match &mapping {
            Some(m) => m.view_axes(&cloud.meta.axes),
            None => cloud.meta.axes.clone(),
        };
        self.box_lines = box_lines(device, &self.axes, self.box_min, self.box_max);
        self.freq = mapping;
        Ok(())
    }

    /// The frequency axis shown.
    pub fn freq_axis(&self) -> FreqAxis {
        self.freq.as_ref().map_or(FreqAxis::Linear, |m| m.axis)
    }

    /// Builds the voxel grid of `cloud` (the cloud this data was made from; its mode and bounds
    /// are read, the points come from the GPU copy; on a remapped frequency axis the host's
    /// points give the remapped box) unless one with the
    /// same resolution and smoothing exists. Returns whether it was rebuilt. Never per frame:
    /// call when the view needs a grid, the cloud is loaded or the voxel settings change.
    pub fn ensure_grid(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        cloud: &PointCloud,
        settings: &VoxelSettings,
    ) -> Result<bool, VoxelizeError> {
        let resolution = settings.resolution_for(cloud.meta.mode);
        let sigma = settings.smoothing_for(cloud.meta.mode);
        let key = (resolution, sigma.to_bits(), self.freq_axis());
        if self.grid.is_some() && self.grid_key == Some(key) {
            return Ok(false);
        }
        // Free the old grid before building the new one.
        self.volume = None;
        self.grid = None;
        // From the points already on the device: no second upload. On the stored axis the
        // host's copy of the points is not read (a caller may have dropped it); a remapped
        // axis reads it for the remapped box.
        let mapping = self.freq.as_ref();
        let request = VoxelizeRequest::on_device(
            self.points.chunk_buffers(),
            (cloud.bounds.min, cloud.bounds.max),
            resolution,
            sigma,
        )
        .mapped(mapping)
        .in_box(mapping.map(|m| grid_box_mapped(&cloud.points, Some(m))))
        .with_host(&cloud.points);
        let (grid, stats) = renderer.voxelize.voxelize(device, queue, &request)?;
        self.volume = Some(VolumeGpu::new(device, &renderer.volume, &grid));
        self.grid = Some(grid);
        self.grid_stats = Some(stats);
        self.grid_key = Some(key);
        Ok(true)
    }

    /// Installs a grid built elsewhere (an A/B compare's grids in their shared box and scale,
    /// or their difference) as if [`SceneData::ensure_grid`] had built it with `settings` for
    /// data of `mode`.
    pub fn set_grid(
        &mut self,
        device: &wgpu::Device,
        renderer: &Renderer,
        grid: VoxelGrid,
        stats: Option<VoxelStats>,
        mode: DataMode,
        settings: &VoxelSettings,
    ) {
        self.volume = Some(VolumeGpu::new(device, &renderer.volume, &grid));
        self.grid = Some(grid);
        self.grid_stats = stats;
        self.grid_key = Some((
            settings.resolution_for(mode),
            settings.smoothing_for(mode).to_bits(),
            self.freq_axis(),
        ));
        self.surface = ExtractedSurface::new();
    }

    /// Whether a grid built with `settings` for `cloud` is already there.
    pub fn grid_matches(&self, cloud: &PointCloud, settings: &VoxelSettings) -> bool {
        let resolution = settings.resolution_for(cloud.meta.mode);
        self.grid.is_some()
            && self.grid_key
                == Some((
                    resolution,
                    settings.smoothing_for(cloud.meta.mode).to_bits(),
                    self.freq_axis(),
                ))
    }

    /// The data box in world space, for fitting the camera.
    pub fn world_box(&self) -> (Vec3, Vec3) {
        world_box(self.world_from_data, self.box_min, self.box_max)
    }
}

/// The box around the data with the ticks of `axes`.
pub(crate) fn box_lines(
    device: &wgpu::Device,
    axes: &Axes,
    box_min: Vec3,
    box_max: Vec3,
) -> LinesGpu {
    let tick_positions = |axis: &crate::data::axes::Axis| -> Vec<f32> {
        axis.ticks(8).iter().map(|t| t.at).collect()
    };
    let (tx, ty, tz) = (
        tick_positions(&axes.x),
        tick_positions(&axes.y),
        tick_positions(&axes.z),
    );
    let lines = box_with_ticks(box_min, box_max, [&tx, &ty, &tz], [0.55, 0.6, 0.68, 0.8]);
    LinesGpu::upload(device, "scene::box_lines", &lines)
}

/// The data-space box `[min, max]` in world space, for fitting the camera.
pub fn world_box(world_from_data: Mat4, min: Vec3, max: Vec3) -> (Vec3, Vec3) {
    let a = world_from_data.transform_point3(min);
    let b = world_from_data.transform_point3(max);
    (a.min(b), a.max(b))
}

/// The box the axes are drawn on: the full normalized cube, where tick positions live.
pub fn data_box() -> (Vec3, Vec3) {
    (Vec3::splat(-1.0), Vec3::splat(1.0))
}

/// The clear colour of `background` (gamma-encoded, as the target holds it).
fn clear_colour(background: Background) -> wgpu::Color {
    let [r, g, b] = background.rgb().map(f64::from);
    wgpu::Color { r, g, b, a: 1.0 }
}

/// Every pass, built once per device.
pub struct Renderer {
    pub frame: FrameBinding,
    pub points: PointsPass,
    pub lines: LinesPass,
    pub markers: MarkersPass,
    pub voxelize: VoxelizePass,
    pub volume: VolumePass,
    pub surface: SurfacePass,
    /// A/B compare: the difference of two grids.
    pub difference: DifferencePass,
}

impl Renderer {
    pub fn new(device: &wgpu::Device) -> Self {
        let frame = FrameBinding::new(device);
        Self {
            points: PointsPass::new(device, &frame),
            lines: LinesPass::new(device, &frame),
            markers: MarkersPass::new(device, &frame),
            voxelize: VoxelizePass::new(device, &frame),
            volume: VolumePass::new(device, &frame),
            surface: SurfacePass::new(device, &frame),
            difference: DifferencePass::new(device),
            frame,
        }
    }

    /// Starts a frame seen from `view` into `target`: writes the frame's uniforms (camera,
    /// palette) and the markers of `settings`, and begins the scene's render pass, cleared to
    /// the background or (`clear` false) drawing over what the target holds. Every recorder
    /// writes them, not only a frame's first: between two recordings another render (a
    /// screenshot, a moving frame) may have written other values. They are small.
    fn begin_frame<'e>(
        &self,
        queue: &wgpu::Queue,
        encoder: &'e mut wgpu::CommandEncoder,
        target: &RenderTarget,
        view: &FrameView,
        settings: &RenderSettings,
        clear: bool,
    ) -> wgpu::RenderPass<'e> {
        self.frame.write(queue, view);
        self.frame.write_palette(
            queue,
            &PaletteUniforms::new(&settings.colours, settings.volume.preset),
        );
        self.markers.prepare(queue, &settings.markers);
        begin_main_pass(
            encoder,
            target,
            clear.then(|| clear_colour(settings.colours.background)),
        )
    }

    /// What is drawn over the view's opaque geometry, last: the box, then the markers (last of
    /// all, so the translucent markers blend over everything drawn before them).
    fn draw_over(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        data: &SceneData,
        settings: &RenderSettings,
    ) {
        if settings.show_box {
            self.lines.draw(pass, &self.frame, &data.box_lines);
        }
        self.markers.draw(pass, &self.frame, settings.markers.len());
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
        if let Some(data) = data {
            self.points
                .prepare(queue, &data.points, &settings.points, view.moving);
            if settings.view == ViewKind::Surface {
                self.surface
                    .prepare(queue, &data.surface, data.grid.as_ref(), &settings.surface);
            }
            if let (ViewKind::Volume, Some(volume)) = (settings.view, &data.volume) {
                self.volume
                    .prepare(queue, volume, &settings.volume, view.moving);
            }
        }
        let mut pass = self.begin_frame(queue, encoder, target, view, settings, true);
        let Some(data) = data else {
            return;
        };
        match (settings.view, &data.volume) {
            (ViewKind::Surface, _)
                if data.grid.is_some() && !data.surface.ready_for(settings.surface_detail) =>
            {
                // Until the grid's first surface comes (it is extracted in the background), the
                // points' sparse subset stands in: an empty box said nothing of the song, and the
                // coarse mesh that comes first is a pale slab (at rest the full one is waited for).
                self.points.draw_lod_from(
                    &mut pass,
                    &self.frame,
                    &data.points,
                    &settings.points,
                    0,
                );
            }
            (ViewKind::Surface, _) if data.grid.is_some() => {
                self.surface.draw(
                    &mut pass,
                    &self.frame,
                    &data.surface,
                    data.grid.as_ref().map(|grid| (grid, &settings.surface)),
                    settings.surface_detail,
                );
            }
            (ViewKind::Volume, Some(volume)) => {
                self.volume.draw(&mut pass, &self.frame, volume);
            }
            // Until a grid is built (ensure_grid), the points stand in.
            (ViewKind::Points | ViewKind::Surface | ViewKind::Volume, _) => {
                self.points.draw(
                    &mut pass,
                    &self.frame,
                    &data.points,
                    &settings.points,
                    view.moving,
                );
            }
        }
        self.draw_over(&mut pass, data, settings);
    }

    /// One slice of a progressive points frame (`points::progressive_ranges`) into `target`:
    /// the slice that starts at point 0 clears the target; every slice adds its points over what
    /// the target holds (colour and depth kept); the slice that ends at the last point draws the
    /// box and the markers. After all slices the target holds exactly what [`Renderer::render`]
    /// draws at rest.
    pub fn render_points_slice(
        &self,
        recording: Recording<'_>,
        data: &SceneData,
        view: &FrameView,
        settings: &RenderSettings,
        range: std::ops::Range<u64>,
    ) {
        let Recording {
            queue,
            encoder,
            target,
        } = recording;
        let first = range.start == 0;
        let last = range.end >= data.points.total;
        self.points
            .prepare(queue, &data.points, &settings.points, false);
        let mut pass = self.begin_frame(queue, encoder, target, view, settings, first);
        self.points
            .draw_range(&mut pass, &self.frame, &data.points, range);
        // The box and the markers after every point, in the single pass's order.
        if last {
            self.draw_over(&mut pass, data, settings);
        }
    }

    /// The volume of `data` at full quality in the rows `rows` of `target` alone (the pass's
    /// scissor), over what the target holds there, or cleared first (`clear`: the whole
    /// target, colour and depth); no box, no markers. Band by band, the target ends holding
    /// what [`Renderer::render`]'s volume pass writes (`render/volume/progressive.rs`).
    pub fn render_volume_band(
        &self,
        recording: Recording<'_>,
        data: &SceneData,
        view: &FrameView,
        settings: &RenderSettings,
        rows: std::ops::Range<u32>,
        clear: bool,
    ) {
        let Recording {
            queue,
            encoder,
            target,
        } = recording;
        if let Some(volume) = &data.volume {
            self.volume
                .prepare(queue, volume, &settings.volume, view.moving);
        }
        let mut pass = self.begin_frame(queue, encoder, target, view, settings, clear);
        let rows = rows.start.min(target.height)..rows.end.min(target.height);
        if let (Some(volume), false) = (&data.volume, rows.is_empty()) {
            pass.set_scissor_rect(0, rows.start, target.width, rows.end - rows.start);
            self.volume.draw(&mut pass, &self.frame, volume);
        }
    }

    /// The box and the markers of `settings` over what `target` holds (points drawn slice by
    /// slice, copied in): the last step of a progressive frame, redrawn alone when only the
    /// markers (the playhead) change. With `rest_from`, first the moving subset of the points
    /// from that index on (those no slice has drawn yet), so the picture is whole, sparse where
    /// the slices have not reached, while it refines; call it after a slice
    /// ([`Renderer::render_points_slice`] prepared the points' parameters).
    pub fn render_overlay(
        &self,
        recording: Recording<'_>,
        data: &SceneData,
        view: &FrameView,
        settings: &RenderSettings,
        rest_from: Option<u64>,
    ) {
        let Recording {
            queue,
            encoder,
            target,
        } = recording;
        let mut pass = self.begin_frame(queue, encoder, target, view, settings, false);
        if let Some(first) = rest_from {
            self.points.draw_lod_from(
                &mut pass,
                &self.frame,
                &data.points,
                &settings.points,
                first,
            );
        }
        self.draw_over(&mut pass, data, settings);
    }
}

/// Where a recorder records: the queue the frame's uniforms are written through, the encoder
/// and the target.
pub struct Recording<'a> {
    pub queue: &'a wgpu::Queue,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub target: &'a RenderTarget,
}

/// Whether [`Renderer::render`] draws `data`'s points (not a surface or a volume) at rest with
/// `settings`: the frames a progressive points render can stand for.
pub fn draws_points_at_rest(settings: &RenderSettings, data: &SceneData) -> bool {
    match settings.view {
        ViewKind::Points => true,
        ViewKind::Surface => data.grid.is_none(),
        ViewKind::Volume => data.volume.is_none(),
    }
}

/// The scene's render pass into `target`: cleared to the background (`clear`) or loading what the
/// target holds.
pub(crate) fn begin_main_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &RenderTarget,
    clear: Option<wgpu::Color>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("scene::main_pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &target.color_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: match clear {
                    Some(color) => wgpu::LoadOp::Clear(color),
                    None => wgpu::LoadOp::Load,
                },
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &target.depth_view,
            depth_ops: Some(wgpu::Operations {
                load: if clear.is_some() {
                    wgpu::LoadOp::Clear(1.0)
                } else {
                    wgpu::LoadOp::Load
                },
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
