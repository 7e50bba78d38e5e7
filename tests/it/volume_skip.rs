//! The volume's shortcuts leave the picture as it was: the demo's volume drawn with transparent
//! bricks skipped and the gradient from its texture, against the full march (every step sampled,
//! gradients from six samples), at PSNR >= 40 dB; and the bricks' maxima read back equal the
//! CPU's.

use crate::common;

use loudscape::render::gpu::readback::read_buffer;
use loudscape::render::grid::VoxelGrid;
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::volume::TransferPreset;
use loudscape::render::volume_grids::{BRICK, VolumeGridsPass, brick_counts};

/// Half the benchmark's 1280x720, the same camera (fitted default).
const SIZE: (u32, u32) = (640, 360);
/// Below this the difference would show: 40 dB is an RMS error of 2.5 levels in 255, and
/// differences from rounding (the gradient's 16-bit floats, the skipped steps' sums) are far
/// under one level.
const MIN_PSNR_DB: f64 = 40.0;

/// Peak signal-to-noise ratio of `b` against `a` over the RGB channels, in dB.
fn psnr(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let (mut sum, mut n) = (0.0_f64, 0_u64);
    for (p, q) in a.pixels().zip(b.pixels()) {
        for c in 0..3 {
            let d = f64::from(p[c]) - f64::from(q[c]);
            sum += d * d;
            n += 1;
        }
    }
    let mse = sum / n as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0_f64 * 255.0 / mse).log10()
    }
}

#[test]
fn skipping_and_the_gradient_texture_keep_the_demo_volume() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let cloud = common::demo_song();
    let mut data = SceneData::new(&gpu.device, &renderer, &cloud);
    let base = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &cloud, &base.voxels)
        .expect("voxelize the demo");
    let view = common::view_of(&data, SIZE.0, SIZE.1);
    // Every preset shaded and unshaded, a dense Ember and hp tint: each is a pipeline of its own
    // (render/volume.rs's VolumeVariant), compiled from the shader with its constants.
    let cases = [
        ("classic_shaded", TransferPreset::Classic, true, 1.0, false),
        (
            "classic_unshaded",
            TransferPreset::Classic,
            false,
            1.0,
            false,
        ),
        ("ember_shaded", TransferPreset::Ember, true, 1.0, false),
        ("ember_unshaded", TransferPreset::Ember, false, 1.0, false),
        ("glacial_shaded", TransferPreset::Glacial, true, 1.0, false),
        (
            "glacial_unshaded",
            TransferPreset::Glacial,
            false,
            1.0,
            false,
        ),
        (
            "ember_dense_shaded",
            TransferPreset::Ember,
            true,
            3.0,
            false,
        ),
        (
            "classic_tint_shaded",
            TransferPreset::Classic,
            true,
            1.0,
            true,
        ),
    ];
    for (name, preset, shading, density_scale, hp_tint) in cases {
        let mut settings = base.clone();
        settings.volume.preset = preset;
        settings.volume.shading = shading;
        settings.volume.density_scale = density_scale;
        settings.volume.hp_tint = hp_tint;
        let fast = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
        settings.volume.full_march = true;
        let full = render_image(&gpu, &renderer, Some(&data), &view, &settings).expect("render");
        assert!(
            common::coverage(&full) > 0.05,
            "{name}: the full march is nearly blank, the comparison would say nothing"
        );
        let db = psnr(&full, &fast);
        println!("{name}: PSNR {db:.1} dB");
        if db < MIN_PSNR_DB {
            let dir = common::output_dir();
            for (suffix, image) in [("fast", &fast), ("full", &full)] {
                let path = dir.join(format!("volume_skip_{name}_{suffix}.png"));
                image.save(&path).expect("save the failing images");
            }
        }
        assert!(
            db >= MIN_PSNR_DB,
            "{name}: the fast march differs from the full one, PSNR {db:.1} dB < {MIN_PSNR_DB} \
             (both in tests/output/volume_skip_{name}_*.png)"
        );
    }
}

#[test]
fn brick_maxima_cover_every_voxel_a_sample_in_the_brick_reads() {
    let gpu = common::gpu();
    // Dims that are not multiples of the brick, a sparse field with a few peaks.
    let dims = glam::UVec3::new(21, 17, 9);
    let n = (dims.x * dims.y * dims.z) as usize;
    let mut density = vec![0.0_f32; n];
    let mut state = 12345_u32;
    for value in density.iter_mut() {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        if state >> 28 == 0 {
            *value = (state >> 8) as f32 / 16_777_216.0;
        }
    }
    let grid = VoxelGrid::from_fields(
        &gpu.device,
        dims,
        glam::Vec3::ZERO,
        glam::Vec3::ONE,
        &density,
        &vec![0.5; n],
    );
    let grids = VolumeGridsPass::new(&gpu.device).build(&gpu.device, &grid);
    grids.submit_once(&gpu.queue);
    let bricks = brick_counts(dims);
    assert_eq!(bricks, glam::UVec3::new(3, 3, 2));
    let count = (bricks.x * bricks.y * bricks.z) as usize;
    let bytes = read_buffer(
        &gpu.device,
        &gpu.queue,
        "test::brick_max",
        &grids.brick_max,
        count as u64 * 4,
    )
    .expect("read back the bricks");
    let got: &[f32] = bytemuck::cast_slice(&bytes);
    let at = |i: u32, j: u32, k: u32| density[(i + dims.x * (j + dims.y * k)) as usize];
    for k in 0..bricks.z {
        for j in 0..bricks.y {
            for i in 0..bricks.x {
                let b = glam::UVec3::new(i, j, k);
                let lo = (b * BRICK).saturating_sub(glam::UVec3::ONE);
                let hi = ((b + 1) * BRICK).min(dims - 1);
                let mut most = f32::MIN;
                for z in lo.z..=hi.z {
                    for y in lo.y..=hi.y {
                        for x in lo.x..=hi.x {
                            most = most.max(at(x, y, z));
                        }
                    }
                }
                let index = (i + bricks.x * (j + bricks.y * k)) as usize;
                assert_eq!(got[index], most, "brick {b}");
            }
        }
    }
}
