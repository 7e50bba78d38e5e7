//! Frequency axes at view time (src/data/freq_axis.rs): the GPU voxel grid against the CPU
//! reference of the mapping on each axis, no empty sheets in log mode, golden images of the log
//! and mel views, and hover read-outs that invert the mapping.

use crate::common::{self, demo_song, loudscape};

use std::path::PathBuf;

use glam::Vec3;
use loudscape::data::axes::Axis;
use loudscape::data::cloud::{Point, PointCloud};
use loudscape::data::field::Field;
use loudscape::data::freq_axis::{FreqAxis, FreqMapping, empty_sheets};
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::grid::reference::ReferenceGrid;
use loudscape::render::grid::voxelize::{FIXED_POINT_SCALE, VoxelSettings};
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;
use loudscape::view::pick;

/// The demo song as `--freq-scale log` writes it: z linear in log10 f from bin 1 to Nyquist,
/// the 0 Hz bin dropped (docs/FORMAT.md, Song mode).
fn demo_song_log_scale() -> PointCloud {
    let mut cloud = demo_song();
    let linear = FreqMapping::new(&cloud.meta, FreqAxis::Log).expect("a song");
    let stored = cloud.meta.axes.z.clone();
    let bin_hz = linear.bin_hz;
    let log_axis = Axis::log(&stored.label, "Hz", bin_hz, stored.max);
    cloud.points = cloud
        .points
        .iter()
        .filter_map(|p| {
            let k = linear.bin_of(p.position[2]);
            (k > 0).then(|| Point {
                position: [
                    p.position[0],
                    p.position[1],
                    log_axis.normalized_of(f64::from(k) * bin_hz) as f32,
                ],
                ..*p
            })
        })
        .collect();
    cloud.meta.axes.z = log_axis;
    cloud
}

/// The GPU grid (unsmoothed) of `cloud` on `axis` and the CPU reference of the same mapping.
fn gpu_and_reference(
    gpu: &GpuContext,
    renderer: &Renderer,
    cloud: &PointCloud,
    axis: FreqAxis,
    resolution: u32,
) -> (Field, ReferenceGrid, f64) {
    let mut data = SceneData::new(&gpu.device, renderer, cloud);
    data.set_freq_axis(&gpu.device, renderer, cloud, axis)
        .expect("a song has a frequency axis");
    let settings = VoxelSettings {
        resolution: Some(resolution),
        smoothing_sigma: Some(0.0),
    };
    data.ensure_grid(&gpu.device, &gpu.queue, renderer, cloud, &settings)
        .expect("voxelize");
    let grid = data.grid.as_ref().expect("a grid");
    let field = Field {
        dims: grid.dims,
        box_min: grid.box_min,
        box_max: grid.box_max,
        density: grid
            .read_field(&gpu.device, &gpu.queue, &grid.density)
            .expect("read"),
        hp_mean: grid
            .read_field(&gpu.device, &gpu.queue, &grid.hp_mean)
            .expect("read"),
    };
    let mapping = FreqMapping::new(&cloud.meta, axis).expect("mapping");
    let reference = ReferenceGrid::build_mapped(&cloud.points, resolution, &mapping);
    let reference_sum = f64::from(data.grid_stats.expect("statistics").reference_sum);
    (field, reference, reference_sum)
}

#[test]
fn gpu_grid_follows_the_cpu_mapping_on_every_axis_and_stored_scale() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    for cloud in [demo_song(), demo_song_log_scale()] {
        for axis in FreqAxis::ALL {
            let what = format!("{:?} axis of a {:?} cloud", axis, cloud.meta.axes.z.scale);
            let (field, reference, reference_sum) =
                gpu_and_reference(&gpu, &renderer, &cloud, axis, 64);
            // The same box: the remapped points' bounds.
            assert_eq!(field.box_min, reference.box_min, "{what}");
            assert_eq!(field.box_max, reference.box_max, "{what}");
            // The same voxels hold points, and the densities are the reference's sums over the
            // GPU's reference sum (its 99th percentile; tests/it/voxelize.rs checks that one).
            let gpu_nonempty: Vec<bool> = field.density.iter().map(|&d| d > 0.0).collect();
            let cpu_nonempty: Vec<bool> = reference.sums.iter().map(|&s| s > 0.0).collect();
            let differing = gpu_nonempty
                .iter()
                .zip(&cpu_nonempty)
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differing, 0, "{what}: voxels occupied differently");
            for (i, (&d, &s)) in field.density.iter().zip(&reference.sums).enumerate() {
                let expected = (s / reference_sum).min(1.0);
                let count = f64::from(reference.counts[i].max(1));
                // Fixed-point rounding (half a unit per point) plus f32 arithmetic.
                let tolerance = count * 0.5 / f64::from(FIXED_POINT_SCALE) / reference_sum
                    + 2e-6
                    + expected * 2e-6;
                assert!(
                    (f64::from(d) - expected).abs() <= tolerance,
                    "{what}: voxel {i}: GPU {d}, CPU {expected}"
                );
            }
        }
    }
}

/// Empty z-sheets (slices of the grid with no voxel holding a point) between the lowest and the
/// highest occupied sheet.
fn empty_grid_sheets(field: &Field) -> (usize, usize) {
    let (nx, ny, nz) = (
        field.dims.x as usize,
        field.dims.y as usize,
        field.dims.z as usize,
    );
    let filled: Vec<bool> = (0..nz)
        .map(|k| (0..nx * ny).any(|ij| field.density[ij + nx * ny * k] > 0.0))
        .collect();
    let first = filled.iter().position(|&f| f).expect("occupied");
    let last = filled.iter().rposition(|&f| f).expect("occupied");
    (
        filled[first..=last].iter().filter(|&&f| !f).count(),
        last - first + 1,
    )
}

#[test]
fn log_mode_leaves_no_empty_sheets_on_the_demo() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = demo_song();
    let mapping = FreqMapping::new(&cloud.meta, FreqAxis::Log).expect("mapping");
    // Before: every point at its bin's centre on the log axis (what a log axis without
    // spreading shows): the lowest bins are sheets with empty sheets between them.
    let centred: Vec<Point> = cloud
        .points
        .iter()
        .map(|p| {
            let k = mapping.bin_of(p.position[2]);
            let z = if k == 0 {
                f32::NAN
            } else {
                mapping.view.normalized_of(f64::from(k) * mapping.bin_hz) as f32
            };
            Point {
                position: [p.position[0], p.position[1], z],
                ..*p
            }
        })
        .collect();
    let (before, range_before) = empty_sheets(&centred, 128);
    // After: spread over each bin's extent.
    let (after, range_after) = empty_sheets(&mapping.view_points(&cloud.points), 128);
    eprintln!(
        "log axis, 128 sheets: {before} of {range_before} empty at bin centres, \
         {after} of {range_after} spread"
    );
    assert!(before >= 10, "the centred log axis should show the gaps");
    assert_eq!(after, 0);
    // The GPU grid (unsmoothed, 128^3) agrees.
    let (field, _, _) = gpu_and_reference(&gpu, &renderer, &cloud, FreqAxis::Log, 128);
    let (grid_empty, grid_range) = empty_grid_sheets(&field);
    eprintln!("GPU grid 128^3, log axis: {grid_empty} of {grid_range} z-sheets empty");
    assert_eq!(grid_empty, 0);
}

fn render(cloud: &PointCloud, axis: FreqAxis, view: ViewKind) -> image::RgbaImage {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let mut data = SceneData::new(&gpu.device, &renderer, cloud);
    data.set_freq_axis(&gpu.device, &renderer, cloud, axis)
        .expect("a song");
    let settings = RenderSettings {
        view,
        ..Default::default()
    };
    if view != ViewKind::Points {
        data.ensure_grid(&gpu.device, &gpu.queue, &renderer, cloud, &settings.voxels)
            .expect("voxelize");
    }
    let frame = FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        480,
        270,
    );
    render_image(&gpu, &renderer, Some(&data), &frame, &settings).expect("render")
}

#[test]
fn log_and_mel_views_match_golden() {
    let cloud = demo_song();
    for (axis, view, name, tolerance) in [
        (
            FreqAxis::Log,
            ViewKind::Points,
            "points_demo_song_log",
            common::RASTER_EDGES,
        ),
        (
            FreqAxis::Mel,
            ViewKind::Points,
            "points_demo_song_mel",
            common::RASTER_EDGES,
        ),
        (
            FreqAxis::Log,
            ViewKind::Volume,
            "volume_demo_song_log",
            common::RAY_MARCH,
        ),
    ] {
        let image = render(&cloud, axis, view);
        assert!(common::coverage(&image) > 0.05, "{name} is nearly empty");
        common::assert_golden(name, &image, tolerance);
    }
}

#[test]
fn the_linear_axis_of_a_linear_cloud_draws_as_before() {
    let cloud = demo_song();
    let image = render(&cloud, FreqAxis::Linear, ViewKind::Points);
    common::assert_golden("points_demo_song", &image, common::RASTER_EDGES);
}

#[test]
fn a_log_scale_cloud_looks_like_the_linear_cloud_on_the_log_axis() {
    // The same song, extracted either way, maps to the same view (up to the jitter's seeds,
    // which follow the point index; the log file has no 0 Hz points, which the log axis hides).
    let from_linear = render(&demo_song(), FreqAxis::Log, ViewKind::Points);
    let from_log = render(&demo_song_log_scale(), FreqAxis::Log, ViewKind::Points);
    let (share, _) = common::difference(&from_linear, &from_log, 32);
    assert!(share < 0.2, "{share}");
    let (field_a, _, _) = {
        let gpu = common::gpu();
        let renderer = Renderer::new(&gpu.device);
        gpu_and_reference(&gpu, &renderer, &demo_song(), FreqAxis::Log, 64)
    };
    let (field_b, _, _) = {
        let gpu = common::gpu();
        let renderer = Renderer::new(&gpu.device);
        gpu_and_reference(&gpu, &renderer, &demo_song_log_scale(), FreqAxis::Log, 64)
    };
    // Occupancy along z agrees sheet by sheet (the boxes are the same within a voxel).
    let sheets = |f: &Field| -> Vec<f64> {
        let n = (f.dims.x * f.dims.y) as usize;
        (0..f.dims.z as usize)
            .map(|k| {
                f.density[k * n..(k + 1) * n]
                    .iter()
                    .map(|&d| f64::from(d))
                    .sum()
            })
            .collect()
    };
    let (a, b) = (sheets(&field_a), sheets(&field_b));
    let total: f64 = a.iter().sum();
    let apart: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum();
    assert!(
        apart / total < 0.1,
        "z profiles differ by {}",
        apart / total
    );
}

/// A 1 kHz sine: 32 kHz / 2048 puts bin 64 exactly on 1 kHz; 200 frames, a little leakage into
/// the neighbouring bins 20 dB down.
fn sine_cloud() -> PointCloud {
    let mut cloud = demo_song();
    cloud.meta.source.as_mut().expect("source").sample_rate = Some(32000);
    cloud.meta.stft.as_mut().expect("stft").n_fft = Some(2048);
    cloud.meta.axes.z = Axis::linear("frequency", "Hz", 0.0, 16000.0);
    let z_of = |k: u32| (f64::from(k) / 1024.0 * 2.0 - 1.0) as f32;
    cloud.points = (0..200)
        .flat_map(|frame| {
            let x = frame as f32 / 199.0 * 2.0 - 1.0;
            [(63, 0.3), (64, 0.9), (65, 0.3)].map(|(k, y)| Point {
                position: [x, y, z_of(k)],
                scalar: 0.5 + y * 0.5,
                hp: 1.0,
            })
        })
        .collect();
    cloud
}

/// The frequency a read-out names: "1.000 kHz (B5 +21 ct)" or "996.1 Hz".
fn hertz_of(reading: &str) -> f64 {
    let mut words = reading.split(' ');
    let (number, unit) = (words.next().expect("value"), words.next().expect("unit"));
    let value: f64 = number.parse().expect("a number");
    match unit {
        "kHz" => value * 1000.0,
        "Hz" => value,
        other => panic!("unit {other}"),
    }
}

#[test]
fn hover_reads_a_1_khz_sine_as_1_khz_on_every_axis() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = sine_cloud();
    for axis in FreqAxis::ALL {
        // Points: pick among the points as the view shows them, read the stored point.
        let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
        data.set_freq_axis(&gpu.device, &renderer, &cloud, axis)
            .expect("a song");
        let mapping = FreqMapping::new(&cloud.meta, axis).expect("mapping");
        let shown = mapping.view_points(&cloud.points);
        let view = FrameView::fitted(
            Camera::default(),
            data.world_from_data,
            data.world_box(),
            640,
            360,
        );
        let sine = 3 * 100 + 1;
        let px = view
            .project(Vec3::from(shown[sine].position))
            .expect("on screen");
        let picked = pick::pick_point(&shown, &view, px, 2.0, 0.0).expect("a point");
        let readings = pick::point_readings(&cloud.meta.axes, &cloud.points[picked]);
        let z = readings.iter().find(|r| r.name.starts_with("frequency"));
        let hz = hertz_of(&z.expect("a frequency reading").value);
        assert!((hz - 1000.0).abs() < 0.5, "{axis:?} point reads {hz}");

        // Voxels: a ray up the frequency axis through the sine's loudest row stops at the
        // sine's voxels, which read 1 kHz through the view's axis (within a voxel).
        let (field, _, _) = gpu_and_reference(&gpu, &renderer, &cloud, axis, 128);
        let origin = Vec3::new(0.0, 0.9, -2.0);
        let hit = field
            .pick(origin, Vec3::Z, 0.05)
            .expect("the sine's voxels");
        let readings = pick::voxel_readings(&data.axes, &hit);
        let z = readings.iter().find(|r| r.name.starts_with("frequency"));
        let hz = hertz_of(&z.expect("a frequency reading").value);
        let voxel = (field.box_max.z - field.box_min.z) / field.dims.z as f32;
        let low = data.axes.z.value_at(f64::from(hit.position.z - voxel));
        let high = data.axes.z.value_at(f64::from(hit.position.z + voxel));
        let half_bin = mapping.bin_hz / 2.0;
        assert!(
            hz > 1000.0 - half_bin - (hz - low) && hz < 1000.0 + half_bin + (high - hz),
            "{axis:?} voxel reads {hz} (voxel {low}..{high})"
        );
        assert!((hz - 1000.0).abs() < 40.0, "{axis:?} voxel reads {hz}");
    }
}

#[test]
fn render_takes_freq_axis_and_refuses_what_has_none() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = common::output_dir().join("freq_axis_cli");
    std::fs::create_dir_all(&dir).expect("mkdir");
    let out = dir.join("mel.png");
    let _ = std::fs::remove_file(&out);
    let song = repo.join("data/demo_song.ply");
    let timeline = repo.join("data/demo_timeline.ply");
    let (song, timeline, out_text) = (
        song.to_str().unwrap(),
        timeline.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let output = loudscape(&[
        "render",
        song,
        "--freq-axis",
        "mel",
        "--size",
        "320x200",
        "-o",
        out_text,
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(common::coverage(&image::open(&out).expect("png").to_rgba8()) > 0.02);
    std::fs::remove_file(&out).expect("remove");
    // An unknown name is a usage error (exit 2, clap's line naming the possible values); an
    // axis the cloud cannot take is refused for that file (exit 1).
    for (input, axis, names, code) in [
        (song, "octave", "octave", 2),
        (timeline, "log", "demo_timeline.ply", 1),
    ] {
        let output = loudscape(&["render", input, "--freq-axis", axis, "-o", out_text]);
        assert_eq!(output.status.code(), Some(code), "{axis}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{axis}: {stderr}");
        assert!(lines[0].contains(names), "{axis}: {}", lines[0]);
        assert!(!stderr.contains("panicked"));
        assert!(!out.exists(), "{axis}: an output was written");
    }
    // A timeline's linear axis is its stored z: rendering it as before is fine.
    let output = loudscape(&[
        "render",
        timeline,
        "--freq-axis",
        "linear",
        "--size",
        "320x200",
        "-o",
        out_text,
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}
