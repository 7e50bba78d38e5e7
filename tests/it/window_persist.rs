//! Closing the window from outside keeps what it showed: `xdotool windowclose` destroys the
//! window without the close eframe saves on, so the window saves a change within a second by
//! itself (eframe's default was every 30 s: the last half minute was lost). Reopened with no
//! arguments, it shows the same compare (B is remembered with A) in the same view. Needs a
//! display (`make test` runs it under xvfb-run) and xdotool.

use crate::common::{self, assert_display, line_starting, repo, wait_for_window};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The camera's azimuth in eframe's saved state, when there is one.
fn saved_azimuth(state: &Path) -> Option<f32> {
    let text = std::fs::read_to_string(state).ok()?;
    let after = &text[text.find("azimuth:")? + "azimuth:".len()..];
    let number: String = after
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | 'e' | 'E'))
        .collect();
    number.parse().ok()
}

/// Polls `state` (a minute at most) until `wanted` holds for its text.
fn wait_for_saved(state: &Path, wanted: impl Fn(&str) -> bool) -> Option<String> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        if let Ok(text) = std::fs::read_to_string(state)
            && wanted(&text)
        {
            return Some(text);
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    None
}

fn xdotool(args: &[&str]) {
    assert!(common::xdotool(args).is_some(), "xdotool {args:?}");
}

#[test]
fn a_window_closed_from_outside_comes_back_as_it_was_left() {
    let _screen = common::screen();
    assert_display();
    let home = common::output_dir().join("window_persist_home");
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let state = home.join("loudscape/app.ron");
    let b = repo().join("data/fixture_song.ply");
    let b_name = b.display().to_string();
    let mut child = common::home_in(&mut Command::new(env!("CARGO_BIN_EXE_loudscape")), &home)
        .arg(repo().join("data/demo_song.ply"))
        .arg("--compare")
        .arg(&b)
        .args(["--view", "surface"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start loudscape");
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let window = wait_for_window(&mut child).expect("no window");
        // Saved without a close: the compare's B with A.
        let first = wait_for_saved(&state, |text| text.contains(&b_name))
            .expect("the state was never saved while the window was open");
        let before = saved_azimuth(&state).unwrap_or_else(|| panic!("no camera in {first}"));
        // Orbit with the mouse over the 3D view (right of the side panel): the button is held
        // and the pointer moves right a step at a time until the window has saved a turned
        // camera, so its frames see the drag however slowly they come. A press that came before
        // the window laid out its view (the compare's surfaces still building on a loaded
        // machine) starts no drag: then the drag is made again, until the deadline.
        let turned = || saved_azimuth(&state).is_some_and(|a| (a - before).abs() > 1e-3);
        let deadline = Instant::now() + Duration::from_secs(90);
        while !turned() && Instant::now() < deadline {
            xdotool(&["mousemove", "--window", &window, "700", "300"]);
            xdotool(&["mousedown", "1"]);
            let mut x = 700;
            let drag_end = Instant::now() + Duration::from_secs(15);
            while !turned() && Instant::now() < drag_end {
                if x < 1000 {
                    x += 25;
                    xdotool(&["mousemove", "--window", &window, &x.to_string(), "300"]);
                }
                std::thread::sleep(Duration::from_millis(100));
            }
            xdotool(&["mouseup", "1"]);
        }
        xdotool(&["mousemove", "--window", &window, "5", "5"]);
        wait_for_saved(&state, |_| turned()).expect("the orbit was never saved");
        let orbited = saved_azimuth(&state).unwrap();
        xdotool(&["windowclose", &window]);
        (orbited, before)
    }));
    let output = common::exit_within_30_s(child);
    let (orbited, before) = match result {
        Ok(found) => found,
        Err(panic) => std::panic::resume_unwind(panic),
    };
    assert_eq!(output.status.code(), Some(0), "closed from outside: exit 0");
    assert_eq!(
        saved_azimuth(&state),
        Some(orbited),
        "the orbit (from {before}) is what stays saved"
    );

    // Reopened with nothing named: A, B and the Surface view come back.
    let mut child = common::home_in(&mut Command::new(env!("CARGO_BIN_EXE_loudscape")), &home)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape again");
    let lines = common::stderr_lines(&mut child);
    let mut seen = Vec::new();
    let shown = line_starting(
        &lines,
        "compare surface:",
        Duration::from_secs(180),
        &mut seen,
    )
    .is_some();
    let _ = child.kill();
    let _ = child.wait();
    assert!(shown, "the compare did not come back: {seen:#?}");
}
