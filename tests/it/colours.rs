//! Colour maps, the light background and the legends in pictures, rendered headless: the GPU's
//! colours against the CPU maps (`render::colormap`), golden images of a non-default map and of
//! the light background, the legend's pixels against the map it keys, and the CLI flags.

use crate::common::{self, demo_song, loudscape, repo};

use loudscape::data::cloud::{DataMode, Point, PointCloud};
use loudscape::data::synthetic::synthetic_song;
use loudscape::render::colormap::{Background, Colours, DensityColourMap, HpColourMap, Ramp};
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::volume::TransferPreset;
use loudscape::ui::screenshot;
use loudscape::ui::{annotation, legends};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

fn fitted(data: &SceneData, w: u32, h: u32) -> FrameView {
    FrameView::fitted(
        Camera::from_angles(-30.0, 28.0, 4.0),
        data.world_from_data,
        data.world_box(),
        w,
        h,
    )
}

fn light() -> Colours {
    Colours {
        background: Background::Light,
        ..Colours::default()
    }
}

/// Points land in the colour of the chosen hp map, as the CPU map gives it.
#[test]
fn points_take_the_chosen_hp_map() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let points: Vec<Point> = [0.0f32, 0.3, 0.5, 0.8, 1.0]
        .iter()
        .enumerate()
        .map(|(i, &hp)| Point {
            position: [-0.8 + 0.4 * i as f32, 0.0, 0.0],
            scalar: 1.0,
            hp,
        })
        .collect();
    let cloud = PointCloud::synthetic(points.clone(), DataMode::Song);
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let view = fitted(&data, 320, 160);
    for map in HpColourMap::ALL {
        let mut settings = RenderSettings {
            show_box: false,
            ..Default::default()
        };
        settings.colours.hp = map;
        settings.points.size_px = 9.0;
        let image = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
        for point in &points {
            let pixel = view.project(point.position.into()).expect("in view");
            let got = image.get_pixel(pixel.x as u32, pixel.y as u32);
            let want = map.points().sample_u8(point.hp);
            for c in 0..3 {
                assert!(
                    got[c].abs_diff(want[c]) <= 3,
                    "{map:?} hp {}: pixel {got:?}, map {want:?}",
                    point.hp
                );
            }
        }
    }
}

fn volume_scene() -> (GpuContext, Renderer, PointCloud, SceneData) {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = PointCloud::synthetic(synthetic_song(300_000, 7), DataMode::Song);
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    data.ensure_grid(
        &gpu.device,
        &gpu.queue,
        &renderer,
        &cloud,
        &Default::default(),
    )
    .expect("voxelize");
    (gpu, renderer, cloud, data)
}

/// A non-default density map: golden, and different from the preset's own ramp.
#[test]
fn volume_in_magma_matches_its_golden() {
    let (gpu, renderer, _cloud, data) = volume_scene();
    let view = fitted(&data, 320, 200);
    let mut settings = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    let classic = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    settings.colours.density = DensityColourMap::Magma;
    let magma = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    let (share, _) = common::difference(&classic, &magma, 24);
    assert!(share > 0.1, "magma looks like classic ({share})");
    common::assert_golden("volume_magma", &magma, common::RAY_MARCH);
}

/// On the light background the volume is still readable: it is drawn in ink darker than the
/// paper (not washed out to white), the dense core darkest, and the background is white.
#[test]
fn volume_on_the_light_background_is_ink_on_paper() {
    let (gpu, renderer, _cloud, data) = volume_scene();
    let view = fitted(&data, 320, 200);
    let settings = RenderSettings {
        view: ViewKind::Volume,
        show_box: false,
        colours: light(),
        ..Default::default()
    };
    let image = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    assert_eq!(image.get_pixel(0, 0).0, [255, 255, 255, 255]);
    let luma =
        |p: &image::Rgba<u8>| 0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32;
    let inked = image.pixels().filter(|p| luma(p) < 200.0).count() as f64;
    let dark = image.pixels().filter(|p| luma(p) < 120.0).count() as f64;
    let total = (image.width() * image.height()) as f64;
    assert!(
        inked / total > 0.05,
        "too little of the volume shows: {}",
        inked / total
    );
    assert!(dark > 0.0, "no dense core drawn dark");
    common::assert_golden("volume_light", &image, common::RAY_MARCH);
}

/// Renders `settings` of the demo song as a screenshot (labels and legend drawn over it).
fn demo_picture(settings: &RenderSettings, w: u32, h: u32) -> image::RgbaImage {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = demo_song();
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    if settings.view != ViewKind::Points {
        data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &settings.voxels)
            .expect("voxelize");
    }
    let view = FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        w,
        h,
    );
    screenshot::render_view(&gpu, &renderer, Some((&cloud, &data)), &view, settings)
        .expect("screenshot")
}

/// The strip's colour at `t` as painted (centre row), for comparing with the map.
fn strip_pixel(image: &image::RgbaImage, t: f32) -> [u8; 3] {
    let rect = legends::key_strip_rect(eframe::egui::Rect::from_min_size(
        eframe::egui::Pos2::ZERO,
        eframe::egui::vec2(image.width() as f32, image.height() as f32),
    ));
    let x = rect.left() + 2.0 + (rect.width() - 4.0) * t;
    let y = rect.center().y;
    let p = image.get_pixel(x as u32, y as u32);
    [p[0], p[1], p[2]]
}

fn assert_near(got: [u8; 3], want: [u8; 3], tolerance: u8, what: &str) {
    assert!(
        (0..3).all(|c| got[c].abs_diff(want[c]) <= tolerance),
        "{what}: got {got:?}, want {want:?}"
    );
}

/// The points' picture carries its hp key: the strip's pixels are the map's colours, and the
/// name is written top left.
#[test]
fn headless_pictures_carry_the_hp_key_and_the_name() {
    for map in [HpColourMap::Classic, HpColourMap::PuOr] {
        let mut settings = RenderSettings::default();
        settings.colours.hp = map;
        let image = demo_picture(&settings, 640, 400);
        for t in [0.05f32, 0.5, 0.95] {
            let want = map.points().sample_u8(t);
            assert_near(strip_pixel(&image, t), want, 12, &format!("{map:?} at {t}"));
        }
        // Text of the name in the top left: light ink on the dark background.
        let name_ink = (14..200)
            .flat_map(|x| (14..32).map(move |y| (x, y)))
            .filter(|&(x, y)| image.get_pixel(x, y)[0] > 150)
            .count();
        assert!(name_ink > 40, "{map:?}: no name drawn ({name_ink} pixels)");
    }
}

/// The volume's picture keys its transfer function over density, in the chosen map.
#[test]
fn volume_pictures_carry_the_density_key() {
    let mut settings = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    settings.colours.density = DensityColourMap::Viridis;
    let image = demo_picture(&settings, 640, 400);
    let strip = settings.colours.legend(TransferPreset::Classic, 101);
    for t in [0.1f32, 0.5, 0.9] {
        let [r, g, b, _] = strip[(t * 100.0).round() as usize];
        assert_near(
            strip_pixel(&image, t),
            [r, g, b],
            14,
            &format!("density {t}"),
        );
    }
    // Viridis' top end (yellow) lies at the right of the strip.
    let right = strip_pixel(&image, 0.99);
    assert!(
        right[0] > 200 && right[1] > 180 && right[2] < 100,
        "{right:?}"
    );
}

/// The light background: white paper, dark ink for labels and the legend. Golden.
#[test]
fn light_background_picture_matches_its_golden() {
    let settings = RenderSettings {
        colours: light(),
        ..Default::default()
    };
    let image = demo_picture(&settings, 640, 400);
    assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255, 255]);
    let dark_text = (14..200)
        .flat_map(|x| (14..32).map(move |y| (x, y)))
        .filter(|&(x, y)| image.get_pixel(x, y)[0] < 100)
        .count();
    assert!(dark_text > 40, "no dark name on the light background");
    common::assert_golden("points_light", &image, common::RASTER_EDGES);
}

/// The diverging painter puts zero at the map's centre and the signed ends at its ends.
#[test]
fn the_diverging_legend_centres_zero() {
    let gpu = common::gpu();
    let target = RenderTarget::new(&gpu.device, 400, 120);
    let renderer = Renderer::new(&gpu.device);
    // Clear the target (the dark background) by rendering an empty scene into it.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let view = FrameView::at_rest(Camera::default(), glam::Mat4::IDENTITY, 400, 120);
    renderer.render(
        &gpu.queue,
        &mut encoder,
        &target,
        None,
        &view,
        &RenderSettings::default(),
    );
    gpu.queue.submit([encoder.finish()]);
    let ramp = Ramp::new(&loudscape::render::colormap_data::PUOR);
    let strip = eframe::egui::Rect::from_min_size(
        eframe::egui::pos2(40.0, 40.0),
        eframe::egui::vec2(300.0, 16.0),
    );
    // As the window paints a diverging legend: laid out by annotate::legend, painted by egui.
    screenshot::paint_headless(&gpu, &target, |painter, _| {
        let shapes = loudscape::annotate::legend::diverging(
            annotation::rect(strip),
            &ramp,
            (-2.0, 6.0),
            "B - A, density",
            Background::Dark,
        );
        annotation::paint(painter, &shapes);
    });
    let image = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let at = |value: f32| {
        let x = strip.left() + strip.width() * (value + 2.0) / 8.0;
        let x = x.clamp(strip.left() + 2.0, strip.right() - 2.0);
        let p = image.get_pixel(x as u32, strip.center().y as u32);
        [p[0], p[1], p[2]]
    };
    assert_near(at(0.0), ramp.sample_u8(0.5), 10, "zero");
    assert_near(at(6.0), ramp.sample_u8(1.0), 14, "+6");
    assert_near(at(-2.0), ramp.sample_u8(1.0 / 3.0), 14, "-2");
}

/// `render --background light --colormap puor` writes a white picture with the legend; bad
/// names fail with one line naming the choices.
#[test]
fn render_takes_colour_flags_and_rejects_bad_names() {
    let out = common::output_dir().join("colours_cli_light.png");
    let input = repo().join("data/demo_song.ply");
    let output = loudscape(&[
        "render",
        input.to_str().unwrap(),
        "--size",
        "640x400",
        "--background",
        "light",
        "--colormap",
        "puor",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let image = image::open(&out).expect("png").to_rgba8();
    assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255, 255]);
    let want = HpColourMap::PuOr.points().sample_u8(0.05);
    assert_near(strip_pixel(&image, 0.05), want, 12, "puor key");

    for (flag, value, says) in [
        (
            "--colormap",
            "rainbow",
            "'rainbow' for '--colormap <COLORMAP>' [possible values: classic, puor, cividis, viridis]",
        ),
        (
            "--tf-colormap",
            "jet",
            "'jet' for '--tf-colormap <TF_COLORMAP>' [possible values: preset, viridis, cividis, magma, inferno]",
        ),
        (
            "--background",
            "grey",
            "'grey' for '--background <BACKGROUND>' [possible values: dark, light]",
        ),
    ] {
        let output = loudscape(&[
            "render",
            input.to_str().unwrap(),
            flag,
            value,
            "-o",
            common::output_dir().join("never.png").to_str().unwrap(),
        ]);
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
}

/// `render-demo` writes every view with its legend: the key strip is not the background, and
/// in the light background the paper is white.
#[test]
fn render_demo_pictures_carry_legends() {
    let out_dir = common::output_dir().join("colours_demo");
    let _ = std::fs::remove_dir_all(&out_dir);
    let input = repo().join("data/demo_timeline.ply");
    let output = loudscape(&[
        "-q",
        "render-demo",
        "--out-dir",
        out_dir.to_str().unwrap(),
        "--size",
        "640x400",
        "--background",
        "light",
        "--colormap",
        "viridis",
        input.to_str().unwrap(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    for view in ["points", "surface", "volume"] {
        let path = out_dir.join(format!("demo_timeline_{view}.png"));
        let image = image::open(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .to_rgba8();
        assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255, 255], "{view}");
        let want = if view == "volume" {
            let colours = Colours {
                hp: HpColourMap::Viridis,
                ..light()
            };
            let [r, g, b, _] = colours.legend(TransferPreset::Classic, 101)[90];
            [r, g, b]
        } else if view == "surface" {
            HpColourMap::Viridis.surface().sample_u8(0.9)
        } else {
            HpColourMap::Viridis.points().sample_u8(0.9)
        };
        assert_near(strip_pixel(&image, 0.9), want, 14, view);
    }
}
