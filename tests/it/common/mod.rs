//! Helpers shared by the GPU integration tests: a device on whatever adapter exists (lavapipe on
//! machines without a GPU) and golden-image comparison with a tolerance.
#![allow(dead_code)]

use std::path::PathBuf;

use loudscape::render::gpu::context::GpuContext;

/// A headless device; the tests need one (install mesa-vulkan-drivers for lavapipe).
pub fn gpu() -> GpuContext {
    match GpuContext::new_headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!("GPU tests need an adapter (lavapipe will do): {e}"),
    }
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Where failing tests leave their actual and difference images.
pub fn output_dir() -> PathBuf {
    let dir = repo().join("tests").join("output");
    std::fs::create_dir_all(&dir).expect("create tests/output");
    dir
}

/// How two images differ: the share of pixels whose largest channel difference exceeds
/// `threshold`, and the mean absolute channel difference.
pub fn difference(a: &image::RgbaImage, b: &image::RgbaImage, threshold: u8) -> (f64, f64) {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let mut over = 0usize;
    let mut sum = 0u64;
    for (pa, pb) in a.pixels().zip(b.pixels()) {
        let mut worst = 0u8;
        for c in 0..3 {
            let d = pa[c].abs_diff(pb[c]);
            worst = worst.max(d);
            sum += u64::from(d);
        }
        if worst > threshold {
            over += 1;
        }
    }
    let n = (a.width() * a.height()) as f64;
    (over as f64 / n, sum as f64 / (n * 3.0))
}

/// Compares `actual` with tests/golden/NAME.png. Differences allowed: at most `max_share` of the
/// pixels may differ by more than 32 in some channel (rasterizers differ at edges).
/// Run with `UPDATE_GOLDEN=1` to write the golden after looking at the actual image.
/// On failure the actual image and a difference image are written to tests/output/.
pub fn assert_golden(name: &str, actual: &image::RgbaImage, max_share: f64) {
    let golden_path = repo()
        .join("tests")
        .join("golden")
        .join(format!("{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        actual.save(&golden_path).expect("write golden");
        return;
    }
    let actual_path = output_dir().join(format!("{name}.actual.png"));
    actual.save(&actual_path).expect("write actual");
    let golden = match image::open(&golden_path) {
        Ok(img) => img.to_rgba8(),
        Err(e) => panic!(
            "no golden image {} ({e}); look at {} and run with UPDATE_GOLDEN=1 to accept it",
            golden_path.display(),
            actual_path.display()
        ),
    };
    assert_eq!(
        golden.dimensions(),
        actual.dimensions(),
        "{name}: size differs"
    );
    let (share, mean) = difference(&golden, actual, 32);
    if share > max_share {
        let diff = image::RgbaImage::from_fn(actual.width(), actual.height(), |x, y| {
            let (a, b) = (actual.get_pixel(x, y), golden.get_pixel(x, y));
            let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
            image::Rgba([d.saturating_mul(4), 0, 0, 255])
        });
        let diff_path = output_dir().join(format!("{name}.diff.png"));
        diff.save(&diff_path).expect("write diff");
        panic!(
            "{name}: {:.3}% of pixels differ (allowed {:.3}%), mean difference {mean:.2}; see {} and {}",
            share * 100.0,
            max_share * 100.0,
            actual_path.display(),
            diff_path.display()
        );
    }
}

/// The share of pixels that are not the background, to check an image is not blank.
pub fn coverage(image: &image::RgbaImage) -> f64 {
    let bg = image.get_pixel(0, 0);
    let covered = image
        .pixels()
        .filter(|p| (0..3).any(|c| p[c].abs_diff(bg[c]) > 16))
        .count();
    covered as f64 / (image.width() * image.height()) as f64
}
