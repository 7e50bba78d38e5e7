//! Save PNG at a chosen size, drawn over frames: one frame of the save's own picture
//! (`state/save_wait.rs`'s [`Sliced`]), as the view draws its own (`ui/bridge.rs`): at rest, the
//! points a slice a frame when the cloud is larger than a frame's budget (`ui/progressive.rs`),
//! the volume coarse and then a band of rows a frame (`render/volume/progressive.rs`), anything
//! else (a surface, a small cloud) in one render. Recorded into an encoder of its own and
//! submitted at once, before the frame's own submission, so the renderer's frame uniforms
//! written for the save's view are the ones its passes read. The slices end as one render's
//! pass (tests/it/big_clouds.rs, tests/it/volume.rs), so the picture is the one a single
//! render draws; the frame of the click and every frame after draw a frame's share of it.

use crate::data::cloud::PointCloud;
use crate::picture::{Overlay, PendingPicture};
use crate::render::scene::{ViewKind, draws_points_at_rest};
use crate::ui::bridge::{RenderKey, ViewResources};
use crate::ui::state::picture_save::{RENDERED, SLICED};
use crate::ui::state::save_wait::Sliced;

/// Draws the next part of `sliced`'s picture of cloud `id`. `Some` once it is complete: its
/// read-back submitted, with the labels to draw over it (`PendingPicture::finish`), or why
/// nothing can be saved (the cloud is gone from the GPU), and how it was drawn (in slices, or
/// in one render). `None`: draw again next frame.
pub(super) fn draw_next(
    render_state: &eframe::egui_wgpu::RenderState,
    sliced: &mut Sliced,
    id: u64,
    cloud: &PointCloud,
) -> Option<(Result<PendingPicture, String>, &'static str)> {
    let device = &render_state.device;
    let queue = &render_state.queue;
    ViewResources::read(render_state, |r| {
        let Some(data) = r.scenes.get(&id) else {
            let gone = format!(
                "Save PNG: {} is no longer shown: nothing saved",
                cloud.path.display()
            );
            return Some((Err(gone), RENDERED));
        };
        let Sliced {
            target,
            points,
            volume,
            view,
            settings,
        } = sliced;
        // Revised GPU data (new points, a grid) starts the slices over, as in the view.
        let key = RenderKey::new(view, settings, Some(id), r.cache.revision)
            .with_points_revision(r.cache.points_revision);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("save_png::slice"),
        });
        let mut how = SLICED;
        let complete =
            if draws_points_at_rest(settings, data) && points.refine.wants(data.points.total) {
                points.frame(
                    device,
                    queue,
                    &mut encoder,
                    &r.renderer,
                    target,
                    data,
                    &key,
                    view,
                    settings,
                )
            } else if settings.view == ViewKind::Volume && !draws_points_at_rest(settings, data) {
                let mut volume_key = key;
                volume_key.settings.markers.clear();
                volume_key.settings.show_box = false;
                volume.frame(
                    device,
                    queue,
                    &mut encoder,
                    &r.renderer,
                    target,
                    data,
                    &volume_key,
                    view,
                    settings,
                    std::time::Instant::now(),
                )
            } else {
                r.renderer
                    .render(queue, &mut encoder, target, Some(data), view, settings);
                how = RENDERED;
                true
            };
        queue.submit([encoder.finish()]);
        if !complete {
            return None;
        }
        let gpu = crate::render::gpu::context::GpuContext {
            adapter: render_state.adapter.clone(),
            device: device.clone(),
            queue: queue.clone(),
        };
        let what = Overlay {
            labels: settings.show_box,
            legend: true,
        };
        let shapes = crate::picture::overlay(view, cloud, data, settings, what);
        let mut picture = PendingPicture::new(target.width, target.height, image::Rgba([0; 4]));
        let submitted = picture
            .add(&gpu, target, 0, shapes)
            .map(|()| picture)
            .map_err(|e| e.to_string());
        Some((submitted, how))
    })
    .unwrap_or_else(|| Some((Err("Save PNG: the 3D view is not ready".into()), RENDERED)))
}
