//! Helpers shared by the integration tests: a device on whatever adapter exists (lavapipe on
//! machines without a GPU), golden-image comparison with a tolerance, the demo song, running the
//! `loudscape` binary, songs and videos made and decoded (media.rs), and the window tests'
//! display, window, stderr and process look-ups.

#![allow(dead_code)]

mod golden;
mod media;
pub use golden::{RASTER_EDGES, RAY_MARCH, assert_golden};
pub use media::{
    chord_with_clicks, compare_render, compare_video, decode_audio, decode_frames,
    delayed_louder_demo, demo_through, extractor, half, write_wav,
};

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use loudscape::data::cloud::{self, PointCloud};
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::scene::SceneData;
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

/// A headless device; the tests need one (install mesa-vulkan-drivers for lavapipe).
pub fn gpu() -> GpuContext {
    match GpuContext::new_headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!("GPU tests need an adapter (lavapipe will do): {e}"),
    }
}

/// The repository's root (the package's folder).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// data/demo_song.ply, loaded.
pub fn demo_song() -> PointCloud {
    cloud::load(&repo().join("data/demo_song.ply")).unwrap_or_else(|e| panic!("{e}"))
}

/// A song cloud at `path`: `n` points along a curve whose y is `sin(wave * t)` (other waves,
/// other points), with a song's axes (4 s, 0 to 11,025 Hz, -80 to 0 dB) and `extra`'s fields
/// (warnings, metrics) in its metadata. The prepared clouds the stand-in extractors copy.
pub fn write_song_cloud(path: &Path, n: usize, wave: f32, extra: serde_json::Value) {
    let mut meta = serde_json::json!({
        "format_version": 2,
        "mode": "song",
        "axes": {
            "x": {"label": "time", "unit": "s", "min": 0.0, "max": 4.0},
            "y": {"label": "frequency", "unit": "Hz", "min": 0.0, "max": 11025.0},
            "z": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0},
            "scalar": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0},
            "hp": {"label": "hp", "unit": "", "min": 0.0, "max": 1.0}
        }
    });
    if let (Some(meta), serde_json::Value::Object(extra)) = (meta.as_object_mut(), extra) {
        meta.extend(extra);
    }
    let last = (n - 1) as f32;
    let points: Vec<cloud::Point> = (0..n)
        .map(|i| {
            let t = i as f32 / last;
            cloud::Point {
                position: [
                    t * 2.0 - 1.0,
                    (t * wave).sin() * 0.8,
                    (t * 11.0).cos() * 0.5,
                ],
                scalar: t,
                hp: 1.0 - t,
            }
        })
        .collect();
    let mut bytes = Vec::new();
    cloud::write(&mut bytes, &points, Some(&meta)).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// How many runs the stand-in extractors in `dir` have logged (a line each in `runs.txt`).
pub fn runs(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("runs.txt"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

/// The names in `dir`, sorted (none if there is no such folder).
pub fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// The default camera's view of `data`, fitted to a `width` x `height` picture.
pub fn view_of(data: &SceneData, width: u32, height: u32) -> FrameView {
    FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        width,
        height,
    )
}

/// Where failing tests leave their actual and difference images.
pub fn output_dir() -> PathBuf {
    let dir = repo().join("tests").join("output");
    std::fs::create_dir_all(&dir).expect("create tests/output");
    dir
}

/// How two images differ: the share of pixels whose largest channel difference exceeds
/// `threshold`, and the mean absolute channel difference.
pub fn difference(a: &image::RgbaImage, b: &image::RgbaImage, threshold: u8) -> (f64, f64) {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let mut over = 0usize;
    let mut sum = 0u64;
    for (pa, pb) in a.pixels().zip(b.pixels()) {
        let mut worst = 0u8;
        for c in 0..3 {
            let d = pa[c].abs_diff(pb[c]);
            worst = worst.max(d);
            sum += u64::from(d);
        }
        if worst > threshold {
            over += 1;
        }
    }
    let n = (a.width() * a.height()) as f64;
    (over as f64 / n, sum as f64 / (n * 3.0))
}

/// A fresh (emptied) folder under tests/output for one test.
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = output_dir().join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create the test folder");
    dir
}

/// Runs the `loudscape` binary with `args` and waits for it.
pub fn loudscape<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(args)
        .output()
        .expect("start loudscape")
}

/// Runs the `loudscape` binary with `args`, the song cache in `cache` and `extractor` as the
/// extractor it runs, and waits for it.
pub fn loudscape_extracting(args: &[&OsStr], cache: &Path, extractor: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(args)
        .env("LOUDSCAPE_CACHE_DIR", cache)
        .env("LOUDSCAPE_EXTRACT", extractor)
        .output()
        .expect("start loudscape")
}

/// Fails with the command's error output unless it succeeded.
pub fn assert_success(output: &Output) {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// ffprobe's streams and format of `path`, as JSON.
pub fn ffprobe(path: &Path) -> serde_json::Value {
    let output = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-show_streams",
            "-show_format",
            "-of",
            "json",
        ])
        .arg(path)
        .output()
        .expect("ffprobe (install ffmpeg)");
    assert!(
        output.status.success(),
        "ffprobe failed on {}: {}",
        path.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("ffprobe json")
}

/// The window tests need a display (`make test` runs them under xvfb-run).
pub fn assert_display() {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "this test needs a display: run it through `make test` (xvfb-run) or xvfb-run -a cargo test"
    );
}

/// One window test on the screen at a time: the window tests share one process and one
/// display, look at the screen and move the pointer and the keyboard focus, and windows opened
/// together overlap (there is no window manager). Every window test holds this while its
/// window is open; the GPU and command tests run beside them. A test that failed holding it
/// leaves it usable.
pub fn screen() -> std::sync::MutexGuard<'static, ()> {
    static SCREEN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    SCREEN
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The X window id of `child`'s own window (the other tests' windows are named alike), once it
/// is mapped; `None` if the process ends or no window appears within 90 s.
pub fn wait_for_window(child: &mut Child) -> Option<String> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(90) {
        if let Ok(Some(_)) = child.try_wait() {
            return None;
        }
        let search = Command::new("xdotool")
            .args(["search", "--all", "--pid", &child.id().to_string()])
            .args(["--name", "^loudscape$"])
            .output()
            .expect("xdotool (scripts/setup-system.sh installs it)");
        let ids = String::from_utf8_lossy(&search.stdout).into_owned();
        if let Some(id) = ids.lines().next() {
            return Some(id.trim().to_string());
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    None
}

/// `xdotool` with `args`: what it printed, trimmed, if it ran and succeeded.
pub fn xdotool(args: &[&str]) -> Option<String> {
    let output = Command::new("xdotool").args(args).output().ok()?;
    output
        .status
        .success()
        .then(|| String::from_utf8_lossy(&output.stdout).trim().to_string())
}

/// Runs `test` on `child` (spawned with stderr piped) and its stderr lines; the child is killed
/// and reaped whether `test` passes or panics, and then its panic goes on.
pub fn while_running(mut child: Child, test: impl FnOnce(&mut Child, &Receiver<String>)) {
    let lines = stderr_lines(&mut child);
    let result =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| test(&mut child, &lines)));
    let _ = child.kill();
    let _ = child.wait();
    if let Err(panic) = result {
        std::panic::resume_unwind(panic);
    }
}

/// `child`'s stderr (spawned piped) a line at a time, read on a thread of its own.
pub fn stderr_lines(child: &mut Child) -> Receiver<String> {
    let (sender, lines) = channel();
    let stderr = child.stderr.take().expect("the child's stderr is piped");
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = sender.send(line);
        }
    });
    lines
}

/// The first line starting with `prefix` within `timeout`; every line read goes to `seen`.
pub fn line_starting(
    lines: &Receiver<String>,
    prefix: &str,
    timeout: Duration,
    seen: &mut Vec<String>,
) -> Option<String> {
    let deadline = Instant::now() + timeout;
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        let line = lines.recv_timeout(left).ok()?;
        seen.push(line.clone());
        if line.starts_with(prefix) {
            return Some(line);
        }
    }
    None
}

/// Presses B on a compare's `window` every second until a "listening to X at T s" line comes
/// (within `timeout`): X, T and the whole line.
pub fn switch_with_b(
    window: &str,
    lines: &Receiver<String>,
    timeout: Duration,
) -> Option<(String, f64, String)> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        xdotool(&["windowfocus", "--sync", window]);
        xdotool(&["key", "--clearmodifiers", "b"]);
        let heard = line_starting(
            lines,
            "listening to ",
            Duration::from_secs(1),
            &mut Vec::new(),
        );
        if let Some(line) = heard {
            let mut words = line["listening to ".len()..].split_whitespace();
            let side = words.next()?.to_string();
            let seconds: f64 = words.nth(1)?.parse().ok()?;
            return Some((side, seconds, line));
        }
    }
    None
}

/// The 3D view of a window at the screen's top left that is `size` pixels (right of the side
/// panel, the window's top 60 %, above the status area): where the window tests look for the
/// data, as `[x0, y0, x1, y1]`.
pub fn view_region(size: (u32, u32)) -> [u32; 4] {
    [300, 60, size.0, size.1 * 6 / 10]
}

/// The share of `region`'s pixels that are strongly coloured: the points and surfaces, red to
/// blue by hp; the background, the panels, the axes and the labels are grey.
pub fn coloured_share(image: &image::RgbaImage, region: [u32; 4]) -> f64 {
    let [x0, y0, x1, y1] = region;
    let (x1, y1) = (x1.min(image.width()), y1.min(image.height()));
    let mut coloured = 0usize;
    for y in y0..y1 {
        for x in x0..x1 {
            let p = image.get_pixel(x, y);
            if (i32::from(p[0]) - i32::from(p[2])).abs() > 60 {
                coloured += 1;
            }
        }
    }
    coloured as f64 / f64::from((x1 - x0) * (y1 - y0)).max(1.0)
}

/// Takes screenshots into `path` until one shows what `wanted` accepts and `region` of it is
/// the same as in the shot before (the picture there holds still: the window has drawn what
/// it was waiting for), or until `timeout`; returns that shot, or the last one at the
/// deadline for the caller's assertion to judge. What the window tests wait for instead of a
/// fixed time.
pub fn shot_settled(
    path: &Path,
    region: [u32; 4],
    timeout: Duration,
    wanted: impl Fn(&image::RgbaImage) -> bool,
) -> image::RgbaImage {
    let deadline = Instant::now() + timeout;
    let mut last: Option<image::RgbaImage> = None;
    loop {
        screenshot_root(path);
        let shot = image::open(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .to_rgba8();
        let still = last
            .as_ref()
            .is_some_and(|before| same_in(before, &shot, region));
        if (still && wanted(&shot)) || Instant::now() >= deadline {
            return shot;
        }
        last = Some(shot);
    }
}

/// The screen once a window opened at its size (1280 x 800, at the screen's top left: there
/// is no window manager) shows the demo song's points in its 3D view, held still; saved to
/// `path`. Fails if they are not drawn within 60 s.
pub fn song_drawn(path: &Path) -> image::RgbaImage {
    let region = view_region((1280, 800));
    let drawn = |shot: &image::RgbaImage| coloured_share(shot, region) > 0.02;
    let shot = shot_settled(path, region, Duration::from_secs(60), drawn);
    assert!(
        drawn(&shot),
        "the song is not drawn (see {})",
        path.display()
    );
    shot
}

/// Whether `a` and `b` have the same pixels in `region`.
pub fn same_in(a: &image::RgbaImage, b: &image::RgbaImage, region: [u32; 4]) -> bool {
    let [x0, y0, x1, y1] = region;
    a.dimensions() == b.dimensions()
        && (y0..y1.min(a.height()))
            .all(|y| (x0..x1.min(a.width())).all(|x| a.get_pixel(x, y) == b.get_pixel(x, y)))
}

/// The whole screen saved to `path` (imagemagick's `import`), to look at.
pub fn screenshot_root(path: &Path) {
    let status = Command::new("import")
        .args(["-window", "root"])
        .arg(path)
        .status()
        .expect("import (imagemagick)");
    assert!(status.success(), "import -window root {}", path.display());
}

/// Runs the window on `file` until it saves its screenshot to `shot`; returns the screenshot.
pub fn window_screenshot(file: &Path, shot: &Path) -> image::RgbaImage {
    let _ = std::fs::remove_file(shot);
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg(file)
        .arg("--screenshot")
        .arg(shot)
        .output()
        .expect("start loudscape");
    assert!(
        output.status.success(),
        "loudscape exited with {}: {}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    image::open(shot)
        .unwrap_or_else(|e| panic!("no screenshot at {}: {e}", shot.display()))
        .to_rgba8()
}

/// Gives `command` the folder `home` as its home and XDG data, config, state and cache folders,
/// so that the window's saved state and files stay in the test's folder.
pub fn home_in<'a>(command: &'a mut Command, home: &Path) -> &'a mut Command {
    for var in [
        "HOME",
        "XDG_DATA_HOME",
        "XDG_CONFIG_HOME",
        "XDG_STATE_HOME",
        "XDG_CACHE_HOME",
    ] {
        command.env(var, home);
    }
    command
}

/// Runs `command` (the window) with a `--press` for each of `press`, waits for it, and returns
/// its stderr; fails with it unless the window exited successfully.
pub fn run_pressing<S: AsRef<OsStr>>(command: &mut Command, press: &[S]) -> String {
    for key in press {
        command.arg("--press").arg(key);
    }
    let output = command.output().expect("start loudscape");
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "loudscape failed: {err}");
    err
}

/// Waits up to 30 s for `child` to exit, kills it if it has not, and returns its output.
pub fn exit_within_30_s(mut child: Child) -> Output {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(30) && child.try_wait().ok().flatten().is_none() {
        std::thread::sleep(Duration::from_millis(100));
    }
    if child.try_wait().ok().flatten().is_none() {
        let _ = child.kill();
    }
    child.wait_with_output().expect("wait for loudscape")
}

/// How many processes have `path` in their command line (Linux: reads /proc).
pub fn processes_naming(path: &Path) -> usize {
    let needle = path.to_str().expect("a UTF-8 path").as_bytes().to_vec();
    std::fs::read_dir("/proc")
        .expect("/proc")
        .flatten()
        .filter_map(|e| std::fs::read(e.path().join("cmdline")).ok())
        .filter(|c| c.windows(needle.len()).any(|w| w == needle.as_slice()))
        .count()
}

/// The share of pixels that are not the background, to check an image is not blank.
pub fn coverage(image: &image::RgbaImage) -> f64 {
    let bg = image.get_pixel(0, 0);
    let covered = image
        .pixels()
        .filter(|p| (0..3).any(|c| p[c].abs_diff(bg[c]) > 16))
        .count();
    covered as f64 / (image.width() * image.height()) as f64
}

/// A song cloud of `count` synthetic points (`data::synthetic::synthetic_song`, its `seed`) at
/// `path`, with the demo's axes (so the two share them in a compare).
pub fn write_synthetic_song(path: &Path, count: usize, seed: u64) {
    let points = loudscape::data::synthetic::synthetic_song(count, seed);
    let axis = |label: &str, unit: &str, min: f64, max: f64| serde_json::json!({"label": label, "unit": unit, "min": min, "max": max, "scale": "linear"});
    let meta = serde_json::json!({
        "format_version": loudscape::data::cloud::FORMAT_VERSION,
        "mode": "song",
        "point_count": points.len(),
        "axes": {
            "x": axis("time", "s", 0.0, 29.953741),
            "y": axis("level", "dB", -65.018802, -5.018802),
            "z": axis("frequency", "Hz", 0.0, 11025.0),
            "scalar": axis("A-weighted level", "dB", -114.0, 0.0),
            "hp": axis("harmonic-percussive ratio", "", 0.0, 1.0),
        },
    });
    let mut file = Vec::new();
    loudscape::data::cloud::write(&mut file, &points, Some(&meta)).unwrap();
    std::fs::write(path, file).unwrap();
}

/// A PATH without zenity and no session bus: no file dialog can open, so a save goes straight
/// to its default name.
pub fn no_dialog(command: &mut Command) -> &mut Command {
    command
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .env("PATH", "/usr/bin/false-folder-without-zenity")
}

/// The pictures Save PNG wrote into `dir` under its default names (`loudscape-….png`).
pub fn saved_pictures(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name().is_some_and(|n| {
                let n = n.to_string_lossy();
                n.starts_with("loudscape-") && n.ends_with(".png")
            })
        })
        .collect()
}
