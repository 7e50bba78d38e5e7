//! `loudscape bench --only volume`: the volume part measures the INPUT cloud (with its own grid
//! resolution) at the `--size` frame, and a bad size or an unknown part fails with one line
//! before any work.

use std::path::PathBuf;
use std::process::{Command, Output};

fn bench(args: &[&str]) -> (Output, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg("bench")
        .args(args)
        .output()
        .expect("start loudscape");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    (output, stdout)
}

fn fixture(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format");
    path.join(name).to_str().unwrap().to_string()
}

#[test]
fn volume_part_measures_the_input_at_the_given_size() {
    for (file, resolution) in [("song_v2.ply", 128), ("timeline_v2.ply", 224)] {
        let input = fixture(file);
        let (output, stdout) = bench(&[
            "--only", "volume", "--size", "320x200", "--runs", "1", &input,
        ]);
        assert!(
            output.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let song_line = stdout
            .lines()
            .find(|l| l.starts_with("song: "))
            .unwrap_or_else(|| panic!("no song line: {stdout}"));
        assert!(song_line.contains(&input), "{song_line}");
        assert!(
            song_line.contains(&format!("{resolution}^3 grid")),
            "{song_line}"
        );
        assert!(
            stdout.contains(&format!("-> {resolution}^3")),
            "the song's voxelize stage is not at {resolution}^3: {stdout}"
        );
        for state in ["at rest", "moving"] {
            let wanted = format!("volume frame 320x200 ({state}, {resolution}^3");
            assert!(stdout.contains(&wanted), "no '{wanted}': {stdout}");
        }
        assert!(!stdout.contains("1280x720"), "{stdout}");
    }
}

#[test]
fn a_bad_size_fails_with_one_line_before_any_work() {
    let (output, stdout) = bench(&["--only", "volume", "--size", "320by200"]);
    assert!(!output.status.success());
    assert!(stdout.is_empty(), "work started: {stdout}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("320by200"), "{stderr}");
}

/// `--only` takes the parts by name (clap's `ValueEnum`): an unknown one is a usage error
/// (exit 2, one line naming it and the possible values) before any work.
#[test]
fn an_unknown_part_is_a_usage_error() {
    let (output, stdout) = bench(&["--only", "points,lighting"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stdout.is_empty(), "work started: {stdout}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    for word in ["lighting", "points", "volume", "surface"] {
        assert!(lines[0].contains(word), "no {word}: {}", lines[0]);
    }
    assert!(!stderr.contains("panicked"));
}
