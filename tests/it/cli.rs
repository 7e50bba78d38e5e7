//! The command line: bad input gets one clear line naming the file, a non-zero exit, no panic
//! and no output file; good input writes the PNG.

use crate::common::{self, assert_success, loudscape};

use std::path::PathBuf;
use std::process::Output;

fn stderr_lines(output: &Output) -> Vec<String> {
    String::from_utf8_lossy(&output.stderr)
        .lines()
        .filter(|l| l.starts_with("loudscape"))
        .map(str::to_string)
        .collect()
}

fn temp(name: &str) -> PathBuf {
    let dir = common::output_dir().join("cli");
    std::fs::create_dir_all(&dir).expect("mkdir");
    let path = dir.join(name);
    let _ = std::fs::remove_file(&path);
    path
}

#[test]
fn render_writes_a_png() {
    let out = temp("demo.png");
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let output = loudscape(&[
        "render",
        repo.join("data/demo_song.ply").to_str().unwrap(),
        "--size",
        "320x200",
        "--camera",
        "-30,20,4",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_success(&output);
    let image = image::open(&out).expect("png").to_rgba8();
    assert_eq!(image.dimensions(), (320, 200));
    assert!(common::coverage(&image) > 0.02);
}

#[test]
fn bad_inputs_fail_cleanly() {
    let bad = temp("not_a_ply.ply");
    std::fs::write(&bad, b"hello world\n").unwrap();
    let truncated = temp("truncated.ply");
    let demo = std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply"))
        .unwrap();
    std::fs::write(&truncated, &demo[..demo.len() / 2]).unwrap();
    let cases: Vec<(String, Vec<String>)> = vec![
        ("missing".into(), vec!["no/such/file.ply".into()]),
        ("not a ply".into(), vec![bad.display().to_string()]),
        ("truncated".into(), vec![truncated.display().to_string()]),
    ];
    for (name, input) in cases {
        let out = temp(&format!("{}.png", name.replace(' ', "_")));
        let mut args = vec!["render".to_string()];
        args.extend(input.iter().cloned());
        args.extend(["-o".to_string(), out.display().to_string()]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let output = loudscape(&refs);
        assert_eq!(output.status.code(), Some(1), "{name}: exit status");
        let lines = stderr_lines(&output);
        assert_eq!(
            lines.len(),
            1,
            "{name}: expected one error line, got {lines:?}"
        );
        assert!(
            lines[0].contains(&input[0]),
            "{name}: error does not name the file: {}",
            lines[0]
        );
        assert!(!lines[0].contains("panicked"), "{name}: {}", lines[0]);
        assert!(!out.exists(), "{name}: an output file was written");
    }
}

#[test]
fn bad_flags_fail_cleanly() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let demo = repo.join("data/demo_song.ply");
    let out = temp("flags.png");
    for flags in [
        vec!["--size", "12"],
        vec!["--camera", "1,2"],
        vec!["--view", "hologram"],
        vec!["--normalize", "tidal"],
        vec!["--normalize", "spotify"], // a song cloud has no songs to normalize
    ] {
        let mut args = vec![
            "render",
            demo.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(flags.iter());
        let output = loudscape(&args);
        assert!(!output.status.success(), "{flags:?} succeeded");
        assert_eq!(
            stderr_lines(&output).len(),
            1,
            "{flags:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(!out.exists());
    }
    // An output folder that does not exist.
    let output = loudscape(&["render", demo.to_str().unwrap(), "-o", "no/such/dir/x.png"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr_lines(&output)[0].contains("no/such/dir"));
}

/// `--normalize` draws a timeline as heard: the loud modern songs of the demo come down to
/// Spotify's -14 LUFS, so the picture changes; `none` is the file as it is.
#[test]
fn render_normalize_shifts_a_timeline() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let demo = repo.join("data/demo_timeline.ply");
    let mut images = Vec::new();
    for preset in ["none", "spotify"] {
        let out = temp(&format!("heard_{preset}.png"));
        let output = loudscape(&[
            "render",
            demo.to_str().unwrap(),
            "--size",
            "320x200",
            "--camera",
            "0,0,4",
            "--normalize",
            preset,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_success(&output);
        images.push(image::open(&out).expect("png").to_rgba8());
    }
    let plain = loudscape(&[
        "render",
        demo.to_str().unwrap(),
        "--size",
        "320x200",
        "--camera",
        "0,0,4",
        "-o",
        temp("heard_default.png").to_str().unwrap(),
    ]);
    assert_success(&plain);
    let default = image::open(temp_path("heard_default.png"))
        .expect("png")
        .to_rgba8();
    assert_eq!(images[0], default, "--normalize none is the file as it is");
    assert_ne!(images[0], images[1], "--normalize spotify moved nothing");
}

fn temp_path(name: &str) -> PathBuf {
    common::output_dir().join("cli").join(name)
}

/// A minimal .npy file (format 1.0) holding `values` as `descr` with the given shape text.
fn npy_bytes(descr: &str, shape: &str, values: &[f32]) -> Vec<u8> {
    let header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}\n");
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes
}

#[test]
fn mesh_reads_npy_fields_and_rejects_bad_ones() {
    // A ball of radius 5 voxels in a 16^3 field, in voxel units (no .json box beside it).
    let n = 16usize;
    let ball: Vec<f32> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            let d = [x, y, z].map(|c| c as f32 - 7.5);
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            (0.5 - (r - 5.0) / 4.0).clamp(0.0, 1.0)
        })
        .collect();
    let field = temp("ball.npy");
    std::fs::write(&field, npy_bytes("<f4", "(16, 16, 16)", &ball)).unwrap();
    let out = temp("ball.obj");
    let output = loudscape(&[
        "mesh",
        field.to_str().unwrap(),
        "--method",
        "dc",
        "--iso",
        "0.5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_success(&output);
    // Every vertex lies on the sphere of radius 5 around the field's centre, in voxel units.
    let text = std::fs::read_to_string(&out).unwrap();
    let radii: Vec<f32> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let p: Vec<f32> = l
                .split_whitespace()
                .take(3)
                .map(|v| v.parse().unwrap())
                .collect();
            ((p[0] - 7.5).powi(2) + (p[1] - 7.5).powi(2) + (p[2] - 7.5).powi(2)).sqrt()
        })
        .collect();
    assert!(radii.len() > 100, "{} vertices", radii.len());
    assert!(radii.iter().all(|r| (r - 5.0).abs() < 0.25), "{radii:?}");

    let cases = [
        (
            "int.npy",
            npy_bytes("<i4", "(2, 2, 2)", &[0.0; 8]),
            "float32",
        ),
        ("flat.npy", npy_bytes("<f4", "(8,)", &[0.0; 8]), "shape"),
        (
            "short.npy",
            npy_bytes("<f4", "(4, 4, 4)", &[0.0; 8]),
            "cut short",
        ),
        (
            "thin.npy",
            npy_bytes("<f4", "(1, 4, 2)", &[0.0; 8]),
            "at least 2",
        ),
        (
            "nan.npy",
            npy_bytes("<f4", "(2, 2, 2)", &[f32::NAN; 8]),
            "not finite",
        ),
    ];
    for (name, bytes, reason) in cases {
        let input = temp(name);
        std::fs::write(&input, bytes).unwrap();
        let out = temp(&format!("{name}.ply"));
        let output = loudscape(&["mesh", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert_eq!(output.status.code(), Some(1), "{name}: exit status");
        let lines = stderr_lines(&output);
        assert_eq!(lines.len(), 1, "{name}: {lines:?}");
        assert!(
            lines[0].contains(name) && lines[0].contains(reason),
            "{name}: {}",
            lines[0]
        );
        assert!(!out.exists(), "{name}: an output file was written");
    }
}

/// `voxelize` writes the array and its description together or not at all (a long name whose
/// temporary would pass 255 bytes included), and `mesh` refuses a description that is not of
/// the array beside it (before: a 96^3 array beside a 64^3 description was meshed in silence).
#[test]
fn voxelize_pairs_appear_together_and_mesh_checks_them() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let cloud = repo.join("data/fixture_song.ply");
    let dir = common::output_dir().join("cli_pairs");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let long = dir.join(format!("{}.npy", "g".repeat(243)));
    let output = loudscape(&[
        "voxelize",
        cloud.to_str().unwrap(),
        "--res",
        "64",
        "-o",
        long.to_str().unwrap(),
    ]);
    assert_success(&output);
    let sidecar = PathBuf::from(format!("{}.json", long.display()));
    assert!(long.is_file() && sidecar.is_file());
    let names = |dir: &PathBuf| -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect()
    };
    assert_eq!(names(&dir).len(), 2, "no temporaries: {:?}", names(&dir));

    // The description cannot be put in place (a folder has its name): no array either.
    let blocked = dir.join("blocked.npy");
    std::fs::create_dir_all(dir.join("blocked.npy.json").join("x")).unwrap();
    let output = loudscape(&[
        "voxelize",
        cloud.to_str().unwrap(),
        "--res",
        "64",
        "-o",
        blocked.to_str().unwrap(),
    ]);
    assert_eq!(output.status.code(), Some(1));
    assert_eq!(
        stderr_lines(&output).len(),
        1,
        "{:?}",
        stderr_lines(&output)
    );
    assert!(
        !blocked.exists(),
        "the array was left without its description"
    );
    assert_eq!(names(&dir).len(), 3, "{:?}", names(&dir));

    // A 16^3 array beside the 64^3 description, and one of another dtype: refused.
    let n = 16usize;
    let field = dir.join("mixed.npy");
    std::fs::write(
        &field,
        npy_bytes("<f4", "(16, 16, 16)", &vec![0.5; n * n * n]),
    )
    .unwrap();
    let mixed_sidecar = dir.join("mixed.npy.json");
    std::fs::copy(&sidecar, &mixed_sidecar).unwrap();
    let out = dir.join("mixed.obj");
    let output = loudscape(&["mesh", field.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(1));
    let lines = stderr_lines(&output);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].contains("mixed.npy.json")
            && lines[0].contains("64x64x64")
            && lines[0].contains("16x16x16"),
        "{}",
        lines[0]
    );
    assert!(!out.exists());
    let mut meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sidecar).unwrap()).unwrap();
    meta["dims"] = serde_json::json!([16, 16, 16]);
    meta["dtype"] = serde_json::json!("<f8");
    std::fs::write(&mixed_sidecar, meta.to_string()).unwrap();
    let output = loudscape(&["mesh", field.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let lines = stderr_lines(&output);
    assert!(lines.len() == 1 && lines[0].contains("dtype"), "{lines:?}");
    assert!(!out.exists());
}

/// The demo timeline's Surface view was "a few specks": a timeline's few hundred points a song
/// in a 224^3 grid smoothed by a song's sigma of 1 leave each point a speck of its own. With a
/// timeline's own smoothing (sigma 4) the surface joins each song's points into one body. The
/// measure: pixels the surface covers beyond the bare box (a render with no surface, isovalue
/// 1), against those the points cover, in the default picture size (the points' discs keep
/// their pixel size, so smaller pictures favour the points). The specks of sigma 1 cover about a fifth of the points'
/// footprint, one body a song over half (the surface keeps the dense core at half the
/// 99th-percentile density, not every stray point): at least 40 % is a shape, not specks.
#[test]
fn a_timelines_surface_shows_the_shape_of_its_songs() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let timeline = repo.join("data/demo_timeline.ply");
    let render = |name: &str, extra: &[&str]| {
        let out = temp(&format!("timeline_{name}.png"));
        let mut args = vec![
            "render",
            timeline.to_str().unwrap(),
            "--size",
            "1280x720",
            "--no-labels",
            "--no-legend",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        assert_success(&loudscape(&args));
        image::open(&out).expect("png").to_rgba8()
    };
    let bare = render("bare", &["--view", "surface", "--iso", "1"]);
    let covered = |image: &image::RgbaImage| {
        image
            .pixels()
            .zip(bare.pixels())
            .filter(|(p, b)| (0..3).any(|c| p[c].abs_diff(b[c]) > 16))
            .count() as f64
    };
    let points = covered(&render("points", &["--view", "points"]));
    let surface = covered(&render("surface", &["--view", "surface"]));
    let specks = covered(&render("specks", &["--view", "surface", "--smooth", "1"]));
    println!(
        "demo timeline at 1280x720: points cover {points} px, the surface {surface} px \
         ({:.0} %), with sigma 1 {specks} px ({:.0} %)",
        100.0 * surface / points,
        100.0 * specks / points
    );
    assert!(points > 1000.0, "the points are drawn: {points} px");
    assert!(
        surface >= 0.4 * points,
        "the surface covers {surface} px of the points' {points}: specks"
    );
    assert!(
        surface > specks,
        "the timeline's own smoothing joins the specks"
    );
}
