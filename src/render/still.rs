//! A still camera's video draws its scene once. With `video --camera fixed` (the default) only
//! the playhead (a timeline's song band) and the labels painted on the CPU change from frame to
//! frame, so the points, surface or volume are drawn once into a layer of their own (colour and
//! depth, without the box and the markers), and every frame copies that layer into its target
//! and draws the box and the markers over it ([`Renderer::render_overlay`]), the window's way
//! of redrawing a refined view when only the playhead moves (`ui/progressive.rs`). The frame is
//! what one [`Renderer::render`] draws: the same passes in the same order over the same depth.
//! An A/B compare's video keeps one layer a half (`picture::compare::submit_compare_image`).

use crate::render::gpu::context::GpuContext;
use crate::render::gpu::target::RenderTarget;
use crate::render::headless::render_into;
use crate::render::scene::{Recording, RenderSettings, Renderer, SceneData};
use crate::view::frame_view::FrameView;

/// The scene drawn once for a still camera, kept for the frames that follow.
#[derive(Default)]
pub struct StillLayer {
    target: Option<RenderTarget>,
    /// The frame [`StillLayer::render_kept`] draws into, kept from frame to frame.
    frame: Option<RenderTarget>,
    /// The view the layer holds (camera, size, detail); another one draws it again.
    drawn_for: Option<FrameView>,
    /// How many times the scene was drawn into the layer.
    draws: u32,
}

impl StillLayer {
    /// Whether the layer holds the scene seen from `view` (drawn for it already).
    pub fn holds(&self, view: &FrameView) -> bool {
        self.drawn_for
            .as_ref()
            .is_some_and(|drawn| same_view(drawn, view))
    }

    /// How many times the scene was drawn into the layer.
    pub fn draws(&self) -> u32 {
        self.draws
    }

    /// [`StillLayer::render`] into a frame target of the layer's own, of the view's size, kept
    /// from frame to frame (a copy of it submitted before the next call reads this frame's).
    pub fn render_kept(
        &mut self,
        gpu: &GpuContext,
        renderer: &Renderer,
        data: &SceneData,
        view: &FrameView,
        settings: &RenderSettings,
    ) -> &RenderTarget {
        let frame = self
            .frame
            .take()
            .filter(|frame| frame.has_size(view.width, view.height))
            .unwrap_or_else(|| RenderTarget::new(&gpu.device, view.width, view.height));
        self.render(gpu, renderer, data, view, settings, &frame);
        self.frame.insert(frame)
    }

    /// Draws the frame of `data` seen from `view` with `settings` into `target`: the scene from
    /// the layer (drawn first when the view changed), the box and the markers over it.
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        renderer: &Renderer,
        data: &SceneData,
        view: &FrameView,
        settings: &RenderSettings,
        target: &RenderTarget,
    ) {
        let (width, height) = (target.width, target.height);
        let layer = match self.target.take() {
            Some(layer) if layer.has_size(width, height) => layer,
            _ => {
                self.drawn_for = None;
                RenderTarget::new(&gpu.device, width, height)
            }
        };
        if !self.holds(view) {
            let mut bare = settings.clone();
            bare.markers.clear();
            bare.show_box = false;
            // Its own submission: the frame's uniforms are written through the queue, and the
            // overlay's pass below writes them again.
            render_into(gpu, renderer, Some(data), view, &bare, &layer);
            self.drawn_for = Some(*view);
            self.draws += 1;
        }
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("video::still_frame"),
            });
        layer.copy_into(&mut encoder, target);
        let recording = Recording {
            queue: &gpu.queue,
            encoder: &mut encoder,
            target,
        };
        renderer.render_overlay(recording, data, view, settings, None);
        gpu.queue.submit([encoder.finish()]);
        self.target = Some(layer);
    }
}

/// Whether two views see the same scene: the frame's index only seeds the volume's ray jitter
/// (one still picture, one seed).
fn same_view(a: &FrameView, b: &FrameView) -> bool {
    a.camera == b.camera
        && a.world_from_data == b.world_from_data
        && a.moving == b.moving
        && (a.width, a.height) == (b.width, b.height)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::markers::MarkerBox;
    use crate::render::points::PointStyle;
    use crate::render::scene::ViewKind;
    use crate::view::camera::Camera;

    /// Every view of the demo through the layer equals one `render` of it, byte for byte, at
    /// two playheads (the second frame reuses the layer), and the layer is drawn once.
    #[test]
    fn a_still_frame_is_the_render_of_it_byte_for_byte() {
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe will do)");
        let renderer = Renderer::new(&gpu.device);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
        let cloud = crate::extract::open_for_command(&path).expect("the demo cloud");
        let (w, h) = (320, 180);
        for view_kind in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
            let mut settings = RenderSettings {
                view: view_kind,
                ..Default::default()
            };
            settings.points.size_px = PointStyle::size_for(cloud.points.len());
            let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
            if view_kind != ViewKind::Points {
                data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &settings.voxels)
                    .expect("the grid");
            }
            if let (ViewKind::Surface, Some(grid)) = (view_kind, data.grid.as_ref()) {
                renderer
                    .surface
                    .extract_blocking(&gpu.queue, &data.surface, grid, &settings.surface)
                    .expect("the surface");
            }
            let camera = FrameView::fitted(
                Camera::default(),
                data.world_from_data,
                data.world_box(),
                w,
                h,
            )
            .camera;
            let view = FrameView::at_rest(camera, data.world_from_data, w, h);
            let mut still = StillLayer::default();
            let frame = RenderTarget::new(&gpu.device, w, h);
            for (k, x) in [-0.4f32, 0.35].into_iter().enumerate() {
                settings.markers = vec![MarkerBox::playhead(x)];
                let mut frame_view = view;
                frame_view.frame_index = k as u32;
                still.render(&gpu, &renderer, &data, &frame_view, &settings, &frame);
                let got = frame.read_rgba(&gpu.device, &gpu.queue).expect("read back");
                let fresh = RenderTarget::new(&gpu.device, w, h);
                render_into(&gpu, &renderer, Some(&data), &view, &settings, &fresh);
                let want = fresh.read_rgba(&gpu.device, &gpu.queue).expect("read back");
                let differ = got
                    .pixels()
                    .zip(want.pixels())
                    .filter(|(a, b)| a != b)
                    .count();
                assert_eq!(differ, 0, "{view_kind:?}, playhead {x}: pixels differ");
            }
            assert_eq!(still.draws(), 1, "{view_kind:?}: the scene drawn once");
            assert!(still.holds(&view));
        }
    }
}
