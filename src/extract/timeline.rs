//! Timelines from the app: `loudscape-extract timeline` as a child process, in two steps. First
//! `--list-songs --progress json` (the songs under the chosen files and folders, with the year,
//! title and artist of their tags), so that the window can ask for the years the tags lack;
//! then the build, from a manifest (path, year, title, artist: every song with a year, the typed
//! ones included) or with `--x-by order` (no years needed), with `--progress json`: one line a
//! song as each finishes. The timeline lands in the cloud cache under a key of the extractor's
//! version, the songs (path, size, modification time, year) and the mode, so building the same
//! timeline again opens at once; the extractor's own per-song cache makes a changed one quick.

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};

use sha2::{Digest, Sha256};

use super::Extractor;
use super::lines::{LinedChild, Next, last_words};

/// A song found for a timeline, with its tags.
#[derive(Clone, Debug, PartialEq)]
pub struct SongTags {
    pub path: PathBuf,
    pub year: Option<i32>,
    pub title: String,
    pub artist: String,
    /// Why its tags could not be read (the build will say so again and skip it).
    pub tag_error: Option<String>,
}

/// One line of `loudscape-extract timeline --progress json` (or `--list-songs`).
#[derive(Debug, PartialEq)]
pub enum Line {
    Listed(SongTags),
    SongDone {
        song: PathBuf,
        done: usize,
        total: usize,
        failed: Option<String>,
    },
    LeftOut {
        without_year: Vec<PathBuf>,
        failed: Vec<(PathBuf, String)>,
    },
    Done,
    Error(String),
    Other,
}

/// Parses one line of the timeline's JSON output.
pub fn parse_line(text: &str) -> Line {
    let Ok(value) = serde_json::from_str::<serde_json::Value>(text) else {
        return Line::Other;
    };
    let text_of = |key: &str| value.get(key).and_then(|v| v.as_str()).map(str::to_string);
    if let Some(message) = text_of("error") {
        return Line::Error(message);
    }
    if value.get("done").is_some() {
        return Line::Done;
    }
    if let Some(without) = value.get("without_year").and_then(|v| v.as_array()) {
        let failed = value
            .get("failed")
            .and_then(|v| v.as_object())
            .map(|m| {
                m.iter()
                    .map(|(k, v)| (PathBuf::from(k), v.as_str().unwrap_or("").to_string()))
                    .collect()
            })
            .unwrap_or_default();
        return Line::LeftOut {
            without_year: without
                .iter()
                .filter_map(|v| v.as_str().map(PathBuf::from))
                .collect(),
            failed,
        };
    }
    let Some(song) = text_of("song").map(PathBuf::from) else {
        return Line::Other;
    };
    if let (Some(done), Some(total)) = (
        value.get("songs_done").and_then(|v| v.as_u64()),
        value.get("songs_total").and_then(|v| v.as_u64()),
    ) {
        return Line::SongDone {
            song,
            done: done as usize,
            total: total as usize,
            failed: text_of("failed"),
        };
    }
    Line::Listed(SongTags {
        path: song,
        year: value.get("year").and_then(|v| v.as_i64()).map(|y| y as i32),
        title: text_of("title").unwrap_or_default(),
        artist: text_of("artist").unwrap_or_default(),
        tag_error: text_of("tag_error"),
    })
}

/// Runs the extractor with `args`, handing every stdout line to `on_line`; kills it when
/// `cancel` is set (`Err("cancelled")`). Errors are the extractor's own last words.
pub fn run_lines(
    extractor: &Path,
    args: &[OsString],
    cancel: &AtomicBool,
    on_line: &mut dyn FnMut(Line),
) -> Result<(), String> {
    let child = LinedChild::spawn(Command::new(extractor).args(args))
        .map_err(|e| format!("cannot start {}: {e}", extractor.display()))?;
    let (mut done, mut error) = (false, None);
    loop {
        if cancel.load(Ordering::Relaxed) {
            child.kill();
            return Err("cancelled".into());
        }
        match child.next_line() {
            Next::Line(text) => match parse_line(&text) {
                Line::Done => done = true,
                Line::Error(message) => error = Some(message),
                line => on_line(line),
            },
            Next::Waiting => {}
            Next::Closed => break,
        }
    }
    let (status, stderr_text) = child.finish().map_err(|e| e.to_string())?;
    if done && error.is_none() {
        return Ok(());
    }
    Err(error.unwrap_or_else(|| last_words(&stderr_text.tail, status)))
}

/// The songs under `inputs` with their tags (`timeline --list-songs`).
pub fn list_songs(
    extractor: &Extractor,
    inputs: &[PathBuf],
    cancel: &AtomicBool,
) -> Result<Vec<SongTags>, String> {
    let mut args: Vec<OsString> = vec!["timeline".into()];
    args.extend(inputs.iter().map(|p| p.as_os_str().to_owned()));
    args.extend(["--list-songs".into(), "--progress".into(), "json".into()]);
    let mut songs = Vec::new();
    run_lines(&extractor.path, &args, cancel, &mut |line| {
        if let Line::Listed(song) = line {
            songs.push(song);
        }
    })?;
    Ok(songs)
}

/// One CSV field, quoted (the manifest's paths and titles may hold commas and quotes).
fn csv_field(text: &str) -> String {
    format!("\"{}\"", text.replace('"', "\"\""))
}

/// The manifest of `songs` (path, year, title, artist; absolute paths).
pub fn manifest_text(songs: &[(PathBuf, i32, String, String)]) -> String {
    let mut text = String::from("path,year,title,artist\n");
    for (path, year, title, artist) in songs {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.clone());
        let _ = writeln!(
            text,
            "{},{year},{},{}",
            csv_field(&path.to_string_lossy()),
            csv_field(title),
            csv_field(artist)
        );
    }
    text
}

/// The cache key of a timeline: the extractor's version, the mode and each song's path, size,
/// modification time and year.
pub fn key(version: &str, order: bool, songs: &[(PathBuf, Option<i32>)]) -> String {
    let mut hasher = Sha256::new();
    hasher.update(b"loudscape-timeline-cache 1\0");
    hasher.update(version.as_bytes());
    hasher.update([0, u8::from(order)]);
    for (path, year) in songs {
        let meta = std::fs::metadata(path).ok();
        let modified = meta
            .as_ref()
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        hasher.update(path.to_string_lossy().as_bytes());
        hasher.update([0]);
        hasher.update(meta.map_or(0, |m| m.len()).to_le_bytes());
        hasher.update(modified.to_le_bytes());
        hasher.update(year.unwrap_or(0).to_le_bytes());
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// How to place the songs.
pub enum Placement {
    /// By year, from a manifest of every song with a year.
    ByYear(Vec<(PathBuf, i32, String, String)>),
    /// In order, each an equal span (`--x-by order`): no years needed.
    InOrder(Vec<PathBuf>),
}

/// Builds the timeline into the cache folder `dir` (or finds it there); `on_song` hears every
/// finished song. Returns the cloud's path and whether it came from the cache.
pub fn build(
    extractor: &Extractor,
    placement: &Placement,
    dir: &Path,
    cancel: &AtomicBool,
    on_song: &mut dyn FnMut(Line),
) -> Result<(PathBuf, bool), String> {
    let (order, songs): (bool, Vec<(PathBuf, Option<i32>)>) = match placement {
        Placement::ByYear(songs) => (
            false,
            songs
                .iter()
                .map(|(p, y, _, _)| (p.clone(), Some(*y)))
                .collect(),
        ),
        Placement::InOrder(paths) => (true, paths.iter().map(|p| (p.clone(), None)).collect()),
    };
    // 64 bits of the key name the file: short enough to read in the panel.
    let key = key(&extractor.version, order, &songs)[..16].to_string();
    let output = dir.join(format!("timeline-{key}.ply"));
    if output.is_file() {
        return Ok((output, true));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("{}: cannot create the cache folder: {e}", dir.display()))?;
    let partial = dir.join(format!("timeline-{key}.partial-{}.ply", std::process::id()));
    let manifest = dir.join(format!(
        "timeline-{key}.manifest-{}.csv",
        std::process::id()
    ));
    let mut args: Vec<OsString> = vec!["timeline".into()];
    match placement {
        Placement::ByYear(songs) => {
            std::fs::write(&manifest, manifest_text(songs))
                .map_err(|e| format!("{}: cannot write the manifest: {e}", manifest.display()))?;
            args.extend(["--manifest".into(), manifest.clone().into_os_string()]);
        }
        Placement::InOrder(paths) => {
            args.extend(paths.iter().map(|p| p.as_os_str().to_owned()));
            args.extend(["--x-by".into(), "order".into()]);
        }
    }
    args.extend(["-o".into(), partial.clone().into_os_string()]);
    args.extend(["--progress".into(), "json".into()]);
    let result = run_lines(&extractor.path, &args, cancel, on_song);
    let _ = std::fs::remove_file(&manifest);
    // On disk before it is renamed into place, so a power cut leaves no half timeline.
    let moved = result.and_then(|()| {
        std::fs::File::open(&partial)
            .and_then(|f| f.sync_all())
            .and_then(|()| std::fs::rename(&partial, &output))
            .map(|()| crate::files::sync_parent(&output))
            .map_err(|e| {
                format!(
                    "{}: cannot move the timeline into the cache: {}",
                    output.display(),
                    crate::files::write_reason(&e)
                )
            })
    });
    if let Err(message) = moved {
        let _ = std::fs::remove_file(&partial);
        return Err(message);
    }
    Ok((output, false))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeline_lines_parse() {
        assert_eq!(
            parse_line(
                r#"{"song": "a.flac", "year": null, "title": "T", "artist": "", "tag_error": null}"#
            ),
            Line::Listed(SongTags {
                path: "a.flac".into(),
                year: None,
                title: "T".into(),
                artist: String::new(),
                tag_error: None,
            })
        );
        assert_eq!(
            parse_line(
                r#"{"stage": "songs", "fraction": 0.5, "song": "b.flac", "songs_done": 1, "songs_total": 2, "failed": "silent"}"#
            ),
            Line::SongDone {
                song: "b.flac".into(),
                done: 1,
                total: 2,
                failed: Some("silent".into())
            }
        );
        assert_eq!(
            parse_line(r#"{"without_year": ["c.flac"], "failed": {"b.flac": "silent"}}"#),
            Line::LeftOut {
                without_year: vec!["c.flac".into()],
                failed: vec![("b.flac".into(), "silent".into())]
            }
        );
        assert_eq!(parse_line(r#"{"done": ""}"#), Line::Done);
        assert_eq!(parse_line(r#"{"error": "x"}"#), Line::Error("x".into()));
        assert_eq!(parse_line("hello"), Line::Other);
    }

    #[test]
    fn manifests_quote_and_keys_follow_years_and_mode() {
        let text = manifest_text(&[(
            PathBuf::from("/m/a, \"b\".flac"),
            1999,
            "Hi, there".into(),
            String::new(),
        )]);
        assert_eq!(
            text,
            "path,year,title,artist\n\"/m/a, \"\"b\"\".flac\",1999,\"Hi, there\",\"\"\n"
        );
        let songs = vec![(PathBuf::from("/no/such.flac"), Some(1999))];
        let other = vec![(PathBuf::from("/no/such.flac"), Some(2000))];
        assert_eq!(key("1", false, &songs), key("1", false, &songs));
        assert_ne!(key("1", false, &songs), key("1", false, &other));
        assert_ne!(key("1", false, &songs), key("1", true, &songs));
        assert_ne!(key("1", false, &songs), key("2", false, &songs));
    }
}
