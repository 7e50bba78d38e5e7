//! A/B compare (issue 17): the difference grid on the GPU against its CPU mirror, a song
//! against itself and against a copy 6 dB louder, golden images of the compare and difference
//! views, and the command line.

use crate::common::{self, demo_song, loudscape, repo};

use std::path::PathBuf;

use loudscape::data::cloud::PointCloud;
use loudscape::data::compare::on_union_axes;
use loudscape::render::compare::CompareScene;
use loudscape::render::grid::difference::{
    DifferenceMeasure, reference_columns, reference_difference, shared_scales,
};
use loudscape::render::grid::voxelize::{VoxelSettings, VoxelizeRequest};
use loudscape::render::scene::{RenderSettings, Renderer, ViewKind};
use loudscape::ui::compare_shot::{CompareView, render_compare_image};
use loudscape::view::camera::Camera;

/// The demo song made 6 dB louder exactly as the extractor makes it from the audio gained by
/// +6 dB (checked against the extractor's output of the demo audio gained in a float WAV): every
/// level is 6 dB higher, so the level axis's ends move up by 6 dB while the normalized
/// coordinates stay (the floor is relative to the loudest bin), and the scalar's axis, whose
/// range the extractor derives from the levels, moves up by 6 dB with the scalars staying.
fn louder_copy(song: &PointCloud, gain_db: f64) -> PointCloud {
    let mut louder = song.clone();
    louder.path = PathBuf::from("demo_song_plus_6_dB.ply");
    let axes = &mut louder.meta.axes;
    for axis in [&mut axes.y, &mut axes.scalar] {
        axis.min += gain_db;
        axis.max += gain_db;
    }
    louder
}

#[test]
fn a_song_against_itself_differs_by_exactly_zero() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let song = demo_song();
    let (a, b) = on_union_axes(&song, &song).expect("same axes");
    let settings = VoxelSettings::default();
    let mut scene = CompareScene::new(&gpu.device, &renderer, &song, &song).expect("compare");
    let shared_box = scene.shared_box();
    // The GPU grids of both, in the shared box, read back: the CPU mirror's input.
    let voxelize = |cloud: &PointCloud| {
        renderer
            .voxelize
            .voxelize(
                &gpu.device,
                &gpu.queue,
                &VoxelizeRequest::new(&cloud.points, 128, settings.smoothing_for(cloud.meta.mode))
                    .in_box(Some(shared_box)),
            )
            .expect("voxelize")
    };
    let (grid_a, stats_a) = voxelize(&a);
    let (grid_b, stats_b) = voxelize(&b);
    let density_a = grid_a
        .read_field(&gpu.device, &gpu.queue, &grid_a.density)
        .unwrap();
    let density_b = grid_b
        .read_field(&gpu.device, &gpu.queue, &grid_b.density)
        .unwrap();
    assert!(density_a.iter().filter(|d| **d > 0.0).count() > 10_000);
    let grids = renderer
        .difference
        .build(
            &gpu.device,
            &gpu.queue,
            (&grid_a, &stats_a),
            (&grid_b, &stats_b),
        )
        .expect("difference");
    let gpu_difference = grids.read_difference(&gpu.device, &gpu.queue).unwrap();
    let (scale_a, scale_b) = shared_scales(&stats_a, &stats_b);
    let cpu_difference = reference_difference(&density_a, &density_b, scale_a, scale_b);
    assert_eq!(gpu_difference, cpu_difference, "GPU and CPU differ");
    assert!(
        gpu_difference.iter().all(|d| *d == 0.0),
        "a song against itself must differ by exactly zero"
    );
    let columns = grids.read_columns(&gpu.device, &gpu.queue).unwrap();
    assert!(columns.iter().all(|c| *c == 0.0));
    // The scene's own build agrees, and its shown grid is empty (transparent).
    scene
        .ensure_grids(&gpu.device, &gpu.queue, &renderer, &settings)
        .expect("grids");
    let built = scene.grids.as_ref().unwrap();
    let shown = built
        .grids
        .shown
        .read_field(&gpu.device, &gpu.queue, &built.grids.shown.density)
        .unwrap();
    assert!(shown.iter().all(|d| *d == 0.0));
}

#[test]
fn a_copy_6_db_louder_is_louder_everywhere_the_song_is() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let song = demo_song();
    let louder = louder_copy(&song, 6.0);
    let mut scene = CompareScene::new(&gpu.device, &renderer, &song, &louder).expect("compare");
    // On the union axes the same point sits 6 dB higher in B.
    let axis = &scene.a.meta.axes.y;
    let i = 1234;
    let db = axis.value_at(f64::from(scene.b.points[i].position[1]))
        - axis.value_at(f64::from(scene.a.points[i].position[1]));
    assert!((db - 6.0).abs() < 1e-3, "moved by {db} dB");
    scene
        .ensure_grids(
            &gpu.device,
            &gpu.queue,
            &renderer,
            &VoxelSettings::default(),
        )
        .expect("grids");
    let built = scene.grids.as_ref().unwrap();
    let grids = &built.grids;
    let difference = grids.read_difference(&gpu.device, &gpu.queue).unwrap();
    let columns = grids.read_columns(&gpu.device, &gpu.queue).unwrap();
    // The GPU's column sums against the CPU mirror over the GPU's difference.
    let expected = reference_columns(&difference, grids.dims);
    let scale = expected.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    for (g, c) in columns.iter().zip(&expected) {
        assert!((g - c).abs() <= 1e-5 * scale.max(1.0), "{g} against {c}");
    }
    // The density difference alone is a dipole: B's points sit higher, so some voxels lose.
    assert!(difference.iter().any(|d| *d < 0.0));
    assert!(difference.iter().any(|d| *d > 0.0));
    // Where the song is (any column where A has density), the level-weighted difference is
    // positive.
    let density_a = grids
        .scaled_a
        .read_field(&gpu.device, &gpu.queue, &grids.scaled_a.density)
        .unwrap();
    let dims = grids.dims;
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let mut song_columns = 0;
    for k in 0..nz {
        for i in 0..nx {
            let present = (0..ny).any(|j| density_a[i + nx * (j + ny * k)] > 0.0);
            if present {
                song_columns += 1;
                let value = columns[i + nx * k];
                assert!(value > 0.0, "column ({i}, {k}) is {value}, not louder");
            }
        }
    }
    assert!(song_columns > nx * nz / 4, "{song_columns} columns");
    // And the other way round it is negative everywhere.
    let mut reversed = CompareScene::new(&gpu.device, &renderer, &louder, &song).expect("compare");
    reversed
        .ensure_grids(
            &gpu.device,
            &gpu.queue,
            &renderer,
            &VoxelSettings::default(),
        )
        .expect("grids");
    let reversed_columns = reversed
        .grids
        .as_ref()
        .unwrap()
        .grids
        .read_columns(&gpu.device, &gpu.queue)
        .unwrap();
    for (forward, backward) in columns.iter().zip(&reversed_columns) {
        if *forward > 0.0 {
            assert!(*backward < 0.0);
        }
    }
}

const SIZE: (u32, u32) = (720, 260);

/// The fitted default camera, as the command uses without --camera.
fn camera() -> Option<Camera> {
    None
}

fn picture(what: CompareView, size: (u32, u32)) -> image::RgbaImage {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let song = demo_song();
    let louder = louder_copy(&song, 6.0);
    let mut scene = CompareScene::new(&gpu.device, &renderer, &song, &louder).expect("compare");
    let mut settings = RenderSettings::default();
    settings.points.size_px = 1.5;
    render_compare_image(
        &gpu,
        &renderer,
        &mut scene,
        what,
        camera(),
        size,
        &settings,
        true,
        None,
        None,
    )
    .expect("render")
}

#[test]
fn golden_compare_side_by_side() {
    let image = picture(CompareView::SideBySide(ViewKind::Points), SIZE);
    assert!(common::coverage(&image) > 0.05);
    common::assert_golden("compare_points", &image, common::RASTER_EDGES);
}

#[test]
fn golden_compare_volumes_on_one_scale() {
    let image = picture(CompareView::SideBySide(ViewKind::Volume), SIZE);
    common::assert_golden("compare_volume", &image, common::RAY_MARCH);
}

#[test]
fn golden_difference_views() {
    let density = picture(
        CompareView::Difference(DifferenceMeasure::Density),
        (480, 300),
    );
    common::assert_golden("difference_density", &density, common::RASTER_EDGES);
    let level = picture(
        CompareView::Difference(DifferenceMeasure::Level),
        (480, 300),
    );
    common::assert_golden("difference_level", &level, common::RASTER_EDGES);
    // B is louder everywhere: the level view is warm (red over blue) wherever it is tinted.
    let (mut warm, mut cool) = (0usize, 0usize);
    for p in level.pixels() {
        let (r, b) = (i32::from(p[0]), i32::from(p[2]));
        if r > b + 40 {
            warm += 1;
        } else if b > r + 40 {
            cool += 1;
        }
    }
    assert!(warm > 20 * cool.max(1), "warm {warm}, cool {cool}");
}

#[test]
fn the_command_renders_compare_and_difference_and_refuses_a_timeline() {
    let dir = common::output_dir().join("compare_cli");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let song = repo().join("data/demo_song.ply");
    let timeline = repo().join("data/demo_timeline.ply");
    let out = dir.join("difference.png");
    let output = loudscape(&[
        "render".as_ref(),
        song.as_os_str(),
        "--compare".as_ref(),
        song.as_os_str(),
        "--view".as_ref(),
        "difference".as_ref(),
        "--size".as_ref(),
        "320x200".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(image::open(&out).is_ok());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("difference, density"), "{stderr}");
    let output = loudscape(&[
        "render".as_ref(),
        song.as_os_str(),
        "--compare".as_ref(),
        timeline.as_os_str(),
        "--view".as_ref(),
        "compare".as_ref(),
        "-o".as_ref(),
        dir.join("no.png").as_os_str(),
    ]);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("demo_timeline.ply"), "{stderr}");
    assert!(!dir.join("no.png").exists());
    // The output may not be the second input either.
    let output = loudscape(&[
        "render".as_ref(),
        song.as_os_str(),
        "--compare".as_ref(),
        out.as_os_str(),
        "--view".as_ref(),
        "compare".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!output.status.success());
}
