//! The window's A/B compare of two releases under a display (Xvfb): the demo song against its
//! copy 0.731 s later and 4 dB louder. The window aligns them on a thread (stderr: "compare:
//! aligned (B starts 0.731 s later, ...)"), and key B then switches to the same moment of the
//! music: from A at 12.5 s to B at 13.231 s, and back to A at 12.5 s. Needs the project's
//! extractor (.venv), ffmpeg and xdotool.

use crate::common::{self, line_starting, switch_with_b, xdotool};

use std::process::{Command, Stdio};
use std::time::Duration;

#[test]
fn key_b_switches_to_the_same_moment_of_an_aligned_release() {
    let _screen = common::screen();
    common::assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to press keys in the window (apt-get install xdotool)"
    );
    let repo = common::repo();
    let extractor = common::extractor();
    let dir = common::fresh_dir("window_compare_align");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::home_in(&mut command, &dir.join("home"));
    let mut child = command
        .arg(repo.join("data/demo_song.ply"))
        .arg("--compare")
        .arg(&b)
        .arg("--seek")
        .arg("12.5")
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env("LOUDSCAPE_EXTRACT", &extractor)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("start loudscape");
    let lines = common::stderr_lines(&mut child);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let window = common::wait_for_window(&mut child).expect("no window");
        let mut seen = Vec::new();
        let aligned = line_starting(
            &lines,
            "compare: aligned",
            Duration::from_secs(180),
            &mut seen,
        )
        .expect("the window never aligned A and B");
        assert!(aligned.contains("B starts 0.731 s later"), "{aligned}");
        assert!(aligned.contains("B -4.0 dB"), "{aligned}");
        let (side, at_b, line) =
            switch_with_b(&window, &lines, Duration::from_secs(60)).expect("B never played");
        assert_eq!(side, "B");
        assert!((at_b - 13.231).abs() < 0.01, "{line}");
        assert!(line.contains("from A 12.500 s"), "{line}");
        common::screenshot_root(&dir.join("window_compare_align.png"));
        let (side, at_a, line) =
            switch_with_b(&window, &lines, Duration::from_secs(60)).expect("A never came back");
        assert_eq!(side, "A");
        assert!((at_a - 12.5).abs() < 0.01, "{line}");
    }));
    let _ = child.kill();
    let _ = child.wait();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}
