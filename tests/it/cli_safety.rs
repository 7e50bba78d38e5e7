//! The command line never loses data and never writes a file the app cannot open: outputs that
//! are inputs (by path or through links) and unknown output types are refused before any work;
//! temporary files vanish on SIGTERM; degenerate clouds (one point, equal axis ends) load and
//! render; messages are one short line; `-q` silences the summaries.

use crate::common::{self, loudscape};

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use loudscape::data::cloud::{self, Point};

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A fresh folder for one test.
fn folder(name: &str) -> PathBuf {
    let dir = common::output_dir().join("cli_safety").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("mkdir");
    dir
}

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn s(path: &Path) -> &str {
    path.to_str().expect("utf-8 test path")
}

/// Asserts a failure with exactly one line on stderr, containing `needle`.
fn assert_one_line_error(output: &Output, needle: &str) {
    let text = stderr(output);
    assert!(!output.status.success(), "succeeded: {text}");
    assert_eq!(text.lines().count(), 1, "not one line: {text}");
    assert!(text.len() < 400, "too long: {text}");
    assert!(text.contains(needle), "{needle:?} not in {text}");
}

/// Unix only: it makes symbolic links, and only there do hard links count (`files::same_file`
/// compares inodes on Unix, absolute paths elsewhere).
#[cfg(unix)]
#[test]
fn outputs_that_are_inputs_are_refused_untouched() {
    let dir = folder("same_file");
    let cloud = dir.join("c.ply");
    std::fs::copy(repo("data/fixture_song.ply"), &cloud).expect("copy");
    let original = std::fs::read(&cloud).unwrap();
    let link = dir.join("link.ply");
    std::os::unix::fs::symlink(&cloud, &link).expect("symlink");
    let hard = dir.join("hard.npy");
    std::fs::hard_link(&cloud, &hard).expect("hard link");

    let cases: Vec<Vec<&str>> = vec![
        vec!["render", s(&cloud), "-o", s(&cloud)],
        vec!["mesh", s(&cloud), "-o", s(&cloud)],
        vec!["mesh", s(&cloud), "-o", s(&link)],
        vec!["render", s(&link), "-o", s(&cloud)],
        vec!["voxelize", s(&cloud), "-o", s(&hard)],
    ];
    for args in &cases {
        let output = loudscape(args);
        assert_one_line_error(&output, "the output is the input");
        assert_eq!(
            std::fs::read(&cloud).unwrap(),
            original,
            "{args:?} changed it"
        );
    }
    // The same for render-demo's pictures and the window's screenshot.
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::os::unix::fs::symlink(&cloud, out.join("c_points.png")).unwrap();
    let output = loudscape(&["render-demo", "--out-dir", s(&out), s(&cloud)]);
    assert_one_line_error(&output, "the output is the input");
    let output = loudscape(&["--screenshot", s(&link), s(&cloud)]);
    assert_one_line_error(&output, "the output is the input");
    let output = loudscape(&["--screenshot", s(&dir.join("shot.jpg")), s(&cloud)]);
    assert_one_line_error(&output, "cannot write this file type; supported: .png");
    let png_link = dir.join("c.png");
    std::os::unix::fs::symlink(&cloud, &png_link).unwrap();
    let output = loudscape(&["--screenshot", s(&png_link), s(&cloud)]);
    assert_one_line_error(&output, "the output is the input");
    assert_eq!(std::fs::read(&cloud).unwrap(), original);
}

#[test]
fn output_types_are_checked_first() {
    let dir = folder("types");
    let jpg = dir.join("a.jpg");
    let output = loudscape(&["render", s(&repo("data/fixture_song.ply")), "-o", s(&jpg)]);
    assert_one_line_error(&output, "supported: .png");
    assert!(!jpg.exists());
    let output = loudscape(&["voxelize", s(&repo("data/fixture_song.ply")), "-o", s(&jpg)]);
    assert_one_line_error(&output, ".npy or .nrrd");
    let output = loudscape(&["mesh", s(&repo("data/fixture_song.ply")), "-o", s(&jpg)]);
    assert_one_line_error(&output, ".ply or .obj");
}

#[test]
fn unknown_subcommands_get_clap_usual_error() {
    let output = loudscape(&["frobnicate"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    let text = stderr(&output);
    assert!(
        text.starts_with("error: unrecognized subcommand 'frobnicate'"),
        "{text}"
    );
    assert!(
        !text.contains("registry") && !text.to_lowercase().contains("window"),
        "{text}"
    );
}

#[test]
fn a_missing_file_says_its_os_error_once() {
    let dir = folder("missing");
    let output = loudscape(&[
        "render",
        s(&dir.join("nope.ply")),
        "-o",
        s(&dir.join("a.png")),
    ]);
    assert_one_line_error(&output, "nope.ply: cannot open");
    assert_eq!(
        stderr(&output).matches("No such file").count(),
        1,
        "{}",
        stderr(&output)
    );
}

#[test]
fn long_echoed_content_is_cut_to_one_line() {
    let dir = folder("long");
    let path = dir.join("long.ply");
    let meta = serde_json::json!({
        "format_version": cloud::FORMAT_VERSION,
        "mode": format!("{}\nsecond line", "song".repeat(5000)),
        "axes": {},
    });
    let mut file = Vec::new();
    cloud::write(&mut file, &[point(0.0, 0.0, 0.0)], Some(&meta)).unwrap();
    std::fs::write(&path, file).unwrap();
    let output = loudscape(&["render", s(&path), "-o", s(&dir.join("a.png"))]);
    assert_one_line_error(&output, "long.ply");
}

fn point(x: f32, y: f32, z: f32) -> Point {
    Point {
        position: [x, y, z],
        scalar: 0.5,
        hp: 0.5,
    }
}

/// A song cloud with the given axis ends for x, y, z.
fn write_cloud(path: &Path, points: &[Point], ends: [(f64, f64); 3]) {
    let axis = |label: &str, unit: &str, (min, max): (f64, f64)| serde_json::json!({"label": label, "unit": unit, "min": min, "max": max, "scale": "linear"});
    let meta = serde_json::json!({
        "format_version": cloud::FORMAT_VERSION,
        "mode": "song",
        "point_count": points.len(),
        "axes": {
            "x": axis("time", "s", ends[0]),
            "y": axis("level", "dB", ends[1]),
            "z": axis("crest", "dB", ends[2]),
            "scalar": axis("level", "dB", (-100.0, 0.0)),
            "hp": axis("hp", "", (0.0, 1.0)),
        },
    });
    let mut file = Vec::new();
    cloud::write(&mut file, points, Some(&meta)).unwrap();
    std::fs::write(path, file).unwrap();
}

#[test]
fn degenerate_clouds_load_and_render() {
    let dir = folder("degenerate");
    let one = dir.join("one_point.ply");
    write_cloud(
        &one,
        &[point(0.0, 0.0, 0.0)],
        [(0.2, 0.2), (-12.0, -12.0), (9.0, 9.0)],
    );
    let flat = dir.join("constant_z.ply");
    let points: Vec<Point> = (0..200)
        .map(|i| {
            let t = i as f32 / 199.0 * 2.0 - 1.0;
            point(t, (t * 7.0).sin(), 0.0)
        })
        .collect();
    write_cloud(&flat, &points, [(0.0, 30.0), (-60.0, 0.0), (6.0, 6.0)]);
    let line = dir.join("constant_xy.ply");
    let points: Vec<Point> = (0..50)
        .map(|i| point(0.0, 0.0, i as f32 / 49.0 * 2.0 - 1.0))
        .collect();
    write_cloud(&line, &points, [(1.0, 1.0), (-3.0, -3.0), (0.0, 20.0)]);

    for path in [&one, &flat, &line] {
        let cloud = cloud::load(path).unwrap_or_else(|e| panic!("{e}"));
        for (name, axis) in cloud.meta.axes.named() {
            assert!(axis.problem().is_none(), "{name}");
            assert!(!axis.ticks(6).is_empty(), "{name} has no tick");
        }
        let readings = loudscape::view::pick::point_readings(&cloud.meta.axes, &cloud.points[0]);
        assert!(
            readings.iter().all(|r| !r.value.contains("NaN")),
            "{readings:?}"
        );
    }
    let cloud = cloud::load(&one).unwrap();
    assert_eq!(cloud.meta.axes.z.ticks(6)[0].label, "9.0 dB");
    assert_eq!(cloud.meta.axes.x.value_at(0.0), 0.2);

    let renders: [(&Path, &[&str]); 3] = [
        (&one, &["points", "volume", "surface"]),
        (&flat, &["points", "volume"]),
        (&line, &["points"]),
    ];
    for (path, views) in renders {
        for view in views {
            let png = dir.join(format!(
                "{}_{view}.png",
                path.file_stem().unwrap().to_string_lossy()
            ));
            let output = loudscape(&[
                "render",
                s(path),
                "--view",
                view,
                "--size",
                "160x120",
                "-o",
                s(&png),
            ]);
            assert!(
                output.status.success(),
                "{view} {}: {}",
                path.display(),
                stderr(&output)
            );
            let image = image::open(&png).expect("png").to_rgba8();
            assert_eq!(image.dimensions(), (160, 120));
        }
    }
}

#[test]
fn summaries_go_to_stderr_and_quiet_silences_them() {
    let dir = folder("quiet");
    let png = dir.join("a.png");
    let fixture = repo("data/fixture_song.ply");
    let args = ["render", s(&fixture), "--size", "64x48", "-o", s(&png)];
    // No XDG_RUNTIME_DIR: the command gives Vulkan a private one, so no "is invalid" line.
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(args)
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        output.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&output.stdout)
    );
    assert_eq!(
        stderr(&output),
        format!("wrote {} (64x48 points)\n", png.display())
    );
    let mut quiet = vec!["-q"];
    quiet.extend(args);
    let output = loudscape(&quiet);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        output.stdout.is_empty() && output.stderr.is_empty(),
        "{}",
        stderr(&output)
    );
}

#[test]
fn sigterm_removes_the_partial_png() {
    let dir = folder("sigterm");
    let png = dir.join("big.png");
    let partial = dir.join("big.png.partial");
    let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args([
            "render",
            s(&repo("data/fixture_song.ply")),
            "--size",
            "8192x8192",
            "-o",
            s(&png),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start loudscape");
    // Wait for the PNG encoder to open its temporary file, then stop the command.
    let start = Instant::now();
    while !partial.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("finished ({status}) before the partial file was seen");
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no partial file"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(128 + 15), "{status}");
    assert!(!partial.exists(), "the partial PNG was left behind");
    assert!(!png.exists(), "a PNG was written after SIGTERM");
}

/// A folder the user cannot write into is refused before any work, naming the folder and why
/// (`render` used to draw first and then fail with "cannot write the screenshot"). Root may write
/// anywhere, so as root the command runs as `nobody` (util-linux's setpriv).
#[cfg(unix)]
#[test]
fn a_folder_that_cannot_be_written_is_refused_first() {
    use std::os::unix::fs::PermissionsExt;
    let dir = folder("read_only");
    let locked = dir.join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let binary = PathBuf::from(env!("CARGO_BIN_EXE_loudscape"));
    let out = locked.join("x.png");
    // SAFETY: geteuid has no preconditions.
    let mut command = if unsafe { libc::geteuid() } == 0 {
        let mut as_nobody = Command::new("setpriv");
        as_nobody.args(["--reuid=nobody", "--regid=nogroup", "--clear-groups", "--"]);
        as_nobody.arg(&binary);
        as_nobody
    } else {
        Command::new(&binary)
    };
    let output = command
        .env_remove("XDG_RUNTIME_DIR")
        .arg("render")
        .arg(repo("data/demo_song.ply"))
        .arg("-o")
        .arg(&out)
        .output()
        .expect("run loudscape (setpriv is in util-linux)");
    assert_one_line_error(&output, "cannot write into the folder");
    assert!(
        stderr(&output).contains("permission denied"),
        "{}",
        stderr(&output)
    );
    assert!(!out.exists());
    let _ = std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755));
}
