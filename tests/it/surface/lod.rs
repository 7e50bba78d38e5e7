//! The coarse level of detail: the downsampled field against a CPU reference, the coarse
//! surface against the full one, and the window path that keeps both.

use super::*;

/// The GPU downsample (shaders/grid/downsample.wgsl) against its CPU mirror: even and odd dims,
/// one and two levels, blocks with and without density; the box stays.
#[test]
fn downsample_matches_the_cpu_reference() {
    use loudscape::render::grid::downsample::{DownsamplePass, reference_downsample};
    let gpu = common::gpu();
    let pass = DownsamplePass::new(&gpu.device);
    for (dims, levels) in [
        (UVec3::new(37, 20, 15), 1),
        (UVec3::new(32, 32, 32), 2),
        (UVec3::new(1, 5, 2), 1),
    ] {
        let (density, hp) = lumpy_fields(dims);
        let (box_min, box_max) = (Vec3::new(-1.0, -0.5, -2.0), Vec3::new(1.0, 0.75, 2.0));
        let grid = VoxelGrid::from_fields(&gpu.device, dims, box_min, box_max, &density, &hp);
        let coarse = pass.downsample(&gpu.device, &gpu.queue, &grid, levels);
        let (mut want_dims, mut want_density, mut want_hp) = (dims, density, hp);
        for _ in 0..levels {
            (want_dims, want_density, want_hp) =
                reference_downsample(want_dims, &want_density, &want_hp);
        }
        assert_eq!(coarse.dims, want_dims);
        assert_eq!((coarse.box_min, coarse.box_max), (box_min, box_max));
        let got_density = coarse
            .read_field(&gpu.device, &gpu.queue, &coarse.density)
            .expect("density");
        let got_hp = coarse
            .read_field(&gpu.device, &gpu.queue, &coarse.hp_mean)
            .expect("hp");
        assert_eq!(got_density.len(), want_density.len());
        let mut empty_blocks = 0;
        for (v, (g, w)) in got_density.iter().zip(&want_density).enumerate() {
            assert!(
                (g - w).abs() <= 1e-6,
                "{dims}: density of voxel {v}: {g} vs {w}"
            );
            empty_blocks += usize::from(*w == 0.0);
        }
        for (v, (g, w)) in got_hp.iter().zip(&want_hp).enumerate() {
            assert!((g - w).abs() <= 1e-5, "{dims}: hp of voxel {v}: {g} vs {w}");
        }
        if levels == 1 && dims.x > 1 {
            assert!(
                empty_blocks > 0,
                "{dims}: the fallback for empty blocks was not exercised"
            );
        }
    }
    // The mirror itself on a block by hand: mean density, density-weighted hp, plain hp mean
    // where empty, and an odd edge counts only the voxels that exist.
    let (dims, density, hp) =
        reference_downsample(UVec3::new(3, 1, 1), &[0.2, 0.6, 0.0], &[1.0, 0.0, 0.3]);
    assert_eq!(dims, UVec3::new(2, 1, 1));
    assert!((density[0] - 0.4).abs() < 1e-6 && density[1] == 0.0);
    assert!((hp[0] - 0.25).abs() < 1e-6, "{}", hp[0]);
    assert!((hp[1] - 0.3).abs() < 1e-6, "{}", hp[1]);
}

/// The coarse surface of the level of detail (the grid downsampled as the window does, same
/// method and isovalue) encloses nearly the same sphere: its area is within 4 % of the full
/// surface's, with far fewer triangles.
#[test]
fn coarse_sphere_is_close_to_the_full_one() {
    use loudscape::render::grid::downsample::DownsamplePass;
    use loudscape::render::surface::lod::COARSE_LEVELS;
    let gpu = common::gpu();
    let pass = surface_pass(&gpu);
    let grid = grid_from(&gpu, 128, sphere);
    let coarse =
        DownsamplePass::new(&gpu.device).downsample(&gpu.device, &gpu.queue, &grid, COARSE_LEVELS);
    assert_eq!(coarse.dims, UVec3::splat(128 >> COARSE_LEVELS));
    for method in SurfaceMethod::ALL {
        let full = extract(&gpu, &pass, &grid, method, 0.5);
        let rough = extract(&gpu, &pass, &coarse, method, 0.5);
        let (a, b) = (full.area(), rough.area());
        let error = (b - a).abs() / a;
        println!(
            "{}: full {} triangles, area {a:.5}; coarse {} triangles, area {b:.5} ({:.2}%)",
            method.name(),
            full.triangle_count(),
            rough.triangle_count(),
            error * 100.0
        );
        assert!(
            error < 0.04,
            "{}: coarse area off by {:.2}%",
            method.name(),
            error * 100.0
        );
        assert!(rough.triangle_count() * 8 < full.triangle_count());
        // Every coarse vertex lies near the sphere.
        for p in &rough.positions {
            assert!((p.length() - SPHERE_RADIUS).abs() < 0.05, "{p}");
        }
    }
}

/// The window's path extracts the coarse surface too (before the full one): once settled, both
/// are there, the coarse one equal to a blocking extraction of the downsampled grid, and the full
/// one unchanged.
#[test]
fn the_window_path_keeps_a_coarse_surface_beside_the_full_one() {
    use loudscape::render::grid::downsample::DownsamplePass;
    use loudscape::render::surface::lod::{COARSE_LEVELS, Level};
    let gpu = common::gpu();
    let grid = grid_from(&gpu, 64, torus);
    let coarse_grid =
        DownsamplePass::new(&gpu.device).downsample(&gpu.device, &gpu.queue, &grid, COARSE_LEVELS);
    for (method, engine) in [MT, DC].into_iter().flat_map(|m| ENGINES.map(|e| (m, e))) {
        let pass = engine_pass(&gpu, engine);
        let settings = SurfaceSettings {
            method,
            iso_value: 0.45,
            lit: true,
        };
        let full = extract(&gpu, &engine_pass(&gpu, engine), &grid, method, 0.45);
        let coarse = extract(&gpu, &engine_pass(&gpu, engine), &coarse_grid, method, 0.45);
        let surface = ExtractedSurface::new();
        let mut frames = 0;
        loop {
            pass.prepare(&gpu.queue, &surface, Some(&grid), &settings);
            // The frame's submission (its style write; the worker extracts).
            gpu.queue.submit([]);
            frames += 1;
            if !surface.needs_another_frame() {
                break;
            }
            assert!(frames < 12_000, "{}: never settled", method.name());
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert_eq!(surface.coarse_installed(), 1, "{}", method.name());
        let got_coarse = pass
            .read_level(&gpu.queue, &surface, Level::Coarse)
            .expect("coarse");
        let got_full = pass.read_mesh(&gpu.queue, &surface).expect("full");
        assert!(coarse.triangle_count() > 50);
        assert_eq!(
            triangle_set(&got_coarse),
            triangle_set(&coarse),
            "{}",
            method.name()
        );
        assert_eq!(
            triangle_set(&got_full),
            triangle_set(&full),
            "{}",
            method.name()
        );
    }
}

/// Until the grid's first surface comes from the background extraction, the Surface view draws
/// the points' sparse subset: the first frames after a switch to Surface used to show an empty
/// box (about a second on a 3.5 M-point song on lavapipe).
#[test]
fn the_surface_view_shows_the_points_until_its_first_surface_comes() {
    use loudscape::render::headless::render_image;
    use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = common::demo_song();
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    let settings = RenderSettings {
        view: ViewKind::Surface,
        show_box: false,
        ..Default::default()
    };
    data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &settings.voxels)
        .expect("grid");
    let view = common::view_of(&data, 320, 180);
    let first = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
    assert!(
        !data.surface.extracted_any(),
        "the surface is installed by a later frame"
    );
    let covered = common::coverage(&first);
    assert!(
        covered > 0.01,
        "the first Surface frame is empty ({:.2} % covered)",
        covered * 100.0
    );
}
