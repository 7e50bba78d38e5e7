//! Golden images: a headless picture compared with tests/golden/NAME.png within a
//! [`Tolerance`] that says why it is what it is. `UPDATE_GOLDEN=1` writes the goldens that
//! changed and fails each of those tests, naming the golden and how much it changed, so one run
//! never re-blesses pictures silently: look at them (`git diff --stat tests/golden`), then run
//! again without it.

use std::path::Path;

use super::{difference, output_dir, repo};

/// How far a picture may stray from its golden: at most `max_share` of the pixels may differ
/// by more than 32 in some channel; `why` is the reason, printed when it fails.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    pub max_share: f64,
    pub why: &'static str,
}

/// The goldens are rendered on Mesa's lavapipe. Another rasterizer (a GPU's Vulkan driver,
/// Metal) decides coverage at triangle and point-disc edges with other rounding, and a pixel
/// on an edge flips between the shape and the background (a difference far above 32), while
/// the inside of shapes agrees within a few levels. 1% of the pixels is a few thousand edge
/// pixels at the tests' sizes, while a view drawn wrong (a wrong colour map, a missing
/// surface, a shifted camera) changes far more than that.
pub const RASTER_EDGES: Tolerance = Tolerance {
    max_share: 0.01,
    why: "rasterizers differ at shape edges (goldens from lavapipe); a wrong picture changes far \
          more than 1% of the pixels",
};

/// The ray-marched volume: each pixel sums many samples along its ray, and another GPU's
/// float rounding and texture filtering move those sums by a few levels (far under 32) inside
/// the volume; only its silhouette, where the first sample falls in or out, flips past 32.
/// So the same 1% as [`RASTER_EDGES`], for another reason.
pub const RAY_MARCH: Tolerance = Tolerance {
    max_share: 0.01,
    why: "ray sums differ by a few levels between GPUs and only the volume's silhouette flips           (goldens from lavapipe)",
};

/// Compares `actual` with tests/golden/NAME.png. On a failure the actual image and a
/// difference image are written to tests/output/. With `UPDATE_GOLDEN` set, a golden the picture no
/// longer matches within `tolerance` is written and the test fails, naming it
/// ([`golden_changed`]); one it still matches is left as it is (no churn from edge pixels).
pub fn assert_golden(name: &str, actual: &image::RgbaImage, tolerance: Tolerance) {
    let golden_path = repo()
        .join("tests")
        .join("golden")
        .join(format!("{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        if let Err(changed) = golden_changed(&golden_path, actual, tolerance) {
            panic!("{changed}");
        }
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
    if share > tolerance.max_share {
        let diff = image::RgbaImage::from_fn(actual.width(), actual.height(), |x, y| {
            let (a, b) = (actual.get_pixel(x, y), golden.get_pixel(x, y));
            let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
            image::Rgba([d.saturating_mul(4), 0, 0, 255])
        });
        let diff_path = output_dir().join(format!("{name}.diff.png"));
        diff.save(&diff_path).expect("write diff");
        panic!(
            "{name}: {:.3}% of pixels differ (allowed {:.3}%: {}), mean difference {mean:.2}; \
             see {} and {}",
            share * 100.0,
            tolerance.max_share * 100.0,
            tolerance.why,
            actual_path.display(),
            diff_path.display()
        );
    }
}

/// `UPDATE_GOLDEN`'s step for one golden: Ok (and nothing written) when `actual` matches
/// `golden_path` within `tolerance`; otherwise (missing, another size, too many pixels past 32)
/// writes `actual` there and says which golden changed and how much (the caller fails the
/// test with it).
pub fn golden_changed(
    golden_path: &Path,
    actual: &image::RgbaImage,
    tolerance: Tolerance,
) -> Result<(), String> {
    let how = match image::open(golden_path).map(|g| g.to_rgba8()) {
        Ok(golden) if golden.dimensions() != actual.dimensions() => format!(
            "its size changed from {:?} to {:?}",
            golden.dimensions(),
            actual.dimensions()
        ),
        Ok(golden) => {
            let (share, mean) = difference(&golden, actual, 32);
            if share <= tolerance.max_share {
                return Ok(());
            }
            format!(
                "{:.3}% of its pixels changed by more than 32 (allowed {:.3}%), mean \
                 difference {mean:.2}",
                share * 100.0,
                tolerance.max_share * 100.0
            )
        }
        Err(_) => "it is new".to_string(),
    };
    actual.save(golden_path).expect("write golden");
    Err(format!(
        "golden {} rewritten ({how}): look at it, then run again without UPDATE_GOLDEN",
        golden_path.display()
    ))
}

#[test]
fn updating_a_golden_fails_naming_it_only_when_it_changed() {
    let dir = super::fresh_dir("golden_update");
    let golden_path = dir.join("picture.png");
    let old = image::RgbaImage::from_pixel(8, 4, image::Rgba([10, 20, 30, 255]));
    let mut new = old.clone();
    new.put_pixel(3, 1, image::Rgba([200, 20, 30, 255]));

    let exact = Tolerance {
        max_share: 0.0,
        why: "the test's own pictures",
    };
    let first = golden_changed(&golden_path, &old, exact).expect_err("a new golden is a change");
    assert!(
        first.contains("picture.png") && first.contains("it is new"),
        "{first}"
    );
    let written = std::fs::metadata(&golden_path)
        .expect("written")
        .modified()
        .ok();

    assert_eq!(golden_changed(&golden_path, &old, exact), Ok(()));
    assert_eq!(
        std::fs::metadata(&golden_path).unwrap().modified().ok(),
        written,
        "an unchanged golden is not written again"
    );

    let mut rounded = old.clone();
    rounded.put_pixel(5, 2, image::Rgba([14, 20, 30, 255]));
    assert_eq!(
        golden_changed(&golden_path, &rounded, exact),
        Ok(()),
        "rounding is no change"
    );
    assert_eq!(image::open(&golden_path).unwrap().to_rgba8(), old);

    let some = Tolerance {
        max_share: 0.05,
        why: "one pixel in 32 may flip",
    };
    assert_eq!(
        golden_changed(&golden_path, &new, some),
        Ok(()),
        "within its tolerance"
    );
    assert_eq!(image::open(&golden_path).unwrap().to_rgba8(), old);
    let changed = golden_changed(&golden_path, &new, exact).expect_err("one pixel changed");
    assert!(
        changed.contains("picture.png")
            && changed.contains("3.125% of its pixels changed by more than 32"),
        "{changed}"
    );
    assert_eq!(image::open(&golden_path).unwrap().to_rgba8(), new);
}
