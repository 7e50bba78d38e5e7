//! The points view, rendered headless (lavapipe where there is no GPU) and read back.

use crate::common::{self, demo_song, view_of};

use loudscape::data::cloud::{DataMode, Point, PointCloud};
use loudscape::render::colormap::HpColourMap;
use loudscape::render::headless::render_image;
use loudscape::render::points::{PointStyle, lod_stride};
use loudscape::render::scene::{RenderSettings, Renderer, SceneData};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

#[test]
fn demo_song_points_match_golden() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = demo_song();
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let view = view_of(&data, 480, 270);
    let image = render_image(
        &gpu,
        &renderer,
        Some(&data),
        &view,
        &RenderSettings::default(),
    )
    .expect("render");
    assert!(
        common::coverage(&image) > 0.05,
        "the points view is nearly empty"
    );
    common::assert_golden("points_demo_song", &image, common::RASTER_EDGES);
}

/// Points uploaded in many small chunks draw exactly what one buffer draws.
#[test]
fn chunked_upload_draws_the_same_image() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = demo_song();
    let whole = SceneData::new(&gpu.device, &renderer, &cloud);
    let chunk_bytes = (cloud.points.len() as u64 / 7 + 1) * std::mem::size_of::<Point>() as u64;
    let chunked = SceneData::with_chunk_limit(&gpu.device, &renderer, &cloud, chunk_bytes);
    assert!(chunked.points.chunk_count() >= 7, "expected several chunks");
    assert_eq!(whole.points.chunk_count(), 1);
    let view = view_of(&whole, 320, 180);
    let settings = RenderSettings::default();
    let a = render_image(&gpu, &renderer, Some(&whole), &view, &settings).expect("render");
    let b = render_image(&gpu, &renderer, Some(&chunked), &view, &settings).expect("render");
    let (share, _) = common::difference(&a, &b, 0);
    assert_eq!(share, 0.0, "chunked drawing differs from one buffer");
}

/// Each point lands on the pixel its position projects to, in its hp colour.
#[test]
fn a_point_lands_where_it_projects_in_its_palette_colour() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let points = vec![
        Point {
            position: [-0.5, 0.0, 0.0],
            scalar: 1.0,
            hp: 0.0,
        },
        Point {
            position: [0.5, 0.0, 0.0],
            scalar: 1.0,
            hp: 1.0,
        },
    ];
    let cloud = PointCloud::synthetic(points.clone(), DataMode::Song);
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let view = view_of(&data, 200, 120);
    let mut settings = RenderSettings {
        show_box: false,
        ..Default::default()
    };
    settings.points.size_px = 9.0;
    let image = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    for point in &points {
        let pixel = view
            .project(point.position.into())
            .expect("in front of the camera");
        let got = image.get_pixel(pixel.x as u32, pixel.y as u32);
        let want = HpColourMap::Classic.points().sample_u8(point.hp);
        for c in 0..3 {
            // The centre of the disc is unshaded; allow for rounding.
            assert!(
                got[c].abs_diff(want[c]) <= 3,
                "hp {}: pixel {got:?}, palette {want:?}",
                point.hp
            );
        }
    }
}

#[test]
fn min_loudness_hides_quiet_points() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = demo_song();
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let view = view_of(&data, 320, 180);
    let mut settings = RenderSettings {
        show_box: false,
        ..Default::default()
    };
    let all = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    settings.points.min_scalar = 0.9;
    let loud = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    assert!(common::coverage(&loud) < common::coverage(&all) * 0.5);
}

#[test]
fn moving_camera_draws_a_subset() {
    let style = PointStyle {
        max_points_moving: 1000,
        ..Default::default()
    };
    assert_eq!(lod_stride(500, &style, true), 1);
    assert_eq!(lod_stride(10_000, &style, false), 1);
    assert_eq!(lod_stride(10_000, &style, true), 10);
    assert_eq!(lod_stride(10_001, &style, true), 11);
}

#[test]
fn empty_scene_renders_background() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let view = FrameView::at_rest(Camera::default(), glam::Mat4::IDENTITY, 64, 64);
    let image =
        render_image(&gpu, &renderer, None, &view, &RenderSettings::default()).expect("render");
    assert_eq!(common::coverage(&image), 0.0);
}
