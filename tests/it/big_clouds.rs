//! Large clouds on the host: the points are sent in bounded pieces, grids are built from the
//! device's copy (the host's may be gone), and a points frame can be drawn in slices that add up
//! to the single-pass frame. Headless, on lavapipe where there is no GPU.

use crate::common::{self, view_of};

use loudscape::data::cloud::{DataMode, POINT_BYTES, PointCloud};
use loudscape::data::synthetic::synthetic_song;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::grid::voxelize::{VoxelSettings, VoxelizeRequest};
use loudscape::render::headless::render_image;
use loudscape::render::points::{PointsGpu, progressive_ranges};
use loudscape::render::scene::{Recording, RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::ui::frame_cache::RenderKey;
use loudscape::ui::progressive::ProgressivePoints;
use loudscape::view::frame_view::FrameView;

fn song(count: usize) -> PointCloud {
    PointCloud::synthetic(synthetic_song(count, 7), DataMode::Song)
}

fn fields(gpu: &GpuContext, data: &SceneData) -> (Vec<f32>, Vec<f32>) {
    let grid = data.grid.as_ref().expect("a grid");
    (
        grid.read_field(&gpu.device, &gpu.queue, &grid.density)
            .expect("read density"),
        grid.read_field(&gpu.device, &gpu.queue, &grid.hp_mean)
            .expect("read hp"),
    )
}

/// Points sent in pieces far smaller than a chunk (and chunks that do not divide the pieces)
/// draw exactly the image of the one-shot upload.
#[test]
fn bounded_upload_draws_the_same_image() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = song(60_001);
    let whole = SceneData::new(&gpu.device, &renderer, &cloud);
    let mut pieces = SceneData::new(&gpu.device, &renderer, &cloud);
    let chunk_bytes = 7_001 * POINT_BYTES as u64;
    pieces.points = PointsGpu::upload_bounded(
        &gpu.device,
        &gpu.queue,
        &renderer.points,
        &cloud.points,
        chunk_bytes,
        1_000 * POINT_BYTES as u64 + 8,
    );
    assert_eq!(pieces.points.chunk_count(), 9);
    assert_eq!(pieces.points.total, 60_001);
    let streamed = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
    // Taking the points: sent from the end in pieces that cross no chunk border.
    let mut drained = SceneData::new(&gpu.device, &renderer, &cloud);
    let mut taken = cloud.points.clone();
    drained.points = PointsGpu::upload_draining(
        &gpu.device,
        &gpu.queue,
        &renderer.points,
        &mut taken,
        chunk_bytes,
        1_000 * POINT_BYTES as u64 + 8,
    );
    assert!(
        taken.is_empty() && taken.capacity() == 0,
        "points left on the host"
    );
    assert_eq!(drained.points.chunk_count(), 9);
    let mut owned = cloud.clone();
    let drained_whole = SceneData::upload_draining(&gpu.device, &gpu.queue, &renderer, &mut owned);
    assert!(owned.points.is_empty());
    assert_eq!(owned.bounds, cloud.bounds);
    let view = view_of(&whole, 320, 180);
    let settings = RenderSettings::default();
    let a = render_image(&gpu, &renderer, Some(&whole), &view, &settings).expect("render");
    assert!(
        common::coverage(&a) > 0.05,
        "the points view is nearly empty"
    );
    for other in [&pieces, &streamed, &drained, &drained_whole] {
        let b = render_image(&gpu, &renderer, Some(other), &view, &settings).expect("render");
        let (share, _) = common::difference(&a, &b, 0);
        assert_eq!(share, 0.0, "the bounded upload draws a different image");
    }
}

/// The grid built from the points view's GPU buffers (several chunks), with the host's points
/// dropped, equals the grid built from the host's points.
#[test]
fn grid_from_the_device_copy_equals_the_grid_from_the_host() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = song(50_000);
    let voxels = VoxelSettings::default();
    let mut from_host = SceneData::new(&gpu.device, &renderer, &cloud);
    let resolution = voxels.resolution_for(DataMode::Song);
    // The compute passes from the host's points, as the device's copy is voxelized (a device
    // that is the CPU would build the host's on the CPU: tests/it/voxelize.rs compares those).
    let frame = loudscape::render::gpu::frame::FrameBinding::new(&gpu.device);
    let passes = loudscape::render::grid::voxelize::VoxelizePass::new(&gpu.device, &frame)
        .with_cpu_engine(false);
    let (grid, stats) = passes
        .voxelize(
            &gpu.device,
            &gpu.queue,
            &VoxelizeRequest::new(
                &cloud.points,
                resolution,
                voxels.smoothing_for(DataMode::Song),
            ),
        )
        .expect("voxelize from the host");
    from_host.grid = Some(grid);

    let mut device_only =
        SceneData::with_chunk_limit(&gpu.device, &renderer, &cloud, 9_999 * POINT_BYTES as u64);
    assert!(device_only.points.chunk_count() >= 5);
    let mut dropped = cloud.clone();
    dropped.points = Vec::new();
    let rebuilt = device_only
        .ensure_grid(&gpu.device, &gpu.queue, &renderer, &dropped, &voxels)
        .expect("voxelize from the device");
    assert!(rebuilt);
    let (a, b) = (
        from_host.grid.as_ref().unwrap(),
        device_only.grid.as_ref().unwrap(),
    );
    assert_eq!((a.box_min, a.box_max), (b.box_min, b.box_max));
    assert_eq!(device_only.grid_stats, Some(stats));
    assert!(stats.nonempty > 1000, "the grid is nearly empty");
    let (density_a, hp_a) = fields(&gpu, &from_host);
    let (density_b, hp_b) = fields(&gpu, &device_only);
    assert_eq!(density_a, density_b, "density differs");
    assert_eq!(hp_a, hp_b, "mean hp differs");
}

/// An empty cloud's grid from the device is built too (all empty), without a panic.
#[test]
fn empty_cloud_grid_from_the_device() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = song(0);
    let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
    data.ensure_grid(
        &gpu.device,
        &gpu.queue,
        &renderer,
        &cloud,
        &VoxelSettings::default(),
    )
    .expect("voxelize an empty cloud");
    assert_eq!(data.grid_stats.map(|s| s.nonempty), Some(0));
}

#[test]
fn progressive_ranges_cover_every_point_once() {
    for (total, per) in [
        (0, 5),
        (1, 5),
        (10, 5),
        (11, 5),
        (1_000_003, 65_536),
        (7, 100),
    ] {
        let ranges = progressive_ranges(total, per);
        let mut next = 0;
        for r in &ranges {
            assert_eq!(r.start, next, "a gap or an overlap at {next}");
            assert!(r.end > r.start && r.end - r.start <= per);
            next = r.end;
        }
        assert_eq!(next, total, "not every point is drawn");
        assert_eq!(ranges.len() as u64, total.div_ceil(per));
    }
}

/// A points frame drawn in slices (each its own submission, slices crossing chunk borders)
/// ends as the single-pass frame.
#[test]
fn points_drawn_in_slices_equal_the_single_pass_frame() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = song(80_000);
    let data =
        SceneData::with_chunk_limit(&gpu.device, &renderer, &cloud, 30_000 * POINT_BYTES as u64);
    assert_eq!(data.points.chunk_count(), 3);
    let view = view_of(&data, 320, 180);
    let settings = RenderSettings {
        view: ViewKind::Points,
        ..Default::default()
    };
    let single = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    let target = RenderTarget::new(&gpu.device, view.width, view.height);
    let ranges = progressive_ranges(data.points.total, 12_345);
    assert_eq!(ranges.len(), 7);
    let mut first_slice = None;
    for (i, range) in ranges.into_iter().enumerate() {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let recording = Recording {
            queue: &gpu.queue,
            encoder: &mut encoder,
            target: &target,
        };
        renderer.render_points_slice(recording, &data, &view, &settings, range);
        gpu.queue.submit([encoder.finish()]);
        if i == 0 {
            first_slice = Some(target.read_rgba(&gpu.device, &gpu.queue).expect("read"));
        }
    }
    let sliced = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    // The same primitives in the same order: the same pixels.
    let (share, _) = common::difference(&single, &sliced, 0);
    assert_eq!(share, 0.0, "sliced frame differs in {share} of pixels");
    // The first slice alone is a partial picture: fewer points than the whole.
    let first = first_slice.unwrap();
    assert!(common::coverage(&first) < common::coverage(&sliced));
    assert!(common::coverage(&first) > 0.0);
}

/// One progressive frame of `key` into `target`, submitted; whether the picture is complete.
fn progressive_frame(
    gpu: &GpuContext,
    renderer: &Renderer,
    progressive: &mut ProgressivePoints,
    target: &RenderTarget,
    data: &SceneData,
    view: &FrameView,
    settings: &RenderSettings,
) -> bool {
    let key = RenderKey::new(view, settings, Some(1), 0);
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    let complete = progressive.frame(
        &gpu.device,
        &gpu.queue,
        &mut encoder,
        renderer,
        target,
        data,
        &key,
        view,
        settings,
    );
    gpu.queue.submit([encoder.finish()]);
    complete
}

/// While the slices refine, the points they have not reached stand in sparsely: the first
/// frame at rest already covers most of what the whole picture covers (the first slice alone,
/// a few seconds of the song, covers far less); the last frame is the single-pass frame.
#[test]
fn progressive_frames_stand_in_for_the_rest_and_end_as_the_single_pass() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let data = SceneData::new(&gpu.device, &renderer, &song(80_000));
    let view = view_of(&data, 320, 180);
    let settings = RenderSettings {
        view: ViewKind::Points,
        ..Default::default()
    };
    let single = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    let target = RenderTarget::new(&gpu.device, view.width, view.height);
    let mut progressive = ProgressivePoints::default();
    progressive.refine.budget = 8_000;
    let complete = progressive_frame(
        &gpu,
        &renderer,
        &mut progressive,
        &target,
        &data,
        &view,
        &settings,
    );
    assert!(!complete, "80,000 points in slices of 8,000");
    let first = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let slice_only = RenderTarget::new(&gpu.device, view.width, view.height);
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    let recording = Recording {
        queue: &gpu.queue,
        encoder: &mut encoder,
        target: &slice_only,
    };
    renderer.render_points_slice(recording, &data, &view, &settings, 0..8_000);
    gpu.queue.submit([encoder.finish()]);
    let slice_only = slice_only.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let (whole, early, alone) = (
        common::coverage(&single),
        common::coverage(&first),
        common::coverage(&slice_only),
    );
    assert!(
        early > 0.6 * whole && early > 2.0 * alone,
        "first frame covers {early}, the whole {whole}, its slice alone {alone}"
    );
    let mut frames = 1;
    while !progressive_frame(
        &gpu,
        &renderer,
        &mut progressive,
        &target,
        &data,
        &view,
        &settings,
    ) {
        frames += 1;
        assert!(frames < 100, "never completes");
    }
    let last = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let (share, _) = common::difference(&single, &last, 0);
    assert_eq!(
        share, 0.0,
        "the complete picture differs in {share} of pixels"
    );
}

/// A completed picture is kept: the view coming back to it (R after an orbit) shows it whole in
/// its first frame, equal to the single-pass frame, with no slice drawn.
#[test]
fn a_view_returned_to_is_complete_at_once() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let data = SceneData::new(&gpu.device, &renderer, &song(60_000));
    let home = view_of(&data, 320, 180);
    let mut away = home;
    away.camera.orbit(40.0, 10.0, 400.0);
    let settings = RenderSettings {
        view: ViewKind::Points,
        ..Default::default()
    };
    let target = RenderTarget::new(&gpu.device, home.width, home.height);
    let mut progressive = ProgressivePoints::default();
    let refine_all = |progressive: &mut ProgressivePoints, view: &FrameView| {
        progressive.refine.budget = 7_000;
        let mut frames = 1;
        while !progressive_frame(
            &gpu,
            &renderer,
            progressive,
            &target,
            &data,
            view,
            &settings,
        ) {
            frames += 1;
        }
        frames
    };
    assert!(refine_all(&mut progressive, &home) > 1);
    // An orbit: moving frames draw another scene, then the new view refines from point 0.
    progressive.set_aside();
    assert_eq!(progressive.kept(), 1, "the home picture is kept");
    assert!(
        refine_all(&mut progressive, &away) > 1,
        "a new view refines"
    );
    // Back home (R): complete in the first frame.
    assert_eq!(refine_all(&mut progressive, &home), 1);
    let back = target.read_rgba(&gpu.device, &gpu.queue).expect("read");
    let single = render_image(&gpu, &renderer, Some(&data), &home, &settings).expect("render");
    let (share, _) = common::difference(&single, &back, 0);
    assert_eq!(share, 0.0, "the kept picture differs in {share} of pixels");
    // And the other way: the orbit's picture was kept when home came back.
    assert_eq!(refine_all(&mut progressive, &away), 1);
}
