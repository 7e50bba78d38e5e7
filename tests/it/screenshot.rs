//! A saved screenshot is what the headless renderer draws for the same view, playhead, labels
//! and legend included.

use crate::common;

use std::path::PathBuf;

use loudscape::data::cloud;
use loudscape::render::headless::render_frame;
use loudscape::render::markers::MarkerBox;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData};
use loudscape::ui::screenshot;
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

#[test]
fn saved_screenshot_matches_the_headless_render() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
    let cloud = cloud::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let (w, h) = (320, 200);
    let view = FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        w,
        h,
    );
    let settings = RenderSettings {
        markers: vec![MarkerBox::playhead(0.2)],
        ..Default::default()
    };

    let shot = screenshot::render_view(&gpu, &renderer, Some((&cloud, &data)), &view, &settings)
        .expect("screenshot");
    let file = common::output_dir().join("screenshot_demo.png");
    screenshot::save_png(&shot, &file).expect("save");
    let saved = image::open(&file).expect("read back").to_rgba8();
    assert_eq!(saved.dimensions(), (w, h));

    let target = render_frame(&gpu, &renderer, Some(&data), &view, &settings);
    // The screenshot carries the labels and the legend, as headless renders do.
    screenshot::draw_overlay(
        &gpu,
        &target,
        &view,
        &cloud,
        &data,
        &settings,
        screenshot::Overlay {
            labels: true,
            legend: true,
        },
    );
    let reference = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let (share, mean) = common::difference(&saved, &reference, 8);
    assert!(
        share < 0.001 && mean < 0.5,
        "screenshot differs from the headless render: {share} of pixels, mean {mean}"
    );

    // The playhead is in the picture: without it the image differs along its plane.
    let plain = screenshot::render_view(
        &gpu,
        &renderer,
        Some((&cloud, &data)),
        &view,
        &RenderSettings::default(),
    )
    .expect("screenshot");
    let (share, _) = common::difference(&saved, &plain, 8);
    assert!(share > 0.01, "the playhead plane is not visible ({share})");
}
