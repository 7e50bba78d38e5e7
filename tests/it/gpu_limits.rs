//! The limits loudscape asks of a GPU (render/gpu/context.rs, reviewed against Metal and DX12 in
//! docs/ARCHITECTURE.md), held to on lavapipe by asking for a device no bigger than that: every
//! view, and both surface methods' GPU passes, run on a device with WebGPU's minimum limits
//! (256 MiB buffers, 128 MiB storage bindings, 256 invocations a workgroup, 16 KiB of workgroup
//! memory) except for `STORAGE_BUFFERS_PER_STAGE` storage buffers per stage, and without any
//! optional feature (timestamp queries, mappable primary buffers); with one fewer the
//! device is refused with its reason, and the marching-tetrahedra passes do fail there.

use crate::common;

use glam::{UVec3, Vec3};
use loudscape::data::cloud;
use loudscape::data::synthetic::song_like_field;
use loudscape::render::gpu::context::{
    ContextError, GpuContext, STORAGE_BUFFERS_PER_STAGE, device_descriptor,
};
use loudscape::render::gpu::frame::FrameBinding;
use loudscape::render::grid::VoxelGrid;
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::surface::cpu::SurfaceEngine;
use loudscape::render::surface::pass::SurfacePass;
use loudscape::render::surface::state::ExtractedSurface;
use loudscape::render::surface::{SurfaceMethod, SurfaceSettings};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

/// WebGPU's minimum limits, but for the storage buffers per stage.
fn smallest(storage: u32) -> wgpu::Limits {
    wgpu::Limits {
        max_storage_buffers_per_shader_stage: storage,
        ..wgpu::Limits::default()
    }
}

fn settings(method: SurfaceMethod) -> SurfaceSettings {
    SurfaceSettings {
        method,
        iso_value: 0.35,
        lit: true,
    }
}

fn song_grid(device: &wgpu::Device) -> VoxelGrid {
    let dims = UVec3::new(96, 64, 64);
    let (density, hp) = song_like_field(dims);
    VoxelGrid::from_fields(device, dims, Vec3::splat(-1.0), Vec3::ONE, &density, &hp)
}

#[test]
fn every_view_runs_within_the_limits_asked_of_a_gpu() {
    // No optional feature either: without timestamp queries and mappable primary buffers
    // everything still works (timings fall back to wall time, meshes are copied).
    let gpu = GpuContext::new_headless_narrowed(|limits, features| {
        *limits = smallest(STORAGE_BUFFERS_PER_STAGE);
        *features = wgpu::Features::empty();
    })
    .expect("a device with the smallest limits loudscape accepts");
    assert_eq!(gpu.device.features(), wgpu::Features::empty());
    let limits = gpu.device.limits();
    assert_eq!(
        limits.max_storage_buffers_per_shader_stage,
        STORAGE_BUFFERS_PER_STAGE
    );
    assert_eq!(
        limits.max_buffer_size,
        wgpu::Limits::default().max_buffer_size
    );

    let renderer = Renderer::new(&gpu.device);
    let song = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
    let cloud = cloud::load(&song).expect("the demo song");
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    for view_kind in [ViewKind::Points, ViewKind::Volume, ViewKind::Surface] {
        let settings = RenderSettings {
            view: view_kind,
            ..Default::default()
        };
        data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &settings.voxels)
            .expect("voxelize");
        if view_kind == ViewKind::Surface {
            let grid = data.grid.as_ref().expect("grid");
            renderer
                .surface
                .extract_blocking(&gpu.queue, &data.surface, grid, &settings.surface)
                .expect("extract");
        }
        let view = FrameView::fitted(
            Camera::from_angles(-30.0, 28.0, 4.0),
            data.world_from_data,
            data.world_box(),
            320,
            200,
        );
        let image = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
        assert!(
            common::coverage(&image) > 0.02,
            "{view_kind:?}: nothing drawn"
        );
    }

    // The GPU extraction passes, which the renderer leaves to the CPU on a CPU adapter.
    let frame = FrameBinding::new(&gpu.device);
    let pass = SurfacePass::new(&gpu.device, &frame).with_engine(SurfaceEngine::Gpu);
    let grid = song_grid(&gpu.device);
    for method in [
        SurfaceMethod::MarchingTetrahedra,
        SurfaceMethod::DualContouring,
    ] {
        let surface = ExtractedSurface::new();
        let counts = pass
            .extract_blocking(&gpu.queue, &surface, &grid, &settings(method))
            .expect("extraction");
        let mesh = pass.read_mesh(&gpu.queue, &surface).expect("read back");
        assert!(
            counts.fits() && !mesh.indices.is_empty(),
            "{method:?}: {counts:?}"
        );
    }
}

#[test]
fn one_storage_buffer_fewer_is_refused_and_would_fail() {
    let fewer = STORAGE_BUFFERS_PER_STAGE - 1;
    let refused = GpuContext::new_headless_narrowed(|limits, _| *limits = smallest(fewer));
    match refused {
        Err(error @ ContextError::TooSmall { .. }) => {
            let line = error.to_string();
            assert!(line.contains(&format!("{fewer} storage buffers")), "{line}");
        }
        Err(other) => panic!("refused for another reason: {other}"),
        Ok(_) => panic!("a device with {fewer} storage buffers per stage was accepted"),
    }

    // The number is no overstatement: on such a device (made here without the check) the
    // marching-tetrahedra passes fail validation.
    let gpu = common::gpu();
    let mut descriptor = device_descriptor(&gpu.adapter);
    descriptor.required_limits = smallest(fewer);
    let (device, queue) =
        pollster::block_on(gpu.adapter.request_device(&descriptor)).expect("device");
    let frame = FrameBinding::new(&device);
    let pass = SurfacePass::new(&device, &frame).with_engine(SurfaceEngine::Gpu);
    let grid = song_grid(&device);
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let surface = ExtractedSurface::new();
    let _ = pass.extract_blocking(
        &queue,
        &surface,
        &grid,
        &settings(SurfaceMethod::MarchingTetrahedra),
    );
    let error = pollster::block_on(scope.pop()).expect("a validation error");
    assert!(
        error.to_string().to_lowercase().contains("storage"),
        "{error}"
    );
}
