//! The song-like field drawn as a surface by both methods, against golden images.

use super::*;

/// The song-like field rendered as a surface, as the render command does.
fn render_song_surface(method: SurfaceMethod) -> image::RgbaImage {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = PointCloud::synthetic(Vec::new(), DataMode::Song);
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    let dims = UVec3::new(96, 64, 64);
    let (density, hp) = song_like_field(dims);
    data.grid = Some(unit_box_grid(&gpu, dims, &density, &hp));
    let settings = RenderSettings {
        view: ViewKind::Surface,
        surface: SurfaceSettings {
            method,
            iso_value: 0.35,
            lit: true,
        },
        ..Default::default()
    };
    let grid = data.grid.as_ref().expect("grid");
    renderer
        .surface
        .extract_blocking(&gpu.queue, &data.surface, grid, &settings.surface)
        .expect("extract");
    let view = FrameView::at_rest(
        Camera::from_angles(-35.0, 30.0, 5.2),
        data.world_from_data,
        480,
        320,
    );
    loudscape::render::headless::render_image(&gpu, &renderer, Some(&data), &view, &settings)
        .expect("render")
}

#[test]
fn golden_surface_marching_tets() {
    let image = render_song_surface(MT);
    assert!(common::coverage(&image) > 0.08, "the surface is missing");
    common::assert_golden("surface_mt", &image, common::RASTER_EDGES);
}

#[test]
fn golden_surface_dual_contour() {
    let image = render_song_surface(DC);
    assert!(common::coverage(&image) > 0.08, "the surface is missing");
    common::assert_golden("surface_dc", &image, common::RASTER_EDGES);
}
