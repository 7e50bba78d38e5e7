//! The bridge between egui and the render passes: one `egui_wgpu` paint callback
//! ([`paint_callback`]) for two jobs ([`OffscreenJob`]), the 3D view's [`ViewCallback`] here and
//! the A/B compare's [`CompareCallback`] in `bridge/compare.rs`.
//!
//! `prepare` renders the job into an [`Offscreen`] target sized to its view, `paint`
//! composites it into egui's frame. GPU state lives in egui_wgpu's callback resources: one
//! [`ViewResources`], created once when the window opens, and the compare's
//! [`CompareResources`] beside it, made when a compare first needs them.
//!
//! The scene is rendered only when what it shows changed ([`FrameCache`]): the camera, the size,
//! the settings (markers and playhead included), the cloud or its GPU data. Frames that change
//! only the panels, the hover read-out or a tooltip composite the last render again, so hovering
//! over a cloud of millions of points costs a composite, not a scene.

use std::collections::HashMap;
use std::sync::Arc;

use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};

use crate::data::cloud::PointCloud;
pub(crate) use crate::render::composite::Offscreen;
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::render::surface::state::ExtractionStatus;
pub use crate::ui::frame_cache::{FrameCache, RenderKey};
use crate::view::frame_view::FrameView;

mod compare;
pub(in crate::ui) use compare::CompareSliced;
pub use compare::{CompareCallback, CompareResources};

/// GPU state owned by the window, kept in egui_wgpu's callback resources. The window reaches it
/// through [`ViewResources::read`] and [`ViewResources::write`] (one lock and one look-up of
/// egui's type map for as much as a caller needs); the methods below are what it does there.
pub struct ViewResources {
    pub renderer: Renderer,
    /// The window's device and queue (egui_wgpu's), for uploads, grid builds and read-backs.
    device: wgpu::Device,
    queue: wgpu::Queue,
    offscreen: Offscreen,
    /// Uploaded clouds by the app's cloud id.
    pub scenes: HashMap<u64, SceneData>,
    /// What the target holds, to skip frames that would render the same scene again.
    pub cache: FrameCache,
    /// Large clouds at rest: drawn a slice a frame (`ui/progressive.rs`).
    pub progressive: crate::ui::progressive::ProgressivePoints,
    /// The volume at rest: a coarse picture, then bands of full-quality rows a frame
    /// (`render/volume/progressive.rs`).
    pub volume_refine: crate::render::volume::progressive::ProgressiveVolume<RenderKey>,
    /// To ask for the next frame from `prepare` while the points fill in.
    repaint: Option<egui::Context>,
}

/// Where the surface of one cloud stands on the GPU, as the scripted isovalue sweep reads it
/// (`ui/iso_sweep.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceProgress {
    /// The isovalue of the surface on screen (None before the first).
    pub shown_iso_value: Option<f32>,
    /// Whether an extraction is under way on the worker (the window comes back for it).
    pub extracting: bool,
    /// Extractions installed so far: full surfaces and coarse ones of the level of detail.
    pub installed: u64,
    pub coarse_installed: u64,
}

/// A song's scene put on another frequency axis ([`ViewResources::set_freq_axis`]): the labels
/// and the mapping the window keeps with the cloud.
pub struct FreqAxisShown {
    pub labels: crate::ui::labels::AxisLabels,
    /// The mapping from stored to shown z (None: z as stored).
    pub mapping: Option<crate::data::freq_axis::FreqMapping>,
}

impl ViewResources {
    pub fn install(render_state: &egui_wgpu::RenderState) {
        let device = &render_state.device;
        device.on_uncaptured_error(Arc::new(on_device_error));
        let resources = ViewResources {
            renderer: Renderer::new(device),
            device: device.clone(),
            queue: render_state.queue.clone(),
            offscreen: Offscreen::new(device, render_state.target_format),
            scenes: HashMap::new(),
            cache: FrameCache::default(),
            progressive: Default::default(),
            volume_refine: Default::default(),
            repaint: None,
        };
        render_state
            .renderer
            .write()
            .callback_resources
            .insert(resources);
    }

    /// Runs `f` with the window's GPU state under egui_wgpu's read lock. None before
    /// [`ViewResources::install`].
    pub fn read<T>(
        render_state: &egui_wgpu::RenderState,
        f: impl FnOnce(&ViewResources) -> T,
    ) -> Option<T> {
        let renderer = render_state.renderer.read();
        renderer.callback_resources.get::<ViewResources>().map(f)
    }

    /// Runs `f` with the window's GPU state under egui_wgpu's write lock. None before
    /// [`ViewResources::install`].
    pub fn write<T>(
        render_state: &egui_wgpu::RenderState,
        f: impl FnOnce(&mut ViewResources) -> T,
    ) -> Option<T> {
        let mut renderer = render_state.renderer.write();
        renderer
            .callback_resources
            .get_mut::<ViewResources>()
            .map(f)
    }

    /// Uploads a cloud under `id`, replacing what was there.
    pub fn upload(&mut self, id: u64, cloud: &PointCloud) {
        // The old buffers go first, so two clouds' buffers never coexist.
        self.scenes.remove(&id);
        let data = SceneData::upload(&self.device, &self.queue, &self.renderer, cloud);
        self.scenes.insert(id, data);
        self.cache.invalidate_points();
    }

    /// Drops cloud `id`'s scene.
    pub fn remove(&mut self, id: u64) {
        self.scenes.remove(&id);
        self.cache.invalidate_points();
    }

    /// Renders the cloud `id` offscreen at the view's size and submits its read-back, labels
    /// to draw over it once read (`PendingPicture::finish`), for a screenshot (the axes and
    /// labels alone, with a renderer of its own, before the window's GPU state is installed
    /// or without the cloud's scene).
    pub fn screenshot(
        render_state: &egui_wgpu::RenderState,
        id: u64,
        cloud: &PointCloud,
        view: &FrameView,
        settings: &RenderSettings,
    ) -> Result<crate::picture::PendingPicture, crate::ui::screenshot::ScreenshotError> {
        let gpu = crate::render::gpu::context::GpuContext {
            adapter: render_state.adapter.clone(),
            device: render_state.device.clone(),
            queue: render_state.queue.clone(),
        };
        let shot = Self::read(render_state, |r| {
            let data = r.scenes.get(&id)?;
            Some(crate::picture::submit_view(
                &gpu,
                &r.renderer,
                Some((cloud, data)),
                view,
                settings,
            ))
        })
        .flatten();
        shot.unwrap_or_else(|| {
            let renderer = Renderer::new(&gpu.device);
            crate::picture::submit_view(&gpu, &renderer, None, view, settings)
        })
    }

    /// Save PNG's quick way: when the view's target holds, complete, the Points, Surface or
    /// Volume view of cloud `id` that a render of `view` with `settings` draws (at rest, at the
    /// view's size, no refinement under way), its read-back is submitted with the labels to
    /// draw over it, and no point or ray is drawn again. The markers are the ones the target
    /// holds (the playhead of the last frame drawn, which moves every frame during playback).
    /// `None` when the target holds anything else (the view fills in, moves, or shows another
    /// scene: wait for it, `state/save_wait.rs`, or render the picture:
    /// [`ViewResources::screenshot`]). The same pixels as a render: the slices of a progressive
    /// frame end as the single pass (tests/it/big_clouds.rs); the volume's bands end as one
    /// render's volume pass, with the jitter of the refinement's first frame
    /// (render/volume/progressive.rs).
    pub fn shown_picture(
        render_state: &egui_wgpu::RenderState,
        id: u64,
        cloud: &PointCloud,
        view: &FrameView,
        settings: &RenderSettings,
    ) -> Option<Result<crate::picture::PendingPicture, crate::ui::screenshot::ScreenshotError>>
    {
        use crate::render::scene::ViewKind;
        if !matches!(
            settings.view,
            ViewKind::Points | ViewKind::Surface | ViewKind::Volume
        ) {
            return None;
        }
        let gpu = crate::render::gpu::context::GpuContext {
            adapter: render_state.adapter.clone(),
            device: render_state.device.clone(),
            queue: render_state.queue.clone(),
        };
        Self::read(render_state, |r| {
            let held = r.cache.holds()?;
            let mut at_rest = *view;
            at_rest.moving = false;
            let mut wanted = RenderKey::new(&at_rest, settings, Some(id), r.cache.revision)
                .with_points_revision(r.cache.points_revision);
            // Only a moving frame draws fewer points; this one is at rest.
            wanted.settings.points.max_points_moving = held.settings.points.max_points_moving;
            // The playhead drawn last frame: during playback it moves every frame.
            wanted.settings.markers = held.settings.markers.clone();
            if *held != wanted {
                return None;
            }
            let data = r.scenes.get(&id)?;
            let target = r.offscreen.target()?;
            let what = crate::picture::Overlay {
                labels: settings.show_box,
                legend: true,
            };
            let shapes = crate::picture::overlay(&at_rest, cloud, data, &held.settings, what);
            let mut picture = crate::picture::PendingPicture::new(
                target.width,
                target.height,
                image::Rgba([0; 4]),
            );
            Some(picture.add(&gpu, target, 0, shapes).map(|()| picture))
        })
        .flatten()
    }

    /// The voxel grid of cloud `id` read back to the CPU (once per grid, for hover picking).
    pub fn read_grid(&self, id: u64) -> Option<crate::data::field::Field> {
        let grid = self.scenes.get(&id)?.grid.as_ref()?;
        let (device, queue) = (&self.device, &self.queue);
        let density = grid.read_field(device, queue, &grid.density).ok()?;
        let hp_mean = grid.read_field(device, queue, &grid.hp_mean).ok()?;
        Some(crate::data::field::Field {
            dims: grid.dims,
            box_min: grid.box_min,
            box_max: grid.box_max,
            density,
            hp_mean,
        })
    }

    /// Builds cloud `id`'s voxel grid unless one with these settings exists. Returns whether it
    /// was rebuilt (then any CPU copy of the old grid is stale); not for an unknown cloud.
    pub fn ensure_grid(
        &mut self,
        id: u64,
        cloud: &PointCloud,
        voxels: &crate::render::grid::voxelize::VoxelSettings,
    ) -> Result<bool, String> {
        let Some(data) = self.scenes.get_mut(&id) else {
            return Ok(false);
        };
        let rebuilt = data
            .ensure_grid(&self.device, &self.queue, &self.renderer, cloud, voxels)
            .map_err(|e| format!("{}: {e}", cloud.path.display()))?;
        if rebuilt {
            self.cache.invalidate();
        }
        Ok(rebuilt)
    }

    /// Where the surface of cloud `id` stands: the counts of its last extraction, an error to
    /// show, and whether an extraction is under way on the worker (the window comes back for
    /// it). Nothing extracted for an unknown cloud.
    pub fn surface_status(&self, id: u64) -> ExtractionStatus {
        self.scenes
            .get(&id)
            .map(|scene| scene.surface.status())
            .unwrap_or_default()
    }

    /// Cloud `id`'s surface as the isovalue sweep follows it (None for an unknown cloud).
    pub fn surface_progress(&self, id: u64) -> Option<SurfaceProgress> {
        let surface = &self.scenes.get(&id)?.surface;
        Some(SurfaceProgress {
            shown_iso_value: surface.shown_iso_value(),
            extracting: surface.needs_another_frame(),
            installed: surface.installed(),
            coarse_installed: surface.coarse_installed(),
        })
    }

    /// Whether cloud `id` has a voxel grid built with these settings (no build needed; an
    /// unknown cloud needs none).
    pub fn grid_matches(
        &self,
        id: u64,
        cloud: &PointCloud,
        voxels: &crate::render::grid::voxelize::VoxelSettings,
    ) -> bool {
        self.scenes
            .get(&id)
            .is_none_or(|s| s.grid_matches(cloud, voxels))
    }

    /// Whether cloud `id` has a voxel grid on the GPU yet.
    pub fn has_grid(&self, id: u64) -> bool {
        self.scenes.get(&id).is_some_and(|s| s.grid.is_some())
    }

    /// Puts song `id`'s scene on the frequency axis `axis`: its labels and mapping, or the
    /// reason it cannot (None for an unknown cloud).
    pub fn set_freq_axis(
        &mut self,
        id: u64,
        cloud: &PointCloud,
        axis: crate::data::freq_axis::FreqAxis,
    ) -> Option<Result<FreqAxisShown, String>> {
        let data = self.scenes.get_mut(&id)?;
        let result = data
            .set_freq_axis(&self.device, &self.renderer, cloud, axis)
            .map(|()| FreqAxisShown {
                labels: crate::ui::labels::axis_labels(cloud, data),
                mapping: data.freq.clone(),
            });
        self.cache.invalidate_points();
        Some(result)
    }

    /// The fraction of the points (or of the volume's rows) drawn while a progressive render
    /// is under way. `ctx` is kept to ask for the next frame when a refinement starts in a
    /// frame's paint.
    pub fn refining(&mut self, ctx: &egui::Context) -> Option<f32> {
        self.repaint.get_or_insert_with(|| ctx.clone());
        self.progressive
            .refine
            .progress()
            .or(self.volume_refine.progress())
    }

    /// Scene renders so far (for the frame read-out and the tests).
    pub fn renders(&self) -> u64 {
        self.cache.renders
    }
}

/// The window's device errors: wgpu's own rule (an error is a bug: panic with it), except a
/// surface reconfiguration that found the queue busy. eframe reconfigures the window's surface
/// on the UI thread when the window is resized or the swapchain says it is suboptimal, and
/// wgpu refuses when work was submitted while it waited for the device to go idle, which the
/// surface extraction thread does (render/surface/background.rs). The surface keeps its
/// previous configuration and eframe configures it again on the next frame, so that one is
/// only logged.
fn on_device_error(error: wgpu::Error) {
    if is_busy_reconfigure(&error) {
        log::warn!("surface reconfiguration deferred: {error}");
        return;
    }
    panic!("wgpu error: {error}");
}

/// Whether `error` is wgpu's "failed to wait for GPU to come idle before reconfiguring the
/// surface" (work submitted from another thread during the wait).
fn is_busy_reconfigure(error: &wgpu::Error) -> bool {
    use wgpu::wgc::present::ConfigureSurfaceError;
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = source {
        if matches!(
            e.downcast_ref::<ConfigureSurfaceError>(),
            Some(ConfigureSurfaceError::GpuWaitTimeout)
        ) {
            return true;
        }
        source = e.source();
    }
    false
}

/// One frame of the 3D view.
pub struct ViewCallback {
    pub view: FrameView,
    pub settings: RenderSettings,
    pub cloud_id: Option<u64>,
    /// The frame time the points' slices aim at while they fill in at rest
    /// (`ViewMotion::refine_target`).
    pub refine_target: std::time::Duration,
}

/// What a bridge callback renders: the 3D view ([`ViewCallback`]) or a part of the compare
/// ([`CompareCallback`]). One `egui_wgpu` callback serves both ([`paint_callback`]): `prepare`
/// renders the job into its offscreen target when what it shows changed, `paint` composites
/// that target into the callback's viewport.
pub(crate) trait OffscreenJob: Send + Sync + 'static {
    /// Renders into the job's target, only when what it shows changed.
    fn render(&self, gpu: Prepare<'_>, resources: &mut CallbackResources);
    /// The target that `paint` composites.
    fn offscreen<'a>(&self, resources: &'a CallbackResources) -> Option<&'a Offscreen>;
}

/// The device, queue and frame encoder a job renders with.
pub(crate) struct Prepare<'a> {
    pub(crate) device: &'a wgpu::Device,
    pub(crate) queue: &'a wgpu::Queue,
    pub(crate) encoder: &'a mut wgpu::CommandEncoder,
}

/// The paint callback that draws `job` into `rect`.
pub(crate) fn paint_callback(rect: egui::Rect, job: impl OffscreenJob) -> egui::PaintCallback {
    egui_wgpu::Callback::new_paint_callback(rect, Painted(job))
}

/// A job as egui_wgpu's callback.
struct Painted<J>(J);

impl<J: OffscreenJob> CallbackTrait for Painted<J> {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let gpu = Prepare {
            device,
            queue,
            encoder,
        };
        self.0.render(gpu, resources);
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(offscreen) = self.0.offscreen(resources) {
            offscreen.draw(render_pass);
        }
    }
}

impl OffscreenJob for ViewCallback {
    fn render(&self, gpu: Prepare<'_>, resources: &mut CallbackResources) {
        let Prepare {
            device,
            queue,
            encoder,
        } = gpu;
        let Some(res) = resources.get_mut::<ViewResources>() else {
            return;
        };
        if res
            .offscreen
            .ensure_size(device, self.view.width, self.view.height)
        {
            res.cache.invalidate();
        }
        // A surface finished in the background: the scene shows it from this frame on.
        if let Some(data) = self.cloud_id.and_then(|id| res.scenes.get(&id))
            && data.surface.install_finished()
        {
            res.cache.invalidate();
        }
        let key = RenderKey::new(
            &self.view,
            &self.settings,
            self.cloud_id,
            res.cache.revision,
        )
        .with_points_revision(res.cache.points_revision);
        if !res.cache.begin(&key) {
            // The target already holds this scene: paint composites it again.
            return;
        }
        let Some(target) = res.offscreen.target() else {
            return;
        };
        let data = self.cloud_id.and_then(|id| res.scenes.get(&id));
        // At rest, a cloud larger than a frame's budget is drawn a slice a frame; the window
        // asks for the next frame while `ViewResources::refining` says so.
        if let Some(data) = data
            && !self.view.moving
            && crate::render::scene::draws_points_at_rest(&self.settings, data)
            && res.progressive.refine.wants(data.points.total)
        {
            res.progressive.refine.target = self.refine_target;
            let complete = res.progressive.frame(
                device,
                queue,
                encoder,
                &res.renderer,
                target,
                data,
                &key,
                &self.view,
                &self.settings,
            );
            res.cache.finish(key, complete);
            if !complete && let Some(ctx) = &res.repaint {
                ctx.request_repaint();
            }
            return;
        }
        // The target shows another scene now (the volume or surface once its grid is built, a
        // moving frame): the slices drawn so far are no longer on screen, and a refinement left
        // unfinished would keep the window asking for frames at rest.
        res.progressive.set_aside();
        // At rest, the volume is drawn coarse first and then a band of rows a frame: the window
        // answers within each frame instead of waiting seconds for one render on a slow device.
        if let Some(data) = data
            && !self.view.moving
            && self.settings.view == crate::render::scene::ViewKind::Volume
            && !crate::render::scene::draws_points_at_rest(&self.settings, data)
        {
            // The box and the markers are drawn over the volume every frame: a playhead moving
            // during playback does not start the refinement over.
            let mut volume_key = key.clone();
            volume_key.settings.markers.clear();
            volume_key.settings.show_box = false;
            let complete = res.volume_refine.frame(
                device,
                queue,
                encoder,
                &res.renderer,
                target,
                data,
                &volume_key,
                &self.view,
                &self.settings,
                std::time::Instant::now(),
            );
            res.cache.finish(key, complete);
            if !complete && let Some(ctx) = &res.repaint {
                ctx.request_repaint();
            }
            return;
        }
        res.volume_refine.set_aside();
        res.renderer
            .render(queue, encoder, target, data, &self.view, &self.settings);
        // Complete even while a surface is extracted in the background: the last mesh is what
        // the view shows until the new one is installed (above).
        res.cache.finish(key, true);
    }

    fn offscreen<'a>(&self, resources: &'a CallbackResources) -> Option<&'a Offscreen> {
        resources.get::<ViewResources>().map(|res| &res.offscreen)
    }
}

use eframe::egui;

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the busy-queue reconfiguration is let through, as wgpu reports it (the configure
    /// error inside wgpu-core's context error); any other device error stays fatal.
    #[test]
    fn only_a_busy_surface_reconfiguration_is_forgiven() {
        use wgpu::wgc::error::ContextError;
        use wgpu::wgc::present::ConfigureSurfaceError;
        let validation = |inner: ConfigureSurfaceError| wgpu::Error::Validation {
            source: Box::new(ContextError {
                fn_ident: "Surface::configure",
                source: Box::new(inner),
                label: String::new(),
            }),
            description: String::new(),
        };
        assert!(is_busy_reconfigure(&validation(
            ConfigureSurfaceError::GpuWaitTimeout
        )));
        assert!(!is_busy_reconfigure(&validation(
            ConfigureSurfaceError::InvalidSurface
        )));
        let other = wgpu::Error::Validation {
            source: Box::new(std::io::Error::other(
                "a bind group does not match its layout",
            )),
            description: String::new(),
        };
        assert!(!is_busy_reconfigure(&other));
        assert!(
            std::panic::catch_unwind(|| on_device_error(wgpu::Error::Validation {
                source: Box::new(std::io::Error::other("bad")),
                description: String::new(),
            }))
            .is_err(),
            "other errors still panic"
        );
        on_device_error(validation(ConfigureSurfaceError::GpuWaitTimeout));
    }
    use crate::view::camera::Camera;

    fn view(frame_index: u32) -> FrameView {
        let mut view = FrameView::at_rest(Camera::default(), glam::Mat4::IDENTITY, 640, 400);
        view.frame_index = frame_index;
        view
    }

    /// Frames that differ only in what egui paints over the scene (hover read-out, tooltips,
    /// panels) or in the frame counter render once; a change to the camera, size, settings,
    /// markers, cloud or its GPU data renders again.
    #[test]
    fn only_frames_that_change_the_scene_render_it() {
        let settings = RenderSettings::default();
        let mut cache = FrameCache::default();
        let frame = |cache: &mut FrameCache, view: &FrameView, settings: &RenderSettings| {
            let key = RenderKey::new(view, settings, Some(1), cache.revision);
            let render = cache.begin(&key);
            if render {
                cache.finish(key, true);
            }
            render
        };
        assert!(frame(&mut cache, &view(0), &settings), "first frame");
        for i in 1..10 {
            // A hover-only frame: the app passes the same view and settings (the read-out is
            // painted by egui), only the frame counter moves on.
            assert!(!frame(&mut cache, &view(i), &settings), "hover frame {i}");
        }
        assert_eq!(cache.renders, 1);

        let mut moved = view(11);
        moved.camera.orbit(5.0, 0.0, 400.0);
        assert!(frame(&mut cache, &moved, &settings), "camera");
        let mut resized = moved;
        resized.width = 800;
        assert!(frame(&mut cache, &resized, &settings), "size");
        let mut changed = settings.clone();
        changed.surface.iso_value = 0.7;
        assert!(frame(&mut cache, &resized, &changed), "settings");
        changed.markers = vec![crate::render::markers::MarkerBox::playhead(0.1)];
        assert!(frame(&mut cache, &resized, &changed), "playhead");
        assert!(!frame(&mut cache, &resized, &changed), "same again");
        cache.invalidate();
        assert!(frame(&mut cache, &resized, &changed), "new GPU data");
        assert_eq!(cache.renders, 6);

        // An unfinished render (one slice of progressive points) is not kept.
        let key = RenderKey::new(&resized, &changed, Some(1), cache.revision);
        cache.finish(key.clone(), false);
        assert!(cache.begin(&key));
    }
}
