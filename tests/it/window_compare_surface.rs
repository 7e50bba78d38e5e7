//! The first Surface of an A/B compare is the surface the grids hold: `loudscape A --compare B
//! --view surface` builds the compare's grids on a thread (the window keeps drawing meanwhile)
//! and comes back for both halves' surfaces by itself, so what it shows with no input at all is
//! what a fresh extraction of those grids gives (the window drew empty boxes, a broken blob or
//! the coarse stand-in until a method toggle extracted again). The window tells stderr each
//! compare surface it shows; the reference is the same compare built and extracted here.

use crate::common::{self, assert_display, line_starting, repo, wait_for_window};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use loudscape::data::cloud::PointCloud;
use loudscape::render::compare::CompareScene;
use loudscape::render::grid::voxelize::VoxelSettings;
use loudscape::render::scene::Renderer;
use loudscape::render::surface::{SurfaceMethod, SurfaceSettings};

/// A's and B's triangles as a fresh extraction of the compare's grids gives them.
fn reference(a: &Path, b: &Path, method: SurfaceMethod) -> (u32, u32) {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let load = |path: &Path| -> PointCloud { loudscape::data::cloud::load(path).expect("a cloud") };
    let mut scene = CompareScene::new(&gpu.device, &renderer, &load(a), &load(b)).unwrap();
    scene
        .ensure_grids(
            &gpu.device,
            &gpu.queue,
            &renderer,
            &VoxelSettings::default(),
        )
        .unwrap();
    let settings = SurfaceSettings {
        method,
        ..Default::default()
    };
    let mut triangles = [0; 2];
    for (side, data) in [&scene.data_a, &scene.data_b].into_iter().enumerate() {
        let counts = renderer
            .surface
            .extract_blocking(
                &gpu.queue,
                &data.surface,
                data.grid.as_ref().unwrap(),
                &settings,
            )
            .unwrap();
        triangles[side] = counts.triangles();
    }
    (triangles[0], triangles[1])
}

/// "compare surface: A 123 triangles, B 45 triangles (...)" -> (123, 45).
fn triangles_told(line: &str) -> (u32, u32) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let number = |after: &str| -> u32 {
        let at = words.iter().position(|w| *w == after).expect(line);
        words[at + 1].parse().expect(line)
    };
    (number("A"), number("B"))
}

/// Runs the compare in the Surface view with `press`, and returns the triangles of its first
/// surfaces and the frames drawn while the grids were built; the screen once they are shown is
/// left in tests/output/NAME.png to look at.
fn first_compare_surface(a: &Path, b: &Path, press: &[&str], name: &str) -> ((u32, u32), u32) {
    let home = common::output_dir().join(format!("{name}_home"));
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::home_in(&mut command, &home)
        .arg(a)
        .arg("--compare")
        .arg(b)
        .args(["--view", "surface"]);
    for key in press {
        command.arg("--press").arg(key);
    }
    let mut child = command
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    let lines = common::stderr_lines(&mut child);
    let mut seen = Vec::new();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if wait_for_window(&mut child).is_none() {
            let said: Vec<String> = lines.try_iter().collect();
            panic!("no window: {said:#?}");
        }
        let built = line_starting(
            &lines,
            "compare: grids built",
            Duration::from_secs(180),
            &mut seen,
        )
        .unwrap_or_else(|| panic!("the grids were never built: {seen:#?}"));
        // "... while the window drew N frames"
        let frames: u32 = built
            .split_whitespace()
            .rev()
            .nth(1)
            .and_then(|n| n.parse().ok())
            .expect(&built);
        // No input from here on: the window comes back for the surfaces by itself.
        let told = line_starting(
            &lines,
            "compare surface:",
            Duration::from_secs(180),
            &mut seen,
        )
        .unwrap_or_else(|| panic!("no compare surface was shown: {seen:#?}"));
        common::screenshot_root(&common::output_dir().join(format!("{name}.png")));
        (triangles_told(&told), frames)
    }));
    let _ = child.kill();
    let _ = child.wait();
    match result {
        Ok(found) => found,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

#[test]
fn the_first_compare_surface_is_the_one_a_toggle_extracts() {
    let _screen = common::screen();
    assert_display();
    let a = repo().join("data/demo_song.ply");
    let b = repo().join("data/fixture_song.ply");
    for (method, press, name) in [
        (
            SurfaceMethod::MarchingTetrahedra,
            vec![],
            "window_compare_surface_mt",
        ),
        (
            SurfaceMethod::DualContouring,
            vec!["surface=dc"],
            "window_compare_surface_dc",
        ),
    ] {
        let expected = reference(&a, &b, method);
        assert!(expected.0 > 0, "the demo song has a surface ({method:?})");
        let (shown, frames) = first_compare_surface(&a, &b, &press, name);
        assert_eq!(
            shown, expected,
            "{method:?}: the first compare surface (A, B triangles) is not a fresh extraction's"
        );
        assert!(
            frames >= 1,
            "{method:?}: the window drew {frames} frames while the grids were built: it froze"
        );
    }
}
