//! The bridge between egui and the render passes: an `egui_wgpu` paint callback.
//!
//! `prepare` renders the scene into an offscreen [`RenderTarget`] sized to the 3D view, `paint`
//! composites it into egui's frame. GPU state lives in egui_wgpu's callback resources as one
//! [`ViewResources`], created once when the window opens.

use std::collections::HashMap;

use eframe::egui_wgpu::{self, CallbackResources, CallbackTrait, ScreenDescriptor};

use crate::data::cloud::PointCloud;
use crate::render::composite::CompositePass;
use crate::render::gpu::target::RenderTarget;
use crate::render::scene::{RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

/// GPU state owned by the window, kept in egui_wgpu's callback resources.
pub struct ViewResources {
    pub renderer: Renderer,
    composite: CompositePass,
    target: Option<RenderTarget>,
    /// Uploaded clouds by the app's cloud id.
    pub scenes: HashMap<u64, SceneData>,
}

impl ViewResources {
    pub fn install(render_state: &egui_wgpu::RenderState) {
        let device = &render_state.device;
        let resources = ViewResources {
            renderer: Renderer::new(device),
            composite: CompositePass::new(device, render_state.target_format),
            target: None,
            scenes: HashMap::new(),
        };
        render_state
            .renderer
            .write()
            .callback_resources
            .insert(resources);
    }

    /// Uploads a cloud under `id`, replacing what was there.
    pub fn upload(render_state: &egui_wgpu::RenderState, id: u64, cloud: &PointCloud) {
        let mut renderer = render_state.renderer.write();
        if let Some(resources) = renderer.callback_resources.get_mut::<ViewResources>() {
            let data = SceneData::new(&render_state.device, &resources.renderer, cloud);
            resources.scenes.insert(id, data);
        }
    }

    /// Renders the cloud `id` offscreen at the view's size, labels included, for a screenshot.
    pub fn screenshot(
        render_state: &egui_wgpu::RenderState,
        id: u64,
        cloud: &PointCloud,
        view: &FrameView,
        settings: &RenderSettings,
    ) -> Result<image::RgbaImage, crate::ui::screenshot::ScreenshotError> {
        let gpu = crate::render::gpu::context::GpuContext {
            adapter: render_state.adapter.clone(),
            device: render_state.device.clone(),
            queue: render_state.queue.clone(),
        };
        let renderer = render_state.renderer.read();
        let resources = renderer.callback_resources.get::<ViewResources>();
        let scene = resources.and_then(|r| r.scenes.get(&id).map(|data| (r, data)));
        match scene {
            Some((r, data)) => crate::ui::screenshot::render_view(
                &gpu,
                &r.renderer,
                Some((cloud, data)),
                view,
                settings,
            ),
            None => {
                let renderer = Renderer::new(&gpu.device);
                crate::ui::screenshot::render_view(&gpu, &renderer, None, view, settings)
            }
        }
    }

    /// The voxel grid of cloud `id` read back to the CPU (once per grid, for hover picking).
    pub fn read_grid(
        render_state: &egui_wgpu::RenderState,
        id: u64,
    ) -> Option<crate::data::field::Field> {
        let renderer = render_state.renderer.read();
        let resources = renderer.callback_resources.get::<ViewResources>()?;
        let grid = resources.scenes.get(&id)?.grid.as_ref()?;
        let (device, queue) = (&render_state.device, &render_state.queue);
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
    /// was rebuilt (then any CPU copy of the old grid is stale).
    pub fn ensure_grid(
        render_state: &egui_wgpu::RenderState,
        id: u64,
        cloud: &PointCloud,
        voxels: &crate::render::grid::voxelize::VoxelSettings,
    ) -> Result<bool, String> {
        let mut renderer = render_state.renderer.write();
        let Some(resources) = renderer.callback_resources.get_mut::<ViewResources>() else {
            return Ok(false);
        };
        let ViewResources {
            renderer, scenes, ..
        } = resources;
        let Some(data) = scenes.get_mut(&id) else {
            return Ok(false);
        };
        data.ensure_grid(
            &render_state.device,
            &render_state.queue,
            renderer,
            cloud,
            voxels,
        )
        .map_err(|e| format!("{}: {e}", cloud.path.display()))
    }

    /// The surface of cloud `id`: triangle counts of the last extraction, an error to show, and
    /// whether it needs another frame to finish (buffers growing).
    pub fn surface_status(
        render_state: &egui_wgpu::RenderState,
        id: u64,
    ) -> (
        Option<crate::render::surface::SurfaceCounts>,
        Option<String>,
        bool,
    ) {
        let renderer = render_state.renderer.read();
        match renderer
            .callback_resources
            .get::<ViewResources>()
            .and_then(|r| r.scenes.get(&id))
        {
            Some(scene) => (
                scene.surface.counts(),
                scene.surface.error(),
                scene.surface.needs_another_frame(),
            ),
            None => (None, None, false),
        }
    }

    /// Whether cloud `id` has a voxel grid on the GPU yet.
    pub fn has_grid(render_state: &egui_wgpu::RenderState, id: u64) -> bool {
        let renderer = render_state.renderer.read();
        renderer
            .callback_resources
            .get::<ViewResources>()
            .and_then(|r| r.scenes.get(&id))
            .is_some_and(|s| s.grid.is_some())
    }

    pub fn remove(render_state: &egui_wgpu::RenderState, id: u64) {
        let mut renderer = render_state.renderer.write();
        if let Some(resources) = renderer.callback_resources.get_mut::<ViewResources>() {
            resources.scenes.remove(&id);
        }
    }
}

/// One frame of the 3D view.
pub struct ViewCallback {
    pub view: FrameView,
    pub settings: RenderSettings,
    pub cloud_id: Option<u64>,
}

impl CallbackTrait for ViewCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(res) = resources.get_mut::<ViewResources>() else {
            return Vec::new();
        };
        let (w, h) = (self.view.width, self.view.height);
        if !res.target.as_ref().is_some_and(|t| t.has_size(w, h)) {
            let target = RenderTarget::new(device, w, h);
            res.composite.set_source(device, &target);
            res.target = Some(target);
        }
        let Some(target) = res.target.as_ref() else {
            return Vec::new();
        };
        let data = self.cloud_id.and_then(|id| res.scenes.get(&id));
        res.renderer
            .render(queue, encoder, target, data, &self.view, &self.settings);
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &CallbackResources,
    ) {
        if let Some(res) = resources.get::<ViewResources>() {
            res.composite.draw(render_pass);
        }
    }
}

use eframe::egui;
