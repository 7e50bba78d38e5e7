//! Running the extractor: `loudscape-extract song AUDIO -o OUT --progress json` as a child
//! process. Its stdout carries one JSON object a line (`{"stage", "fraction"}`, some with the
//! `points` written so far (see [`super::preview`]), then `{"done"}` or `{"error"}`); stderr is read as it comes, its tail kept for the reason when it fails
//! without a JSON error and its `warning:` lines passed on (an extractor that only prints its
//! warnings is still heard). It writes into a private folder the caller removes, so a cancelled,
//! failed or interrupted run (the child killed, with its process group) leaves nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use super::lines::{LinedChild, Next, last_words};
use super::preview::PointsSoFar;
use super::{ExtractError, Progress, Settings};

/// One line of the extractor's `--progress json` output.
#[derive(Debug, PartialEq)]
pub enum Line {
    Progress(Progress),
    /// A progress line with the `points` member: the rows in the body file so far.
    Points(Progress, PointsSoFar),
    Done,
    Error(String),
    /// Not a line of the protocol (ignored).
    Other,
}

/// Parses one line of `--progress json` output.
pub fn parse_line(text: &str) -> Line {
    let Ok(value) = serde_json::from_str::<serde_json::Value>(text) else {
        return Line::Other;
    };
    if let Some(message) = value.get("error").and_then(|v| v.as_str()) {
        return Line::Error(message.to_string());
    }
    if value.get("done").is_some() {
        return Line::Done;
    }
    match (
        value.get("stage").and_then(|v| v.as_str()),
        value.get("fraction").and_then(|v| v.as_f64()),
    ) {
        (Some(stage), Some(fraction)) => {
            let progress = Progress {
                stage: stage.to_string(),
                fraction: (fraction as f32).clamp(0.0, 1.0),
            };
            // A `points` member the window cannot use leaves a plain progress line.
            match PointsSoFar::parse(&value) {
                Some(points) => Line::Points(progress, points),
                None => Line::Progress(progress),
            }
        }
        _ => Line::Other,
    }
}

/// Removes what runs of an app that were killed before they could clean up (SIGKILL, a power
/// cut) left in `cache`: their private extraction folders (`.extract-PID-N`) and the partial
/// clouds of older versions (`*.partial-PID.ply`). One whose process is gone goes at once; one
/// whose process still runs (this one's too) stays; where that cannot be told (no PID in the
/// name, or not Unix), after a day (a live run's is minutes old at most).
pub fn remove_stale_partials(cache: &Path) {
    let Ok(entries) = std::fs::read_dir(cache) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let scratch = name.starts_with(&format!("{SCRATCH_PREFIX}-"));
        let partial = name.contains(".partial-");
        if !(scratch || partial) {
            continue;
        }
        let pid = if scratch {
            name[SCRATCH_PREFIX.len() + 1..]
                .split('-')
                .next()
                .and_then(|p| p.parse::<u32>().ok())
        } else {
            name.rsplit_once(".partial-")
                .and_then(|(_, rest)| rest.strip_suffix(".ply"))
                .and_then(|p| p.parse::<u32>().ok())
        };
        let stale = match pid.and_then(crate::files::process_runs) {
            Some(runs) => !runs,
            None => entry
                .metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|age| age > Duration::from_secs(24 * 3600)),
        };
        if stale && scratch {
            let _ = std::fs::remove_dir_all(entry.path());
        } else if stale {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// The name of the private folder an extraction writes into (`.extract-PID-N`).
pub const SCRATCH_PREFIX: &str = ".extract";

/// A warning line of the extractor's stderr without the audio's path it starts with (the
/// reader names the file itself), as one line.
fn said(warning: &str, audio: &Path) -> String {
    let prefix = format!("{}: ", audio.display());
    let python = format!("{}: ", python_spelling(audio));
    let message = warning
        .strip_prefix(&prefix)
        .or_else(|| warning.strip_prefix(&python))
        .unwrap_or(warning);
    crate::data::cloud::one_line(message)
}

/// How Python prints `path` on stderr: a byte that is not UTF-8 as `\udcXX` (its file-system
/// encoding's surrogate escape, written out by stderr's backslashreplace), so a warning about a
/// file whose name is not UTF-8 is recognised as the same one the cloud's metadata holds.
#[cfg(unix)]
fn python_spelling(path: &Path) -> String {
    use std::os::unix::ffi::OsStrExt;
    let mut out = String::new();
    for chunk in path.as_os_str().as_bytes().utf8_chunks() {
        out.push_str(chunk.valid());
        for byte in chunk.invalid() {
            out.push_str(&format!("\\udc{byte:02x}"));
        }
    }
    out
}

#[cfg(not(unix))]
fn python_spelling(path: &Path) -> String {
    path.display().to_string()
}

/// Runs `extractor` on `audio`, writing its cloud into `scratch` (a private folder: whatever the
/// run leaves there goes with it); errors name the audio as `name`. Returns the cloud's path and
/// the warnings the extractor printed on stderr (without the audio's path). `on_points` hears
/// each line's points so far (the caller reads them: see [`super::preview::Preview`]).
#[allow(clippy::too_many_arguments)]
pub fn run(
    extractor: &Path,
    audio: &Path,
    name: &Path,
    scratch: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
    on_points: &mut dyn FnMut(&PointsSoFar),
) -> Result<(PathBuf, Vec<String>), ExtractError> {
    let partial = scratch.join("cloud.ply");
    let failed = |reason: String| ExtractError::Failed {
        audio: name.to_owned(),
        reason,
    };
    let child = LinedChild::spawn(
        Command::new(extractor)
            .arg("song")
            .arg(audio)
            .arg("-o")
            .arg(&partial)
            .args(settings.arguments())
            .args(["--progress", "json"]),
    )
    .map_err(|e| failed(format!("cannot start {}: {e}", extractor.display())))?;
    let mut done = false;
    let mut error = None;
    loop {
        if cancel.load(Ordering::Relaxed) {
            child.kill();
            return Err(ExtractError::Cancelled {
                audio: name.to_owned(),
            });
        }
        match child.next_line() {
            Next::Line(line) => match parse_line(&line) {
                Line::Progress(progress) => on_progress(&progress),
                Line::Points(progress, points) => {
                    on_progress(&progress);
                    on_points(&points);
                }
                Line::Done => done = true,
                Line::Error(message) => error = Some(message),
                Line::Other => {}
            },
            Next::Waiting => {}
            Next::Closed => break,
        }
    }
    let (status, stderr) = child.finish().map_err(|e| failed(e.to_string()))?;
    if status.success() && done && partial.is_file() {
        let warnings = stderr.warnings.iter().map(|w| said(w, audio)).collect();
        return Ok((partial, warnings));
    }
    Err(failed(
        error.unwrap_or_else(|| last_words(&stderr.tail, status)),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protocol_lines_parse() {
        assert_eq!(
            parse_line(r#"{"stage": "hpss", "fraction": 0.23, "message": "x"}"#),
            Line::Progress(Progress {
                stage: "hpss".into(),
                fraction: 0.23
            })
        );
        assert_eq!(parse_line(r#"{"done": "out.ply"}"#), Line::Done);
        assert_eq!(
            parse_line(r#"{"error": "x.wav: silent"}"#),
            Line::Error("x.wav: silent".into())
        );
        assert_eq!(parse_line("not json"), Line::Other);
        assert_eq!(parse_line(r#"{"points": {"rows": 3}}"#), Line::Other);
        assert_eq!(parse_line(r#"{"stage": "x"}"#), Line::Other);
    }

    fn axes() -> serde_json::Value {
        serde_json::json!({
            "x": {"label": "time", "unit": "s", "min": 0.0, "max": 180.0},
            "y": {"label": "level", "unit": "dB", "min": -80.0, "max": 0.0},
            "z": {"label": "frequency", "unit": "Hz", "min": 0.0, "max": 22050.0, "scale": "linear"},
            "scalar": {"label": "A-weighted level", "unit": "dB", "min": -90.0, "max": 0.0},
            "hp": {"label": "harmonic-percussive ratio", "unit": "", "min": 0.0, "max": 1.0}
        })
    }

    #[test]
    fn a_points_line_parses_with_its_progress() {
        let line = serde_json::json!({
            "stage": "hpss", "fraction": 0.4, "message": "points",
            "points": {"path": "/cache/.extract-1-0/.cloud.ply.points-77", "rows": 12345,
                       "axes": axes(), "mode": "song", "freq_scale": "log"}
        });
        assert_eq!(
            parse_line(&line.to_string()),
            Line::Points(
                Progress {
                    stage: "hpss".into(),
                    fraction: 0.4
                },
                PointsSoFar {
                    path: "/cache/.extract-1-0/.cloud.ply.points-77".into(),
                    rows: 12345,
                    axes: axes(),
                    freq_scale: "log".into(),
                }
            )
        );
    }

    #[test]
    fn a_points_member_the_window_cannot_use_leaves_the_progress() {
        let progress = Line::Progress(Progress {
            stage: "hpss".into(),
            fraction: 0.5,
        });
        for points in [
            serde_json::json!({"path": "/p", "rows": 1, "axes": axes(), "mode": "timeline"}),
            serde_json::json!({"path": "/p", "rows": -1, "axes": axes(), "mode": "song"}),
            serde_json::json!({"path": "/p", "rows": 1, "axes": [], "mode": "song"}),
            serde_json::json!({"rows": 1, "axes": axes(), "mode": "song"}),
            serde_json::json!("nothing"),
        ] {
            let line = serde_json::json!({"stage": "hpss", "fraction": 0.5, "points": points});
            assert_eq!(parse_line(&line.to_string()), progress, "{points}");
        }
    }

    /// Leftovers named by a PID: those of a process that is gone are removed, those of a running
    /// one (this test's) and names without a PID (recent) stay; other files are not touched.
    #[cfg(unix)]
    #[test]
    fn leftovers_go_with_their_process() {
        let dir = std::env::temp_dir().join(format!("loudscape-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut gone = std::process::Command::new("true").spawn().unwrap();
        let (dead, live) = (gone.id(), std::process::id());
        gone.wait().unwrap();
        let names = [
            format!("{SCRATCH_PREFIX}-{dead}-3"),
            format!("{SCRATCH_PREFIX}-{live}-0"),
            format!("{SCRATCH_PREFIX}-x-0"),
            format!("song.partial-{dead}.ply"),
            format!("song.partial-{live}.ply"),
            format!("KEY-{dead}.ply"),
        ];
        for name in &names[..3] {
            std::fs::create_dir(dir.join(name)).unwrap();
        }
        for name in &names[3..] {
            std::fs::write(dir.join(name), b"ply").unwrap();
        }
        remove_stale_partials(&dir);
        let kept: Vec<bool> = names.iter().map(|n| dir.join(n).exists()).collect();
        assert_eq!(kept, [false, true, true, false, true, true], "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn printed_warnings_lose_the_audio_path_only() {
        let audio = Path::new("/music/a.flac");
        assert_eq!(
            said("/music/a.flac: decoded 1.49 s of the 4.00 s", audio),
            "decoded 1.49 s of the 4.00 s"
        );
        assert_eq!(said("other.flac: odd", audio), "other.flac: odd");
    }

    #[cfg(unix)]
    #[test]
    fn a_name_that_is_not_utf8_is_recognised_as_python_prints_it() {
        use std::os::unix::ffi::OsStrExt;
        let audio = Path::new(std::ffi::OsStr::from_bytes(b"/music/caf\xe9.flac"));
        assert_eq!(
            said(
                "/music/caf\\udce9.flac: decoded 1.49 s of the 4.00 s",
                audio
            ),
            "decoded 1.49 s of the 4.00 s"
        );
    }
}
