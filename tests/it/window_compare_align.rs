//! The window's A/B compare of two releases under a display (Xvfb): the demo song against its
//! copy 0.731 s later and 4 dB louder. The window aligns them on a thread (stderr: "compare:
//! aligned (B starts 0.731 s later, ...)"), and key B then switches to the same moment of the
//! music: from A at 12.5 s to B at 13.231 s, and back to A at 12.5 s. Needs the project's
//! extractor (.venv), ffmpeg and xdotool.

use crate::common::{self, line_starting, switch_with_b, xdotool};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The window, its home, cache and extractor in `dir`, stderr piped (the lines the tests wait
/// for); the caller adds the songs and the flags.
fn compare_window(dir: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::home_in(&mut command, &dir.join("home"));
    command
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env("LOUDSCAPE_EXTRACT", common::extractor())
        .stderr(Stdio::piped())
        .stdout(Stdio::null());
    command
}

#[test]
fn key_b_switches_to_the_same_moment_of_an_aligned_release() {
    let _screen = common::screen();
    common::assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to press keys in the window (apt-get install xdotool)"
    );
    let dir = common::fresh_dir("window_compare_align");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let mut command = compare_window(&dir);
    let child = command
        .arg(common::repo().join("data/demo_song.ply"))
        .arg("--compare")
        .arg(&b)
        .arg("--seek")
        .arg("12.5")
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        let window = common::wait_for_window(child).expect("no window");
        let mut seen = Vec::new();
        let aligned = line_starting(
            lines,
            "compare: aligned",
            Duration::from_secs(180),
            &mut seen,
        )
        .expect("the window never aligned A and B");
        assert!(aligned.contains("B starts 0.731 s later"), "{aligned}");
        assert!(aligned.contains("B -4.0 dB"), "{aligned}");
        let (side, at_b, line) =
            switch_with_b(&window, lines, Duration::from_secs(60)).expect("B never played");
        assert_eq!(side, "B");
        assert!((at_b - 13.231).abs() < 0.01, "{line}");
        assert!(line.contains("from A 12.500 s"), "{line}");
        common::screenshot_root(&dir.join("window_compare_align.png"));
        let (side, at_a, line) =
            switch_with_b(&window, lines, Duration::from_secs(60)).expect("A never came back");
        assert_eq!(side, "A");
        assert!((at_a - 12.5).abs() < 0.01, "{line}");
    });
}

/// The gain a switch line ends with: "listening to B at 13.231 s (...); gain -4.0 dB".
fn switch_gain(line: &str) -> f64 {
    line.rsplit_once("; gain ")
        .and_then(|(_, gain)| gain.strip_suffix(" dB"))
        .and_then(|gain| gain.parse().ok())
        .unwrap_or_else(|| panic!("no gain in {line:?}"))
}

/// The gain the alignment line gives `letter`: "...; gains A +0.0 dB, B -4.0 dB, C -2.0 dB".
fn aligned_gain(line: &str, letter: char) -> f64 {
    let gains = line.rsplit_once("; gains ").map_or("", |(_, gains)| gains);
    gains
        .split(", ")
        .find_map(|gain| gain.strip_prefix(&format!("{letter} ")))
        .and_then(|gain| gain.strip_suffix(" dB"))
        .and_then(|gain| gain.parse().ok())
        .unwrap_or_else(|| panic!("no gain of {letter} in {line:?}"))
}

/// Three versions: A (the demo song), B 0.731 s later and 4 dB louder, C starting 0.4 s into
/// the song (its music 0.4 s earlier) and 2 dB louder. Key B steps A -> B -> C -> A, each
/// switch to the same moment of the music through each version's own alignment to A, each
/// version at the gain that brings it to the quietest one's loudness (A's).
#[test]
fn key_b_steps_through_three_versions_at_the_same_moment() {
    let _screen = common::screen();
    common::assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool to press keys in the window (apt-get install xdotool)"
    );
    let dir = common::fresh_dir("window_compare_three");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let c = dir.join("earlier_louder.wav");
    common::demo_through(&c, "atrim=start=0.4,asetpts=PTS-STARTPTS,volume=2dB");
    let mut command = compare_window(&dir);
    let child = command
        .arg(common::repo().join("data/demo_song.ply"))
        .arg("--compare")
        .arg(&b)
        .arg(&c)
        .arg("--seek")
        .arg("12.5")
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        let window = common::wait_for_window(child).expect("no window");
        let mut seen = Vec::new();
        let aligned = line_starting(
            lines,
            "compare: aligned",
            Duration::from_secs(240),
            &mut seen,
        )
        .expect("the window never aligned the versions");
        assert!(aligned.contains("B starts 0.731 s later"), "{aligned}");
        assert!(aligned.contains("C starts 0.400 s earlier"), "{aligned}");
        // A is the quietest: it plays as it is, B 4 dB down, C 2 dB down.
        assert!(
            aligned.contains("gains A +0.0 dB, B -4.0 dB, C "),
            "{aligned}"
        );
        assert!(
            (aligned_gain(&aligned, 'C') + 2.0).abs() < 0.15,
            "{aligned}"
        );
        let (side, at_b, line) =
            switch_with_b(&window, lines, Duration::from_secs(60)).expect("B never played");
        assert_eq!(side, "B", "{line}");
        assert!((at_b - 13.231).abs() < 0.01, "{line}");
        assert!((switch_gain(&line) + 4.0).abs() < 0.15, "{line}");
        let (side, at_c, line) =
            switch_with_b(&window, lines, Duration::from_secs(60)).expect("C never played");
        assert_eq!(side, "C", "{line}");
        assert!((at_c - 12.1).abs() < 0.01, "{line}");
        assert!(line.contains("from B 13.231 s"), "{line}");
        assert!((switch_gain(&line) + 2.0).abs() < 0.15, "{line}");
        // Side by side: A and the version heard.
        line_starting(
            lines,
            "compare: A and C shown",
            Duration::from_secs(60),
            &mut seen,
        )
        .expect("C was never shown beside A");
        common::screenshot_root(&dir.join("window_compare_three.png"));
        let (side, at_a, line) =
            switch_with_b(&window, lines, Duration::from_secs(60)).expect("A never came back");
        assert_eq!(side, "A", "{line}");
        assert!((at_a - 12.5).abs() < 0.01, "{line}");
        assert!(switch_gain(&line).abs() < 0.15, "{line}");
    });
}

/// Pixels of the 3D view's middle (right of the side panel, above the strip) with a colour
/// (the difference's warm and cool tints), not grey.
fn tinted_pixels(screen: &image::RgbaImage) -> usize {
    let mut count = 0;
    for y in 100..450.min(screen.height()) {
        for x in 400..1000.min(screen.width()) {
            let p = screen.get_pixel(x, y);
            let (max, min) = (p[0].max(p[1]).max(p[2]), p[0].min(p[1]).min(p[2]));
            count += usize::from(max - min > 40);
        }
    }
    count
}

/// The range a "compare: difference read (level, range 7.640)" line gives.
fn difference_range(line: &str) -> f64 {
    line.rsplit_once("range ")
        .and_then(|(_, range)| range.strip_suffix(')'))
        .and_then(|range| range.parse().ok())
        .unwrap_or_else(|| panic!("no range in {line:?}"))
}

/// The difference's "matched" measure: the demo song against its copy 0.731 s later and 4 dB
/// louder (both extracted from audio alike, so what differs is the delay and the gain), once
/// aligned, is drawn with B's levels moved by -4 dB (stderr: "compare: A and B shown
/// (matched)"): the level-weighted difference's range falls from the 7.64 of the pair as it
/// is (`render`, docs/COMPARE.md) to under 3, what is left being the STFT frames' phase; and
/// below half of the unmatched range the window itself read where its grids came before the
/// alignment. The screenshot shows what is left.
#[test]
fn the_matched_difference_moves_b_to_as_loudness() {
    let _screen = common::screen();
    common::assert_display();
    let dir = common::fresh_dir("window_compare_matched");
    let b = dir.join("delayed_louder.wav");
    common::delayed_louder_demo(&b);
    let mut command = compare_window(&dir);
    let child = command
        .arg(common::repo().join("data/demo_song.flac"))
        .arg("--compare")
        .arg(&b)
        .args([
            "--press",
            "compare=difference",
            "--press",
            "measure=matched",
        ])
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        common::wait_for_window(child).expect("no window");
        let mut seen = Vec::new();
        let aligned = line_starting(
            lines,
            "compare: aligned",
            Duration::from_secs(300),
            &mut seen,
        )
        .expect("the window never aligned A and B");
        assert!(aligned.contains("B -4.0 dB"), "{aligned}");
        line_starting(
            lines,
            "compare: A and B shown (matched)",
            Duration::from_secs(180),
            &mut seen,
        )
        .unwrap_or_else(|| panic!("B was never matched: {seen:#?}"));
        let matched = line_starting(
            lines,
            "compare: difference read (level, matched",
            Duration::from_secs(120),
            &mut seen,
        )
        .unwrap_or_else(|| panic!("the matched difference never came: {seen:#?}"));
        let after = difference_range(&matched);
        println!("level-weighted range, aligned and matched: {after:.3}");
        assert!(after < 3.0, "{matched}");
        // The grids built before the alignment came (if they did): B as it is.
        if let Some(first) = seen
            .iter()
            .find(|l| l.starts_with("compare: difference read (level, range"))
        {
            let before = difference_range(first);
            println!("level-weighted range as it is: {before:.3}");
            assert!(after < before / 2.0, "{first} / {matched}");
        }
        // The picture, once the window has presented it (a frame of the volume pass on a
        // software device comes well after the line): tinted voxels in the view.
        let shot = dir.join("window_compare_matched.png");
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            common::screenshot_root(&shot);
            let tinted = tinted_pixels(&image::open(&shot).unwrap().to_rgba8());
            if tinted > 500 {
                break;
            }
            assert!(
                Instant::now() < deadline,
                "the matched difference was never drawn ({tinted} tinted pixels)"
            );
        }
    });
}
