//! The A/B compare's halves are drawn progressively at rest (`ui/compare_refine.rs`): with the
//! demo song (147,750 points) beside a synthetic song of a million points, more than one
//! compare frame's budget, the halves fill in over several frames, the window saying so once
//! both are complete; an orbit starts them over while the budget the frames adapted to is still
//! short of both clouds (on a machine fast enough for more, the budget outgrows them and the
//! frames after the orbit draw them whole, as `compare_refine`'s own tests hold), and at the end
//! both halves show a song.
//! Needs a display (`make test` runs it under xvfb-run).

use crate::common::{self, line_starting, xdotool};

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The frames, the most points a frame and the budget left of a "compare: points refined in N
/// frames, at most P points a frame, budget now B" line.
fn refined(line: &str) -> (u32, u64, u64) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let number = |after: &str| {
        let at = words.iter().position(|w| *w == after).expect(line);
        words[at + 1]
            .trim_end_matches(',')
            .parse::<u64>()
            .expect(line)
    };
    (number("in") as u32, number("most"), number("now"))
}

#[test]
fn compare_halves_fill_in_over_frames_and_again_after_an_orbit() {
    let _screen = common::screen();
    common::assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to drag in the window (apt-get install xdotool)"
    );
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let home = common::fresh_dir("window_compare_refine_home");
    let song = repo.join("data/demo_song.ply");
    let big = home.join("synthetic_1m.ply");
    common::write_synthetic_song(&big, 1_000_000, 11);
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    let child = common::home_in(&mut command, &home)
        .arg(&song)
        .arg("--compare")
        .arg(&big)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        let window = common::wait_for_window(child).expect("no window");
        let mut seen = Vec::new();
        let prefix = "compare: points refined in ";
        let line = line_starting(lines, prefix, Duration::from_secs(120), &mut seen)
            .unwrap_or_else(|| panic!("the halves never completed:\n{}", seen.join("\n")));
        let (frames, most, budget) = refined(&line);
        // 1,147,750 points against a first frame's budget of 400,000 (COMPARE_MIN_BUDGET): more
        // than one frame, none of them drawing both clouds whole.
        let total = 147_750 + 1_000_000;
        assert!(frames >= 2, "{line}");
        assert!(most < total, "{line}");

        // An orbit: a drag across the view, then the pointer away from it, so no read-out
        // covers the points.
        let orbit = || {
            xdotool(&["mousemove", "--window", &window, "700", "400"]);
            xdotool(&["mousedown", "1"]);
            for step in 1..=10 {
                std::thread::sleep(Duration::from_millis(40));
                let x = (700 + step * 25).to_string();
                xdotool(&["mousemove", "--window", &window, &x, "400"]);
            }
            xdotool(&["mouseup", "1"]);
            xdotool(&["mousemove", "--window", &window, "5", "5"]);
        };
        if budget < total {
            // Made again until the halves refine anew (a press before the window laid out its
            // view starts no drag).
            let deadline = Instant::now() + Duration::from_secs(90);
            let mut again = None;
            while again.is_none() && Instant::now() < deadline {
                orbit();
                again = line_starting(lines, prefix, Duration::from_secs(20), &mut seen);
            }
            let again = again.unwrap_or_else(|| {
                panic!(
                    "no refinement after the orbit with a budget of {budget} points a frame \
                     for {total}:\n{}",
                    seen.join("\n")
                )
            });
            assert!(refined(&again).0 >= 1, "{again}");
        } else {
            // The budget has outgrown both clouds: the frames after the orbit draw them whole,
            // and there is no line to wait for.
            orbit();
        }

        // Complete: both halves of the 3D view (right of the side panel) show the song.
        let shot = common::output_dir().join("window_compare_refine.png");
        common::screenshot_root(&shot);
        let image = image::open(&shot).unwrap().to_rgba8();
        let (w, h) = image.dimensions();
        let panel = 280;
        let mid = panel + (w - panel) / 2;
        for region in [[panel, 0, mid, h], [mid, 0, w, h]] {
            let share = common::coloured_share(&image, region);
            assert!(share > 0.02, "half {region:?} looks blank ({share:.3})");
        }
    });
}
