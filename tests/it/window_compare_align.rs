//! The window's A/B compare of two releases under a display (Xvfb): the demo song against its
//! copy 0.731 s later and 4 dB louder. The window aligns them on a thread (stderr: "compare:
//! aligned (B starts 0.731 s later, ...)"), and key B then switches to the same moment of the
//! music: from A at 12.5 s to B at 13.231 s, and back to A at 12.5 s. Needs the project's
//! extractor (.venv), ffmpeg and xdotool.

use crate::common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

fn xdotool(args: &[&str]) -> Option<String> {
    let output = Command::new("xdotool").args(args).output().ok()?;
    output
        .status
        .success()
        .then(|| String::from_utf8_lossy(&output.stdout).trim().to_string())
}

/// The next line starting with `prefix` within `timeout`.
fn line_starting(lines: &Receiver<String>, prefix: &str, timeout: Duration) -> Option<String> {
    let deadline = Instant::now() + timeout;
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        let line = lines.recv_timeout(left).ok()?;
        if line.starts_with(prefix) {
            return Some(line);
        }
    }
    None
}

/// Presses B on the window every second until a "listening to" line comes: (side, seconds,
/// the whole line).
fn switch(window: &str, lines: &Receiver<String>) -> Option<(String, f64, String)> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        xdotool(&["windowfocus", "--sync", window]);
        xdotool(&["key", "--clearmodifiers", "b"]);
        if let Some(line) = line_starting(lines, "listening to ", Duration::from_secs(1)) {
            let mut words = line["listening to ".len()..].split_whitespace();
            let side = words.next()?.to_string();
            let seconds: f64 = words.nth(1)?.parse().ok()?;
            return Some((side, seconds, line));
        }
    }
    None
}

#[test]
fn key_b_switches_to_the_same_moment_of_an_aligned_release() {
    let _screen = common::screen();
    common::assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to press keys in the window (apt-get install xdotool)"
    );
    let repo = common::repo();
    let extractor = repo.join(".venv/bin/loudscape-extract");
    assert!(
        extractor.is_file(),
        "this test runs the Python extractor: install it with `make venv`"
    );
    let dir = common::fresh_dir("window_compare_align");
    let b = dir.join("delayed_louder.wav");
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(repo.join("data/demo_song.flac"))
        .args(["-af", "adelay=731:all=1,volume=4dB", "-c:a", "pcm_f32le"])
        .arg(&b)
        .output()
        .expect("this test needs ffmpeg");
    assert!(made.status.success());
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
    let (sender, lines) = channel();
    let stderr = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = sender.send(line);
        }
    });
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let window = common::wait_for_window(&mut child).expect("no window");
        let aligned = line_starting(&lines, "compare: aligned", Duration::from_secs(180))
            .expect("the window never aligned A and B");
        assert!(aligned.contains("B starts 0.731 s later"), "{aligned}");
        assert!(aligned.contains("B -4.0 dB"), "{aligned}");
        let (side, at_b, line) = switch(&window, &lines).expect("B never played");
        assert_eq!(side, "B");
        assert!((at_b - 13.231).abs() < 0.01, "{line}");
        assert!(line.contains("from A 12.500 s"), "{line}");
        let shot = dir.join("window_compare_align.png");
        let status = Command::new("import")
            .args(["-window", "root"])
            .arg(&shot)
            .status()
            .expect("import (imagemagick)");
        assert!(status.success());
        let (side, at_a, line) = switch(&window, &lines).expect("A never came back");
        assert_eq!(side, "A");
        assert!((at_a - 12.5).abs() < 0.01, "{line}");
    }));
    let _ = child.kill();
    let _ = child.wait();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}
