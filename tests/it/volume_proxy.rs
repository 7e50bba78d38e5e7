//! On slow devices the window asks for the points in place of the volume while the camera moves;
//! at rest, and when not asked, the volume is drawn.

use crate::common;

use std::path::PathBuf;

use loudscape::data::cloud;
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

#[test]
fn points_stand_in_for_the_volume_only_while_moving_and_when_asked() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
    let cloud = cloud::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    let volume = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &volume.voxels)
        .expect("voxelize");
    let mut camera = Camera::default();
    let (min, max) = data.world_box();
    camera.fit(min, max, 1.6);
    let view = |moving| FrameView {
        camera,
        world_from_data: data.world_from_data,
        width: 240,
        height: 150,
        frame_index: 0,
        moving,
    };
    let render = |settings: &RenderSettings, moving| {
        render_image(&gpu, &renderer, Some(&data), &view(moving), settings).expect("render")
    };
    let points_moving = render(
        &RenderSettings {
            view: ViewKind::Points,
            ..Default::default()
        },
        true,
    );
    let proxy = RenderSettings {
        points_while_moving: true,
        ..volume.clone()
    };
    // Moving and asked: exactly the points (their level-of-detail subset).
    let (share, _) = common::difference(&render(&proxy, true), &points_moving, 0);
    assert_eq!(share, 0.0, "the stand-in is not the points view");
    // At rest, or not asked: the volume, which looks nothing like the points.
    let at_rest = render(&proxy, false);
    let not_asked = render(&volume, true);
    for (name, image) in [("at rest", &at_rest), ("not asked", &not_asked)] {
        let (share, _) = common::difference(image, &points_moving, 32);
        assert!(share > 0.05, "{name}: the volume was not drawn ({share})");
    }
}
