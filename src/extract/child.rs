//! Running the extractor: `loudscape-extract song AUDIO -o OUT --progress json` as a child
//! process. Its stdout carries one JSON object a line (`{"stage", "fraction"}`, then `{"done"}`
//! or `{"error"}`); stderr is kept for the reason when it fails without a JSON error. It writes
//! to a temporary name beside the cache file, renamed into place only when it succeeded, so a
//! cancelled or failed run (the child killed, its partial output removed) leaves nothing.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use super::lines::{LinedChild, Next, last_words};
use super::{ExtractError, Progress, Settings};

/// One line of the extractor's `--progress json` output.
#[derive(Debug, PartialEq)]
pub enum Line {
    Progress(Progress),
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
        (Some(stage), Some(fraction)) => Line::Progress(Progress {
            stage: stage.to_string(),
            fraction: (fraction as f32).clamp(0.0, 1.0),
        }),
        _ => Line::Other,
    }
}

/// Removes what a run may leave: the partial cloud and the extractor's atomic-write temporaries
/// beside it (`.NAME.XXXX.tmp`).
fn remove_partial(partial: &Path) {
    let _ = std::fs::remove_file(partial);
    let (Some(dir), Some(stem)) = (partial.parent(), partial.file_name()) else {
        return;
    };
    let stem = stem.to_string_lossy().into_owned();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name != stem && name.contains(&stem) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// Removes partial clouds older than a day beside `output`: left by a run whose app was killed
/// before it could clean up (a live run's partial is minutes old at most).
fn remove_stale_partials(output: &Path) {
    let Some(dir) = output.parent() else { return };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let stale = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > Duration::from_secs(24 * 3600));
        if stale && entry.file_name().to_string_lossy().contains(".partial-") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Runs `extractor` on `audio`, writing `output` when it succeeds; errors name the audio as
/// `name`.
pub fn run(
    extractor: &Path,
    audio: &Path,
    name: &Path,
    output: &Path,
    settings: &Settings,
    cancel: &AtomicBool,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<(), ExtractError> {
    remove_stale_partials(output);
    let mut partial_name = output.file_name().unwrap_or_default().to_os_string();
    partial_name.push(format!(".partial-{}.ply", std::process::id()));
    let partial: PathBuf = output.with_file_name(partial_name);
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
            remove_partial(&partial);
            return Err(ExtractError::Cancelled {
                audio: name.to_owned(),
            });
        }
        match child.next_line() {
            Next::Line(line) => match parse_line(&line) {
                Line::Progress(progress) => on_progress(&progress),
                Line::Done => done = true,
                Line::Error(message) => error = Some(message),
                Line::Other => {}
            },
            Next::Waiting => {}
            Next::Closed => break,
        }
    }
    let (status, stderr_text) = child.finish().map_err(|e| failed(e.to_string()))?;
    if status.success() && done && partial.is_file() {
        return std::fs::rename(&partial, output).map_err(|e| {
            remove_partial(&partial);
            ExtractError::Io {
                path: output.to_owned(),
                reason: format!("cannot move the cloud into the cache: {e}"),
            }
        });
    }
    remove_partial(&partial);
    Err(failed(
        error.unwrap_or_else(|| last_words(&stderr_text, status)),
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
        assert_eq!(parse_line(r#"{"stage": "x"}"#), Line::Other);
    }
}
