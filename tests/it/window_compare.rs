//! The window's A/B compare under a display (Xvfb): `loudscape A --compare B --seek 12.5`
//! opens side by side, and key B switches the heard song without moving the playback
//! position (read from the new song's transport, which the window reports on stderr).

use crate::common::{self, switch_with_b, xdotool};

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

#[test]
fn switching_a_and_b_keeps_the_playback_position() {
    let _screen = common::screen();
    assert!(
        std::env::var_os("DISPLAY").is_some(),
        "this test needs a display: run it under xvfb-run"
    );
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to press keys in the window (apt-get install xdotool)"
    );
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let home = common::output_dir().join("window_compare_home");
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let song = repo.join("data/demo_song.ply");
    let child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(&song)
        .arg("--compare")
        .arg(&song)
        .arg("--seek")
        .arg("12.5")
        .env("HOME", &home)
        .env("XDG_DATA_HOME", home.join("data"))
        .env("XDG_CONFIG_HOME", home.join("config"))
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        // Its own window: the other window tests' run in the same process, on the same display.
        let window = common::wait_for_window(child).expect("no window");
        let (side, at_b, _) =
            switch_with_b(&window, lines, Duration::from_secs(120)).expect("B never played");
        assert_eq!(side, "B");
        assert!((at_b - 12.5).abs() < 0.01, "B starts at {at_b} s, not 12.5");
        let (side, at_a, _) =
            switch_with_b(&window, lines, Duration::from_secs(30)).expect("A never came back");
        assert_eq!(side, "A");
        assert!(
            (at_a - at_b).abs() < 0.01,
            "A came back at {at_a} s, B was at {at_b}"
        );
        let shot = common::output_dir().join("window_compare.png");
        common::screenshot_root(&shot);
        let image = image::open(&shot).unwrap().to_rgba8();
        // Side by side: both halves of the 3D view (right of the 270-point panel) show data.
        let (w, h) = image.dimensions();
        let panel = 280;
        let mid = panel + (w - panel) / 2;
        for (from, to) in [(panel, mid), (mid, w)] {
            let mut coloured = 0usize;
            for y in 0..h {
                for x in from..to {
                    let p = image.get_pixel(x, y);
                    if (i32::from(p[0]) - i32::from(p[2])).abs() > 80 {
                        coloured += 1;
                    }
                }
            }
            let share = coloured as f64 / f64::from((to - from) * h);
            assert!(share > 0.02, "half {from}..{to} looks blank ({share:.3})");
        }
    });
}
