//! A compare reopened comes back with the camera it was left with: the window is zoomed in on
//! A and B, closed, and reopened with nothing named; once A and B are shown again, its 3D view
//! is the picture it was left with and the saved camera is the one left. It came back a little
//! closer than at close, the box's bottom edge cut: the compare's scene was fitted again as it
//! came, and the camera, framed for the view as it was left, was kept in frame as the new
//! window's taller first view shrank to that size (the strip arriving).
//! Needs a display (`make test` runs it under xvfb-run) and xdotool.

use crate::common::{self, assert_display, line_starting, repo, wait_for_window, xdotool};

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

/// The camera in eframe's saved state ("target:(...),azimuth:...,distance:..."), when there is
/// one.
fn saved_camera(state: &Path) -> Option<String> {
    let text = std::fs::read_to_string(state).ok()?;
    let after = &text[text.find("camera:Some((")? + "camera:Some((".len()..];
    Some(after[..after.find("))")?].to_string())
}

/// Whether two saved cameras are the same: the same target and angles, the same distance
/// within float rounding (the framing is kept through the view's sizes by steps back and
/// forth).
fn same_camera(a: &str, b: &str) -> bool {
    let split = |c: &str| -> Option<(String, f64)> {
        let (rest, distance) = c.split_once("distance:")?;
        Some((rest.to_string(), distance.parse().ok()?))
    };
    match (split(a), split(b)) {
        (Some((a, da)), Some((b, db))) => a == b && (da - db).abs() < 1e-4 * db,
        _ => false,
    }
}

/// The window on the test's `home`, stderr piped, with `args`.
fn window(home: &Path, args: &[&std::ffi::OsStr]) -> Child {
    common::home_in(&mut Command::new(env!("CARGO_BIN_EXE_loudscape")), home)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape")
}

/// Waits for "compare: A and B shown", then for the view to hold still with points drawn; the
/// screen is left at `shot`.
fn compare_settled(lines: &Receiver<String>, shot: &Path) -> image::RgbaImage {
    let mut seen = Vec::new();
    line_starting(
        lines,
        "compare: A and B shown",
        Duration::from_secs(120),
        &mut seen,
    )
    .unwrap_or_else(|| panic!("the compare was not shown: {seen:#?}"));
    let region = common::view_region((1280, 800));
    let drawn = |image: &image::RgbaImage| common::coloured_share(image, region) > 0.01;
    let image = common::shot_settled(shot, region, Duration::from_secs(90), drawn);
    assert!(drawn(&image), "nothing drawn (see {})", shot.display());
    image
}

#[test]
fn a_reopened_compare_keeps_the_camera_it_was_left_with() {
    let _screen = common::screen();
    assert_display();
    let dir = common::fresh_dir("window_compare_reopen");
    let home = dir.join("home");
    std::fs::create_dir_all(&home).unwrap();
    let state = home.join("loudscape/app.ron");
    let (a, b) = (
        repo().join("data/demo_song.ply"),
        repo().join("data/fixture_song.ply"),
    );
    let child = window(&home, &[a.as_os_str(), "--compare".as_ref(), b.as_os_str()]);
    let mut left = None;
    common::while_running(child, |child, lines| {
        let id = wait_for_window(child).expect("no window");
        compare_settled(lines, &dir.join("opened.png"));
        let fitted = saved_camera(&state);
        // Zoomed in with the wheel over A's half until a closer camera is saved.
        let deadline = Instant::now() + Duration::from_secs(60);
        let zoomed = || saved_camera(&state).is_some_and(|c| Some(&c) != fitted.as_ref());
        while !zoomed() && Instant::now() < deadline {
            xdotool(&["mousemove", "--window", &id, "560", "330"]);
            xdotool(&["click", "--repeat", "2", "4"]);
            std::thread::sleep(Duration::from_millis(300));
        }
        assert!(zoomed(), "the zoom was never saved ({fitted:?})");
        xdotool(&["mousemove", "--window", &id, "5", "5"]);
        let before = compare_settled_after_zoom(&dir.join("left.png"));
        left = Some((saved_camera(&state).unwrap(), before));
        assert!(xdotool(&["windowclose", &id]).is_some(), "windowclose");
        // Gone once it has saved and closed (killed after 30 s by while_running otherwise).
        let deadline = Instant::now() + Duration::from_secs(30);
        while child.try_wait().ok().flatten().is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(100));
        }
    });
    let (camera, before) = left.expect("the camera left");
    assert_eq!(
        saved_camera(&state).as_ref(),
        Some(&camera),
        "saved at close"
    );
    assert!(
        std::fs::read_to_string(&state).is_ok_and(|t| t.contains("view_heights:Some")),
        "the view's height is saved with the camera"
    );

    // Reopened with nothing named: A, B and the camera come back.
    let child = window(&home, &[]);
    common::while_running(child, |child, lines| {
        wait_for_window(child).expect("no window on reopening");
        let after = compare_settled(lines, &dir.join("reopened.png"));
        // The same picture: a camera fitted again, or framed for the new window's first
        // (taller) view, moves every point and the box's edges.
        let [x0, y0, x1, y1] = common::view_region((1280, 800));
        let crop = |image: &image::RgbaImage| {
            image::imageops::crop_imm(image, x0, y0, x1 - x0, y1 - y0).to_image()
        };
        let (changed, _) = common::difference(&crop(&before), &crop(&after), 40);
        assert!(
            changed < 0.002,
            "{:.2} % of the view changed on reopening (see {} and {})",
            changed * 100.0,
            dir.join("left.png").display(),
            dir.join("reopened.png").display()
        );
        let kept = saved_camera(&state).expect("a camera saved");
        assert!(
            same_camera(&kept, &camera),
            "the camera left, {camera}, came back as {kept}"
        );
    });
}

/// The screen once the zoomed view holds still, at `shot`.
fn compare_settled_after_zoom(shot: &Path) -> image::RgbaImage {
    let region = common::view_region((1280, 800));
    common::shot_settled(shot, region, Duration::from_secs(60), |image| {
        common::coloured_share(image, region) > 0.01
    })
}
