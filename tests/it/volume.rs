//! The volume view rendered headless: golden images of the presets and the hp tint, and checks
//! that the controls change the image and degenerate clouds draw.

use crate::common;

use std::time::Instant;

use loudscape::data::cloud::{DataMode, Point, PointCloud};
use loudscape::data::synthetic::synthetic_song;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::headless::render_image;
use loudscape::render::markers::MarkerBox;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::volume::TransferPreset;
use loudscape::render::volume::progressive::{ProgressiveVolume, TARGET_FRAME};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

const SIZE: (u32, u32) = (320, 200);

struct Scene {
    gpu: GpuContext,
    renderer: Renderer,
    cloud: PointCloud,
    data: SceneData,
}

fn scene(points: Vec<Point>) -> Scene {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = PointCloud::synthetic(points, DataMode::Song);
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    Scene {
        gpu,
        renderer,
        cloud,
        data,
    }
}

fn song_scene() -> Scene {
    scene(synthetic_song(300_000, 7))
}

fn view(data: &SceneData, moving: bool) -> FrameView {
    FrameView {
        moving,
        ..FrameView::fitted(
            Camera::from_angles(-30.0, 28.0, 4.0),
            data.world_from_data,
            data.world_box(),
            SIZE.0,
            SIZE.1,
        )
    }
}

fn render(scene: &mut Scene, settings: &RenderSettings, moving: bool) -> image::RgbaImage {
    scene
        .data
        .ensure_grid(
            &scene.gpu.device,
            &scene.gpu.queue,
            &scene.renderer,
            &scene.cloud,
            &settings.voxels,
        )
        .expect("voxelize");
    render_image(
        &scene.gpu,
        &scene.renderer,
        Some(&scene.data),
        &view(&scene.data, moving),
        settings,
    )
    .expect("render")
}

fn volume_settings(preset: TransferPreset) -> RenderSettings {
    let mut settings = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    settings.volume.preset = preset;
    settings
}

#[test]
fn volume_presets_match_golden_images_and_differ_from_each_other() {
    let mut scene = song_scene();
    let mut images = Vec::new();
    for preset in TransferPreset::ALL {
        let image = render(&mut scene, &volume_settings(preset), false);
        common::assert_golden(
            &format!("volume_{}", preset.name().to_lowercase()),
            &image,
            common::RAY_MARCH,
        );
        assert!(common::coverage(&image) > 0.1, "{preset:?} is nearly blank");
        images.push(image);
    }
    for i in 0..3 {
        for j in i + 1..3 {
            let (share, mean) = common::difference(&images[i], &images[j], 24);
            assert!(
                share > 0.1 && mean > 6.0,
                "presets {i} and {j} look alike: {:.1}% differ, mean {mean:.1}",
                share * 100.0
            );
        }
    }
}

#[test]
fn hp_tint_matches_golden_image() {
    let mut scene = song_scene();
    let mut settings = volume_settings(TransferPreset::Classic);
    settings.volume.hp_tint = true;
    let tinted = render(&mut scene, &settings, false);
    common::assert_golden("volume_hp_tint", &tinted, common::RAY_MARCH);
    settings.volume.hp_tint = false;
    let plain = render(&mut scene, &settings, false);
    let (share, _) = common::difference(&tinted, &plain, 24);
    assert!(share > 0.1, "hp tint changed only {:.1}%", share * 100.0);
}

#[test]
fn density_and_opacity_scales_change_the_image() {
    let mut scene = song_scene();
    let base_settings = volume_settings(TransferPreset::Ember);
    let base = render(&mut scene, &base_settings, false);
    for (density, opacity) in [(3.0, 1.0), (0.3, 1.0), (1.0, 4.0), (1.0, 0.2)] {
        let mut settings = base_settings.clone();
        settings.volume.density_scale = density;
        settings.volume.opacity_scale = opacity;
        let image = render(&mut scene, &settings, false);
        let (share, _) = common::difference(&base, &image, 16);
        assert!(
            share > 0.05,
            "density {density} opacity {opacity} changed only {:.1}%",
            share * 100.0
        );
        // More density lights more of the field; less lights less.
        if density != 1.0 {
            let (more, base_coverage) = (common::coverage(&image), common::coverage(&base));
            assert_eq!(
                more > base_coverage,
                density > 1.0,
                "{more} vs {base_coverage}"
            );
        }
    }
}

#[test]
fn moving_camera_uses_coarser_steps_but_keeps_the_picture() {
    let mut scene = song_scene();
    let settings = volume_settings(TransferPreset::Classic);
    let rest = render(&mut scene, &settings, false);
    let moving = render(&mut scene, &settings, true);
    let (_, mean) = common::difference(&rest, &moving, 32);
    assert!(
        mean < 12.0,
        "the moving image strays from the still one: {mean:.1}"
    );
    assert!(common::coverage(&moving) > 0.15);
}

#[test]
fn grid_is_built_once_and_rebuilt_only_when_its_settings_change() {
    let mut scene = song_scene();
    let (gpu, renderer, cloud) = (&scene.gpu, &scene.renderer, &scene.cloud);
    let mut settings = volume_settings(TransferPreset::Classic);
    let data = &mut scene.data;
    assert!(data.grid.is_none());
    let ensure = |data: &mut SceneData, settings: &RenderSettings| {
        data.ensure_grid(&gpu.device, &gpu.queue, renderer, cloud, &settings.voxels)
            .expect("voxelize")
    };
    assert!(ensure(data, &settings));
    assert_eq!(data.grid.as_ref().map(|g| g.dims.x), Some(128));
    assert!(!ensure(data, &settings));
    settings.volume.opacity_scale = 2.0;
    assert!(
        !ensure(data, &settings),
        "opacity must not rebuild the grid"
    );
    settings.voxels.resolution = Some(64);
    assert!(ensure(data, &settings));
    assert_eq!(data.grid.as_ref().map(|g| g.dims.x), Some(64));
}

#[test]
fn degenerate_clouds_render_without_failing() {
    let one = Point {
        position: [0.2, 0.1, -0.3],
        scalar: 0.8,
        hp: 0.1,
    };
    for points in [vec![], vec![one], vec![one; 1000]] {
        let n = points.len();
        let mut scene = scene(points);
        let image = render(&mut scene, &volume_settings(TransferPreset::Glacial), false);
        assert_eq!(image.dimensions(), SIZE, "{n} points");
    }
}

/// One progressive volume frame into `target`, submitted; whether the picture is complete.
fn progressive_frame(
    scene: &Scene,
    progressive: &mut ProgressiveVolume<u32>,
    target: &RenderTarget,
    view: &FrameView,
    settings: &RenderSettings,
    now: Instant,
) -> bool {
    let gpu = &scene.gpu;
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    let complete = progressive.frame(
        &gpu.device,
        &gpu.queue,
        &mut encoder,
        &scene.renderer,
        target,
        &scene.data,
        &1,
        view,
        settings,
        now,
    );
    gpu.queue.submit([encoder.finish()]);
    complete
}

/// The volume at rest drawn progressively (a coarse picture, then bands of full-quality rows)
/// ends as the single full render, box and playhead included; on the way the first frame is
/// the coarse picture, whole but not the full one, and a middle frame is the full render in the
/// rows done (the box and markers aside) and the coarse picture below them.
#[test]
fn progressive_volume_starts_coarse_and_ends_as_the_single_render() {
    let mut scene = song_scene();
    let mut settings = volume_settings(TransferPreset::Classic);
    settings.markers = vec![MarkerBox::playhead(0.4)];
    let single = render(&mut scene, &settings, false);
    assert!(
        common::coverage(&single) > 0.1,
        "the volume is nearly blank"
    );
    // The single render's view: the refinement's first frame (its jitter is every band's).
    let mut view = view(&scene.data, false);
    let target = RenderTarget::new(&scene.gpu.device, view.width, view.height);
    let mut progressive = ProgressiveVolume::default();
    progressive.schedule.rows = 37;
    // Frames exactly on the target time: the rows per band stay.
    let mut now = Instant::now();
    assert!(!progressive_frame(
        &scene,
        &mut progressive,
        &target,
        &view,
        &settings,
        now
    ));
    let coarse = target
        .read_rgba(&scene.gpu.device, &scene.gpu.queue)
        .expect("read");
    let (_, coarse_mean) = common::difference(&single, &coarse, 0);
    let coverage = (common::coverage(&coarse), common::coverage(&single));
    assert!(
        coverage.0 > 0.7 * coverage.1,
        "the coarse frame covers {} of the view, the full one {}",
        coverage.0,
        coverage.1
    );
    assert!(coarse_mean > 0.0, "the coarse frame is the full render");
    let mut frames = 1;
    let mut middle = None;
    loop {
        // Every frame has another index, as in the window; the bands keep the first one's.
        view.frame_index += 1;
        now += TARGET_FRAME;
        let complete = progressive_frame(&scene, &mut progressive, &target, &view, &settings, now);
        frames += 1;
        if frames == 3 {
            middle = Some(
                target
                    .read_rgba(&scene.gpu.device, &scene.gpu.queue)
                    .expect("read"),
            );
        }
        if complete {
            break;
        }
        assert!(frames < 100, "never completes");
    }
    // 200 rows in bands of 37: a coarse frame and six bands.
    assert_eq!(frames, 1 + SIZE.1.div_ceil(37) as usize);
    assert_eq!(progressive.progress(), None);
    let last = target
        .read_rgba(&scene.gpu.device, &scene.gpu.queue)
        .expect("read");
    let (share, mean) = common::difference(&single, &last, 1);
    assert!(
        share == 0.0,
        "the refined picture differs from the single render in {share} of pixels (mean {mean})"
    );
    // Two bands in (74 rows): above, the single render, box and playhead included; below, the
    // coarse picture.
    let middle = middle.expect("a middle frame");
    let rows = |image: &image::RgbaImage, range: std::ops::Range<u32>| {
        image::imageops::crop_imm(image, 0, range.start, SIZE.0, range.len() as u32).to_image()
    };
    let (_, below) = common::difference(&rows(&coarse, 80..200), &rows(&middle, 80..200), 0);
    assert_eq!(below, 0.0, "below the bands the coarse picture stays");
    let (above, _) = common::difference(&rows(&single, 0..74), &rows(&middle, 0..74), 1);
    assert_eq!(
        above, 0.0,
        "the rows of the bands drawn are the single render's"
    );
    // Complete: another frame (a playhead moved) draws no band and stays the single render.
    settings.markers = vec![MarkerBox::playhead(0.6)];
    let moved = render(&mut scene, &settings, false);
    now += TARGET_FRAME;
    assert!(progressive_frame(
        &scene,
        &mut progressive,
        &target,
        &view,
        &settings,
        now
    ));
    let again = target
        .read_rgba(&scene.gpu.device, &scene.gpu.queue)
        .expect("read");
    let (share, _) = common::difference(&moved, &again, 1);
    assert_eq!(share, 0.0, "the playhead redrawn over the complete volume");
}
