//! `loudscape video` trusted with any input (docs/RELIABILITY.md, "The video"): the sound is the
//! audio file named, never the source a cached cloud recorded; a cloud's source is checked
//! against the cloud; every name a file system allows reaches ffmpeg as that file and nothing
//! else (`file:` names, colons, a leading dash, bytes that are not UTF-8), and nothing is
//! written but the output; a run killed outright (SIGKILL) leaves a temporary that the next
//! run removes; `--start` past the song's end says so. The songs are made here (WAV) and
//! extracted by the project's extractor (.venv, `make venv`); needs ffmpeg.

// Names that are not UTF-8 and SIGKILL are Unix's: elsewhere those cases are left out, and
// what they need goes unused.
#![cfg_attr(not(unix), allow(unused_imports, unused_mut))]

use crate::common::{
    self, assert_success, chord_with_clicks, decode_audio, extractor, fresh_dir, repo, write_wav,
};

use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const RATE: u32 = 22_050;

fn demo() -> PathBuf {
    repo().join("data/demo_song.ply")
}

/// Song B (song A is `chord_with_clicks`): another chord, clicks at other times.
fn song_b(i: usize) -> f32 {
    let t = i as f32 / RATE as f32;
    let chord: f32 = [196.0f32, 311.1, 466.2, 622.3]
        .iter()
        .map(|f| (std::f32::consts::TAU * f * t).sin())
        .sum();
    let click = if (i + 3_000) % 8_111 < 40 { 0.6 } else { 0.0 };
    0.15 * chord + click
}

/// The best normalized correlation of `sound` (a passage from `start_s`) with `source`, over
/// lags of +-10 ms (AAC's framing), away from the passage's edges.
fn correlation(sound: &[f32], source: &[f32], start_s: f64) -> f64 {
    let margin = 2_000usize;
    assert!(sound.len() > 2 * margin + 1_000, "{} samples", sound.len());
    let window = &sound[margin..sound.len() - margin];
    let first = (start_s * f64::from(RATE)).round() as i64 + margin as i64;
    let energy = |s: &[f32]| s.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>().sqrt();
    (-220i64..=220)
        .filter_map(|lag| {
            let at = usize::try_from(first + lag).ok()?;
            let other = source.get(at..at + window.len())?;
            let dot: f64 = window
                .iter()
                .zip(other)
                .map(|(a, b)| f64::from(*a) * f64::from(*b))
                .sum();
            Some(dot / (energy(window) * energy(other)).max(1e-12))
        })
        .fold(f64::MIN, f64::max)
}

/// Runs `loudscape` in `dir` with the song cache in `dir/cache` and the project's extractor.
fn run_in(dir: &Path, args: &[&OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .args(args)
        .current_dir(dir)
        .env("LOUDSCAPE_CACHE_DIR", dir.join("cache"))
        .env("LOUDSCAPE_EXTRACT", extractor())
        .output()
        .expect("start loudscape")
}

/// A short, small video of `input` into `output` (both as given, relative to `dir`).
fn video(dir: &Path, input: &OsStr, output: &OsStr, extra: &[&str]) -> Output {
    let mut args: Vec<&OsStr> = ["video", "--size", "160x90", "--fps", "10", "--no-strip"]
        .iter()
        .map(OsStr::new)
        .collect();
    args.extend(["--progress", "none"].iter().map(OsStr::new));
    args.extend(extra.iter().map(OsStr::new));
    args.push(input);
    let mut flag = OsString::from("--output=");
    flag.push(output);
    args.push(&flag);
    run_in(dir, &args)
}

/// The names in `dir` but the song cache, sorted, as bytes shown lossily.
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "cache")
        .collect();
    names.sort();
    names
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Fails unless `output` failed with one line holding every one of `needles`.
fn assert_refused(output: &Output, needles: &[&str]) {
    let err = stderr(output);
    assert!(!output.status.success(), "it succeeded: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    for needle in needles {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
}

/// The case: `mine.wav` and `backup.wav` the same song, `mine.wav` rendered (so
/// cached with source.path `mine.wav`), then overwritten with another song: the video of
/// `backup.wav` sounds like `backup.wav`.
#[test]
fn the_sound_is_the_audio_file_named_not_the_source_its_cached_cloud_recorded() {
    let dir = fresh_dir("video_trust_cached_source");
    let (mine, backup) = (dir.join("mine.wav"), dir.join("backup.wav"));
    write_wav(&mine, 3.0, RATE, chord_with_clicks);
    std::fs::copy(&mine, &backup).unwrap();
    let png = dir.join("mine.png");
    assert_success(&run_in(
        &dir,
        &[
            OsStr::new("render"),
            mine.as_os_str(),
            "-o".as_ref(),
            png.as_os_str(),
        ],
    ));
    write_wav(&mine, 3.0, RATE, song_b);
    let mp4 = dir.join("backup.mp4");
    let output = video(
        &dir,
        backup.as_os_str(),
        mp4.as_os_str(),
        &["--start", "0.5", "--end", "2.5"],
    );
    assert_success(&output);
    let sound = decode_audio(&mp4, RATE);
    let with_backup = correlation(&sound, &decode_audio(&backup, RATE), 0.5);
    let with_mine = correlation(&sound, &decode_audio(&mine, RATE), 0.5);
    eprintln!(
        "the sound correlates {with_backup:.3} with backup.wav, {with_mine:.3} with mine.wav"
    );
    assert!(
        with_backup > 0.9 && with_mine < 0.5,
        "the sound correlates {with_backup:.3} with backup.wav, {with_mine:.3} with mine.wav"
    );
    // With mine.wav gone, the video of backup.wav needs nothing of it.
    std::fs::remove_file(&mine).unwrap();
    std::fs::remove_file(&mp4).unwrap();
    assert_success(&video(
        &dir,
        backup.as_os_str(),
        mp4.as_os_str(),
        &["--end", "1"],
    ));
}

/// A cloud's source is the file it names, as long as it is the audio the cloud was made from:
/// another length or sample rate, or no file, is one line naming the cloud, the source and
/// --silent.
#[test]
fn a_clouds_source_that_changed_or_went_is_refused_in_one_line() {
    let dir = fresh_dir("video_trust_ply_source");
    let (wav, ply) = (dir.join("song.wav"), dir.join("song.ply"));
    write_wav(&wav, 3.0, RATE, chord_with_clicks);
    let made = Command::new(extractor())
        .args(["song", "-q"])
        .arg(&wav)
        .arg("-o")
        .arg(&ply)
        .output()
        .unwrap();
    assert_success(&made);
    let mp4 = dir.join("song.mp4");
    let (p, m) = (ply.as_os_str(), mp4.as_os_str());
    // The source as it was: its sound.
    assert_success(&video(&dir, p, m, &["--start", "1", "--end", "2.5"]));
    let matched = correlation(&decode_audio(&mp4, RATE), &decode_audio(&wav, RATE), 1.0);
    assert!(matched > 0.9, "correlation {matched:.3}");
    std::fs::remove_file(&mp4).unwrap();
    let name = wav.display().to_string();
    let changed = [
        "is not the audio the cloud was made from",
        "song.ply",
        &name,
        "--silent",
    ];
    // Another song of another length in its place.
    write_wav(&wav, 2.0, RATE, song_b);
    let output = video(&dir, p, m, &["--end", "1"]);
    assert_refused(&output, &changed);
    assert!(stderr(&output).contains("2.000 s long, the cloud's 3.000 s"));
    // The same length at another sample rate.
    write_wav(&wav, 3.0, 16_000, chord_with_clicks);
    let output = video(&dir, p, m, &["--end", "1"]);
    assert_refused(&output, &changed);
    assert!(stderr(&output).contains("16000 Hz, the cloud's 22050 Hz"));
    // Gone.
    std::fs::remove_file(&wav).unwrap();
    let output = video(&dir, p, m, &["--end", "1"]);
    assert_refused(&output, &["song.ply", "cannot be found", "--silent"]);
    assert!(!mp4.exists());
    // --silent is the way out it names.
    assert_success(&video(&dir, p, m, &["--end", "1", "--silent"]));
    assert!(mp4.exists());
}

/// Outputs whose names ffmpeg would take for a URL, a protocol or an option, or could not
/// pass on: each is written, as a whole video, under exactly its name, and nothing else is.
#[test]
fn odd_output_names_are_written_as_named_and_nothing_else_is() {
    let dir = fresh_dir("video_trust_output_names");
    let mut names: Vec<OsString> = ["file:f.mp4", "a:b.mp4", "-x.mp4", "pipe:1.mp4"]
        .map(OsString::from)
        .to_vec();
    #[cfg(unix)]
    names.push(<OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(b"v\xff\xe9.mp4").into());
    for name in &names {
        let output = video(&dir, demo().as_os_str(), name, &["--end", "0.5"]);
        assert_success(&output);
        let path = dir.join(name);
        let sound = decode_audio(&path, RATE);
        assert!(
            sound.len().abs_diff(RATE as usize / 2) < 2_000,
            "{}: {} samples of sound",
            path.display(),
            sound.len()
        );
    }
    let mut expected: Vec<String> = names.iter().map(|n| n.to_string_lossy().into()).collect();
    expected.sort();
    assert_eq!(names_in(&dir), expected, "files but the videos named");
}

/// Sources whose names ffmpeg would take for another file: `file:c.wav` beside `c.wav` (as
/// a cloud records it when extracted with that relative name, and as the input itself), and
/// a name that is not UTF-8: the video's sound is theirs.
#[test]
fn odd_source_names_give_their_own_sound() {
    let dir = fresh_dir("video_trust_source_names");
    write_wav(&dir.join("c.wav"), 3.0, RATE, song_b);
    let url_named = OsString::from("file:c.wav");
    write_wav(&dir.join(&url_named), 3.0, RATE, chord_with_clicks);
    // A cloud whose source.path is `file:c.wav`, relative, as given to the extractor.
    let made = Command::new(extractor())
        .args(["song", "-q", "file:c.wav", "-o", "url.ply"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_success(&made);
    let mut cases = vec![
        (OsString::from("url.ply"), url_named.clone()),
        (url_named.clone(), url_named.clone()),
    ];
    #[cfg(unix)]
    {
        let odd: OsString =
            <OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(b"caf\xe9 \xff.wav").into();
        // Its own song (another length: not the cached cloud of `file:c.wav`).
        write_wav(&dir.join(&odd), 3.5, RATE, chord_with_clicks);
        cases.push((odd.clone(), odd));
    }
    for (k, (input, source)) in cases.iter().enumerate() {
        let mp4 = OsString::from(format!("out{k}.mp4"));
        let output = video(&dir, input, &mp4, &["--start", "0.5", "--end", "2.5"]);
        assert_success(&output);
        let sound = decode_audio(&dir.join(&mp4), RATE);
        let own = correlation(&sound, &decode_audio(&dir.join(source), RATE), 0.5);
        let other = correlation(&sound, &decode_audio(&dir.join("c.wav"), RATE), 0.5);
        assert!(
            own > 0.9 && other < 0.5,
            "{}: correlation {own:.3} with its source, {other:.3} with c.wav",
            input.to_string_lossy()
        );
    }
}

/// SIGKILL gives no chance to clean up: the temporary (named with the killed run's PID) stays,
/// and the next run into the folder removes it, leaving files of living runs and files that
/// only look alike.
#[cfg(unix)]
#[test]
fn a_run_killed_outright_leaves_a_temporary_the_next_run_removes() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    use std::time::{Duration, Instant};

    let dir = fresh_dir("video_trust_sigkill");
    let killed = dir.join("killed.mp4");
    let mut child = Command::new(env!("CARGO_BIN_EXE_loudscape"))
        .arg("video")
        .arg(demo())
        .args(["--size", "320x180", "--progress", "json", "-o"])
        .arg(&killed)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().expect("a progress line").unwrap();
    assert!(first.contains("\"frame\""), "{first}");
    let partials = || -> Vec<PathBuf> {
        names_in(&dir)
            .iter()
            .filter(|n| n.starts_with("killed.mp4.") && n.ends_with(".partial.mp4"))
            .map(|n| dir.join(n))
            .collect()
    };
    let left = partials();
    assert_eq!(left.len(), 1, "{:?}", names_in(&dir));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    // Its encoder goes with it (or finishes): wait until none names the file.
    let deadline = Instant::now() + Duration::from_secs(30);
    while common::processes_naming(&left[0]) > 0 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(common::processes_naming(&left[0]), 0, "ffmpeg still runs");
    assert_eq!(partials(), left, "the killed run's temporary");
    // A living run's temporary (this test's PID) and a user's file that only looks alike.
    let living = dir.join(format!(
        "other.mp4.loudscape-{}.partial.mp4",
        std::process::id()
    ));
    let lookalike = dir.join("holiday.2019.partial.mp4");
    std::fs::write(&living, b"in progress").unwrap();
    std::fs::write(&lookalike, b"mine").unwrap();
    let output = video(
        &dir,
        demo().as_os_str(),
        OsStr::new("next.mp4"),
        &["--end", "0.3"],
    );
    assert_success(&output);
    assert_eq!(
        names_in(&dir),
        [
            "holiday.2019.partial.mp4".to_string(),
            "next.mp4".into(),
            living.file_name().unwrap().to_string_lossy().into(),
        ],
        "the killed run's temporary is left"
    );
}

/// `--start` past the end without `--end`: the message is about `--start`.
#[test]
fn start_past_the_songs_end_says_so() {
    let dir = fresh_dir("video_trust_start");
    let output = video(
        &dir,
        demo().as_os_str(),
        OsStr::new("late.mp4"),
        &["--start", "100"],
    );
    assert_refused(&output, &["--start 100 is past the song's end ("]);
    assert!(!stderr(&output).contains("--end"), "{}", stderr(&output));
    assert_eq!(names_in(&dir), Vec::<String>::new());
}
