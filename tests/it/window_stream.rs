//! A song's points appear in the window while it is extracted (docs/FORMAT.md, "Points while
//! extracting"): a stand-in extractor (tests/fixtures/stream_extractor.py) writes the demo
//! cloud's rows a block at a time with the protocol's progress lines and waits after the first
//! block for a file the test writes, so what the window shows then is surely shown before the
//! extraction ends. The first points are drawn, with the progress and Cancel still under the
//! view; the camera moved meanwhile stays when the whole cloud replaces them; a failed
//! extraction takes them off the screen and brings back the cloud they replaced. Needs a display (`make test` runs the window tests
//! under xvfb-run), xdotool and ImageMagick's `import`.

use crate::common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// Rows in the first block (of the demo's 147,750).
const FIRST: usize = 30_000;

fn assert_display() {
    assert!(
        std::env::var_os("DISPLAY").is_some(),
        "this test needs a display: run it under xvfb-run"
    );
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn xdotool(args: &[&str]) -> Option<String> {
    let output = Command::new("xdotool").args(args).output().ok()?;
    output
        .status
        .success()
        .then(|| String::from_utf8_lossy(&output.stdout).trim().to_string())
}

/// The window run on a copy of the demo song with the stand-in extractor; its stderr lines
/// come through the receiver. `fail`: the extractor fails after its first block.
struct Run {
    child: Child,
    lines: Receiver<String>,
    /// Every line seen so far.
    seen: Vec<String>,
    dir: PathBuf,
    go: PathBuf,
}

impl Run {
    fn start(name: &str, fail: bool) -> Run {
        Run::start_with(name, fail, false, &[])
    }

    /// `first_the_demo`: the window opens the demo's cloud first, the song is typed later.
    /// `env`: more of the stand-in's settings (`FAKE_BAD`).
    fn start_with(name: &str, fail: bool, first_the_demo: bool, env: &[(&str, &str)]) -> Run {
        let dir = common::output_dir().join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("home")).unwrap();
        let song = dir.join("song.flac");
        std::fs::copy(repo().join("data/demo_song.flac"), &song).unwrap();
        let demo = repo().join("data/demo_song.ply");
        let cloud = loudscape::data::cloud::load(&demo).expect("the demo cloud loads");
        let axes = dir.join("axes.json");
        std::fs::write(&axes, cloud.meta.raw["axes"].to_string()).unwrap();
        let go = dir.join("go");
        let home = dir.join("home");
        let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
        command.arg(if first_the_demo { &demo } else { &song });
        command
            .env("HOME", &home)
            .env("XDG_DATA_HOME", home.join("data"))
            .env("XDG_CONFIG_HOME", home.join("config"))
            .env("XDG_STATE_HOME", home.join("state"))
            .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
            .env(
                "LOUDSCAPE_EXTRACT",
                repo().join("tests/fixtures/stream_extractor.py"),
            )
            .env("FAKE_PLY", &demo)
            .env("FAKE_AXES", &axes)
            .env("FAKE_ROWS", cloud.points.len().to_string())
            .env("FAKE_FIRST", FIRST.to_string())
            .env("FAKE_GO", &go)
            .stderr(Stdio::piped())
            .stdout(Stdio::null());
        if fail {
            command.env("FAKE_FAIL", "1");
        }
        command.envs(env.iter().copied());
        let mut child = command.spawn().expect("start loudscape");
        let (sender, lines) = channel();
        let stderr = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let _ = sender.send(line);
            }
        });
        Run {
            child,
            lines,
            seen: Vec::new(),
            dir,
            go,
        }
    }

    /// The first stderr line containing `text` within `timeout`.
    fn wait_for(&mut self, text: &str, timeout: Duration) -> String {
        if let Some(line) = self.seen.iter().find(|l| l.contains(text)) {
            return line.clone();
        }
        let end = Instant::now() + timeout;
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            let Ok(line) = self.lines.recv_timeout(left) else {
                break;
            };
            self.seen.push(line.clone());
            if line.contains(text) {
                return line;
            }
        }
        panic!("no '{text}' on stderr in {timeout:?}: {:#?}", self.seen);
    }

    /// Lets the stand-in extractor go on past its first block.
    fn go(&self) {
        std::fs::write(&self.go, b"").unwrap();
    }

    fn stop(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The id of the window of process `pid`, once it is mapped.
fn window(pid: u32) -> String {
    let start = Instant::now();
    loop {
        if let Some(id) = xdotool(&["search", "--pid", &pid.to_string(), "--name", "^loudscape$"])
            && let Some(first) = id.lines().next()
        {
            return first.to_string();
        }
        assert!(start.elapsed() < Duration::from_secs(120), "no window");
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// The share of the 3D view (`common::view_region`) whose pixels are strongly coloured: the
/// points, red to blue by hp.
fn coloured_share(image: &image::RgbaImage, window: (u32, u32)) -> f64 {
    common::coloured_share(image, common::view_region(window))
}

/// How long the window may take to draw what a test waits for.
const DRAWN_WITHIN: Duration = Duration::from_secs(60);

/// The screen once the 3D view shows what `wanted` accepts and holds still (or at
/// [`DRAWN_WITHIN`], for the caller's assertion to judge), saved to `path`.
fn shot_when(
    path: &Path,
    size: (u32, u32),
    wanted: impl Fn(&image::RgbaImage) -> bool,
) -> image::RgbaImage {
    common::shot_settled(path, common::view_region(size), DRAWN_WITHIN, wanted)
}

/// The window's size.
fn window_size(id: &str) -> (u32, u32) {
    let geometry = xdotool(&["getwindowgeometry", "--shell", id]).unwrap_or_default();
    let value = |key: &str| {
        geometry
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{key}=")))
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {key} in {geometry}"))
    };
    (value("WIDTH"), value("HEIGHT"))
}

/// A left-button drag across the 3D view: an orbit. Its pauses are the drag's pace (the
/// window sees the press, the moves and the release in frames of their own, as from a hand),
/// not a wait for the window: what the drag did is waited for on the screen.
fn orbit(id: &str, size: (u32, u32)) {
    let (x, y) = (300 + (size.0 - 300) / 2, size.1 * 3 / 10);
    xdotool(&["mousemove", "--window", id, &x.to_string(), &y.to_string()]);
    std::thread::sleep(Duration::from_millis(200));
    xdotool(&["mousedown", "1"]);
    for step in 1..=12 {
        std::thread::sleep(Duration::from_millis(40));
        let to = (x + step * 20).to_string();
        xdotool(&["mousemove", "--window", id, &to, &y.to_string()]);
    }
    std::thread::sleep(Duration::from_millis(100));
    xdotool(&["mouseup", "1"]);
    // Away from the view, so no read-out covers the points.
    xdotool(&["mousemove", "--window", id, "5", "5"]);
}

/// The share of `part`'s coloured pixels (in the 3D view) that lie within `radius` pixels of a
/// coloured pixel of `whole`: near 1 when `whole` draws the same points from the same camera
/// (the view may have grown a little: the status area under it goes when the load ends).
fn covered_by(part: &image::RgbaImage, whole: &image::RgbaImage, size: (u32, u32)) -> f64 {
    let radius = 8i64;
    let coloured = |image: &image::RgbaImage, x: u32, y: u32| {
        let p = image.get_pixel(x, y);
        (i32::from(p[0]) - i32::from(p[2])).abs() > 60
    };
    let (x0, x1) = (300u32, size.0.min(part.width()));
    let (y0, y1) = (60u32, size.1 * 6 / 10);
    let (mut inside, mut all) = (0usize, 0usize);
    for y in (y0..y1).step_by(2) {
        for x in (x0..x1).step_by(2) {
            if !coloured(part, x, y) {
                continue;
            }
            all += 1;
            let near = (-radius..=radius).step_by(2).any(|dy| {
                (-radius..=radius).step_by(2).any(|dx| {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    nx >= 0
                        && ny >= 0
                        && (nx as u32) < whole.width()
                        && (ny as u32) < whole.height()
                        && coloured(whole, nx as u32, ny as u32)
                })
            });
            if near {
                inside += 1;
            }
        }
    }
    inside as f64 / all.max(1) as f64
}

#[test]
fn the_first_points_show_while_extracting_and_the_whole_cloud_replaces_them() {
    assert_display();
    assert!(
        xdotool(&["version"]).is_some(),
        "this test needs xdotool (apt-get install xdotool)"
    );
    let _screen = common::screen();
    let mut run = Run::start("window_stream", false);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let first = run.wait_for(
            "first points shown while extracting",
            Duration::from_secs(120),
        );
        // The extractor is still waiting for the go file: this is before it ends.
        assert!(!run.go.exists());
        assert!(
            first.contains(&format!("{FIRST} points")),
            "the first block's rows: {first}"
        );
        assert!(
            !run.seen.iter().any(|l| l.contains("cloud extracted")),
            "{:#?}",
            run.seen
        );
        let id = window(run.child.id());
        let size = window_size(&id);
        xdotool(&["mousemove", "--window", &id, "5", "5"]);
        let fitted = shot_when(&run.dir.join("fitted.png"), size, |shot| {
            coloured_share(shot, size) > 0.01
        });
        // Turned by hand while the points come: the whole cloud must not take it back.
        orbit(&id, size);
        let region = common::view_region(size);
        let partial = shot_when(&run.dir.join("partial.png"), size, |shot| {
            !common::same_in(shot, &fitted, region)
        });
        let partial_share = coloured_share(&partial, size);
        assert!(
            partial_share > 0.01,
            "the first points are not drawn: {:.2}% coloured (see {})",
            partial_share * 100.0,
            run.dir.join("partial.png").display()
        );
        run.go();
        let replaced = run.wait_for("the whole cloud (", Duration::from_secs(120));
        let counts: Vec<usize> = replaced
            .split(['(', ' '])
            .filter_map(|w| w.parse().ok())
            .collect();
        assert_eq!(counts.len(), 2, "{replaced}");
        assert_eq!(counts[0], 147_750, "{replaced}");
        assert!(
            (FIRST..=147_750).contains(&counts[1]),
            "the points shown grew from the first block: {replaced}"
        );
        let whole = shot_when(&run.dir.join("whole.png"), size, |shot| {
            coloured_share(shot, size) > partial_share * 1.3
        });
        let whole_share = coloured_share(&whole, size);
        assert!(
            whole_share > partial_share * 1.3,
            "the whole cloud ({:.2}% coloured) is not more than the first points ({:.2}%)",
            whole_share * 100.0,
            partial_share * 100.0
        );
        // The first points are where they were, from the camera turned by hand: not
        // refitted, and drawn with the whole cloud's axes. The fitted view is another picture.
        let kept = covered_by(&partial, &whole, size);
        let refitted = covered_by(&fitted, &whole, size);
        eprintln!(
            "first points within the whole cloud: {kept:.3} (as first fitted: {refitted:.3})"
        );
        assert!(
            kept > 0.75 && kept > refitted + 0.3,
            "the whole cloud is not drawn from the camera the first points were: {kept:.3} of \
             them lie on it, {refitted:.3} of the fitted view's"
        );
        // The whole cloud is the one cached.
        let cached = std::fs::read_dir(run.dir.join("cache"))
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().ends_with(".ply"))
            .count();
        assert_eq!(cached, 1);
    }));
    run.stop();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}

#[test]
fn a_failed_extraction_takes_its_first_points_off_the_screen() {
    assert_display();
    let _screen = common::screen();
    let mut run = Run::start("window_stream_failed", true);
    let shot = run.dir.join("failed.png");
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run.wait_for(
            "first points shown while extracting",
            Duration::from_secs(120),
        );
        let id = window(run.child.id());
        let size = window_size(&id);
        let drawn = |shot: &image::RgbaImage| coloured_share(shot, size) > 0.01;
        let shown = coloured_share(&shot_when(&run.dir.join("shown.png"), size, drawn), size);
        assert!(shown > 0.01, "the first points are not drawn");
        run.go();
        // The error is said under the view; the points are gone.
        let gone = |shot: &image::RgbaImage| coloured_share(shot, size) < 0.001;
        let failed = coloured_share(&shot_when(&shot, size, gone), size);
        assert!(
            failed < 0.001,
            "the points of the failed extraction are still drawn: {:.2}% (see {})",
            failed * 100.0,
            shot.display()
        );
        let clouds = std::fs::read_dir(run.dir.join("cache"))
            .map(|d| {
                d.flatten()
                    .filter(|e| e.file_name().to_string_lossy().ends_with(".ply"))
                    .count()
            })
            .unwrap_or(0);
        assert_eq!(clouds, 0, "a failed extraction caches nothing");
    }));
    run.stop();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}

#[test]
fn a_failed_extraction_brings_back_the_cloud_its_points_replaced() {
    assert_display();
    let _screen = common::screen();
    let mut run = Run::start_with("window_stream_restore", true, true, &[]);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let id = window(run.child.id());
        let size = window_size(&id);
        // The demo's cloud, whole, as it opened.
        let before = shot_when(&run.dir.join("before.png"), size, |shot| {
            coloured_share(shot, size) > 0.02
        });
        assert!(
            coloured_share(&before, size) > 0.02,
            "the demo never showed"
        );
        // The song typed in the Open row's path field (no dialog here), Enter: each step once
        // the row shows the one before it (the field focused, then the name in it).
        let song = run.dir.join("song.flac");
        let open_row = [0, 20, 300, 56];
        let row_changed = |path: &Path, from: &image::RgbaImage| {
            common::shot_settled(path, open_row, Duration::from_secs(10), |shot| {
                !common::same_in(shot, from, open_row)
            })
        };
        xdotool(&["windowfocus", "--sync", &id]);
        xdotool(&["mousemove", "--window", &id, "50", "38"]);
        xdotool(&["click", "1"]);
        let focused = row_changed(&run.dir.join("focused.png"), &before);
        xdotool(&["type", "--delay", "30", &song.display().to_string()]);
        row_changed(&run.dir.join("typed.png"), &focused);
        xdotool(&["key", "Return"]);
        xdotool(&["mousemove", "--window", &id, "5", "5"]);
        run.wait_for(
            "first points shown while extracting",
            Duration::from_secs(120),
        );
        let before_share = coloured_share(&before, size);
        // The first points, fewer than the demo's whole cloud.
        let shown = shot_when(&run.dir.join("shown.png"), size, |shot| {
            let share = coloured_share(shot, size);
            share > 0.001 && share < before_share * 0.8
        });
        let shown_share = coloured_share(&shown, size);
        run.go();
        let after = shot_when(&run.dir.join("after.png"), size, |shot| {
            coloured_share(shot, size) > shown_share * 1.3
        });
        let after_share = coloured_share(&after, size);
        eprintln!(
            "coloured: before {before_share:.4}, first points {shown_share:.4}, after the \
             failure {after_share:.4}"
        );
        assert!(
            shown_share < before_share * 0.8,
            "the first points did not replace the demo's cloud"
        );
        // The demo's cloud is back, from the camera it had.
        assert!(
            after_share > shown_share * 1.3,
            "the cloud the points replaced is not back"
        );
        let back = covered_by(&before, &after, size);
        assert!(back > 0.9, "not the same picture as before: {back:.3}");
    }));
    run.stop();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}

#[test]
fn points_that_cannot_be_read_lose_only_the_preview() {
    assert_display();
    let _screen = common::screen();
    let mut run = Run::start_with("window_stream_bad", false, false, &[("FAKE_BAD", "1")]);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let said = run.wait_for(
            "the points cannot be shown while extracting",
            Duration::from_secs(120),
        );
        assert!(said.contains("row 0"), "{said}");
        run.go();
        run.wait_for("cloud extracted in", Duration::from_secs(120));
        let id = window(run.child.id());
        let size = window_size(&id);
        let drawn = |shot: &image::RgbaImage| coloured_share(shot, size) > 0.02;
        let whole = coloured_share(&shot_when(&run.dir.join("whole.png"), size, drawn), size);
        assert!(whole > 0.02, "the whole cloud is not drawn: {whole:.4}");
        assert!(
            !run.seen.iter().any(|l| l.contains("first points shown")),
            "{:#?}",
            run.seen
        );
    }));
    run.stop();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}
