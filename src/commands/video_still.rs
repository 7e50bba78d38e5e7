//! A still camera's video draws its scene once. With `--camera fixed` (the default) only the
//! playhead (a timeline's song band) and the labels painted on the CPU change from frame to
//! frame, so the points, surface or volume are drawn once into a layer of their own (colour and
//! depth, without the box and the markers), and every frame copies that layer into its target
//! and draws the box and the markers over it ([`Renderer::render_overlay`]), the window's way
//! of redrawing a refined view when only the playhead moves (`ui/progressive.rs`). The frame is
//! what one [`Renderer::render`] draws: the same passes in the same order over the same depth.

use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::headless::render_into;
use loudscape::render::scene::{Recording, RenderSettings, Renderer, SceneData};
use loudscape::view::frame_view::FrameView;

/// The scene drawn once for a still camera, kept for the frames that follow.
#[derive(Default)]
pub struct StillLayer {
    target: Option<RenderTarget>,
    /// The view the layer holds (camera, size, detail); another one draws it again.
    drawn_for: Option<FrameView>,
    /// How many times the scene was drawn into the layer.
    draws: u32,
}

impl StillLayer {
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
        let layer = match &self.target {
            Some(layer) if (layer.width, layer.height) == (width, height) => layer,
            _ => {
                self.drawn_for = None;
                self.target
                    .insert(RenderTarget::new(&gpu.device, width, height))
            }
        };
        // The frame's index only seeds the volume's ray jitter: one still picture, one seed.
        let same = |drawn: &FrameView| {
            drawn.camera == view.camera
                && drawn.world_from_data == view.world_from_data
                && drawn.moving == view.moving
                && (drawn.width, drawn.height) == (view.width, view.height)
        };
        if !self.drawn_for.as_ref().is_some_and(same) {
            let mut bare = settings.clone();
            bare.markers.clear();
            bare.show_box = false;
            // Its own submission: the frame's uniforms are written through the queue, and the
            // overlay's pass below writes them again.
            render_into(gpu, renderer, Some(data), view, &bare, layer);
            self.drawn_for = Some(*view);
            self.draws += 1;
        }
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("video::still_frame"),
            });
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        for (from, to) in [(&layer.color, &target.color), (&layer.depth, &target.depth)] {
            encoder.copy_texture_to_texture(from.as_image_copy(), to.as_image_copy(), size);
        }
        let recording = Recording {
            queue: &gpu.queue,
            encoder: &mut encoder,
            target,
        };
        renderer.render_overlay(recording, data, view, settings, None);
        gpu.queue.submit([encoder.finish()]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loudscape::render::markers::MarkerBox;
    use loudscape::render::points::PointStyle;
    use loudscape::render::scene::ViewKind;
    use loudscape::view::camera::Camera;

    /// Every view of the demo through the layer equals one `render` of it, byte for byte, at
    /// two playheads (the second frame reuses the layer), and the layer is drawn once.
    #[test]
    fn a_still_frame_is_the_render_of_it_byte_for_byte() {
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe will do)");
        let renderer = Renderer::new(&gpu.device);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
        let cloud = crate::commands::args::load_cloud(&path).expect("the demo cloud");
        let (w, h) = (320, 180);
        for view_kind in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
            let mut settings = RenderSettings {
                view: view_kind,
                ..Default::default()
            };
            settings.points.size_px = PointStyle::size_for(cloud.points.len());
            let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
            if view_kind != ViewKind::Points {
                crate::commands::render::prepare_grid(
                    &gpu, &renderer, &cloud, &mut data, &settings,
                )
                .expect("the grid");
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
            assert_eq!(still.draws, 1, "{view_kind:?}: the scene drawn once");
        }
    }
}
