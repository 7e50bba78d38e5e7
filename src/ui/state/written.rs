//! Where the window may write a picture or a video: only to a name of the right kind (a PNG to
//! `.png`, a video to what `loudscape video` writes), and never over a file it did not make
//! itself, for the same purpose, in this run. [`MadeHere`] remembers the files Save PNG (or
//! Export video…) wrote, each with its size and time, so a file changed or replaced since is
//! not "made here" any more; [`target`] picks the path to write: the one asked for when it is
//! free or made here, else the first free `name-2.png`, `name-3.png`, … beside it, and the
//! caller says so. A file chosen in a native save dialog was confirmed there and is written as
//! chosen.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// What a file looked like when the window wrote it.
type Stamp = (u64, Option<SystemTime>);

fn stamp(path: &Path) -> Option<Stamp> {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.len(), meta.modified().ok()))
}

/// The files the window wrote in this run for one purpose (PNGs, or videos).
#[derive(Default, Debug)]
pub(in crate::ui) struct MadeHere {
    files: Vec<(PathBuf, Stamp)>,
}

impl MadeHere {
    /// `path` was just written by the window.
    pub(in crate::ui) fn record(&mut self, path: &Path) {
        let path = absolute(path);
        self.files.retain(|(p, _)| p != &path);
        if let Some(stamp) = stamp(&path) {
            self.files.push((path, stamp));
        }
    }

    /// Whether `path` is a file the window wrote and nothing changed since.
    pub(in crate::ui) fn made(&self, path: &Path) -> bool {
        let path = absolute(path);
        self.files
            .iter()
            .any(|(p, s)| p == &path && stamp(&path).as_ref() == Some(s))
    }
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}

/// Why a name cannot take a file of this kind.
#[derive(Debug, PartialEq)]
pub(in crate::ui) struct WrongKind {
    /// The name's own extension, if it has one.
    pub(in crate::ui) extension: Option<String>,
}

/// `typed` as a name of the kind `extension` (lower case, no dot): as it is when it ends in it
/// (any case), with it added when it has no extension; an error for another extension.
pub(in crate::ui) fn of_kind(typed: &Path, extension: &str) -> Result<PathBuf, WrongKind> {
    match typed.extension().map(|e| e.to_string_lossy().into_owned()) {
        Some(e) if e.eq_ignore_ascii_case(extension) => Ok(typed.to_owned()),
        Some(e) => Err(WrongKind { extension: Some(e) }),
        None if typed.file_name().is_some() => {
            let mut name = typed.as_os_str().to_owned();
            name.push(".");
            name.push(extension);
            Ok(PathBuf::from(name))
        }
        None => Err(WrongKind { extension: None }),
    }
}

/// Where to write what was asked to go to `wanted`: `wanted` when nothing is there or the window
/// made it ([`MadeHere`]), else the first `stem-N.ext` (N from 2) that is free. The second value
/// is true when the name was changed.
pub(in crate::ui) fn target(wanted: &Path, made: &MadeHere) -> (PathBuf, bool) {
    let taken = |p: &Path| p.symlink_metadata().is_ok();
    if !taken(wanted) || made.made(wanted) {
        return (wanted.to_owned(), false);
    }
    let stem = wanted
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let extension = wanted
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut n = 2u32;
    loop {
        let candidate = wanted.with_file_name(format!("{stem}-{n}{extension}"));
        if !taken(&candidate) {
            return (candidate, true);
        }
        n += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/output")
            .join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn only_names_of_the_kind_and_a_missing_extension_added() {
        assert_eq!(
            of_kind(Path::new("a/shot.png"), "png"),
            Ok("a/shot.png".into())
        );
        assert_eq!(of_kind(Path::new("shot.PNG"), "png"), Ok("shot.PNG".into()));
        assert_eq!(
            of_kind(Path::new("out/shot"), "png"),
            Ok("out/shot.png".into())
        );
        assert_eq!(
            of_kind(Path::new("out/song1.mp4"), "png"),
            Err(WrongKind {
                extension: Some("mp4".into())
            })
        );
        assert!(of_kind(Path::new("shot.png"), "mp4").is_err());
        assert_eq!(of_kind(Path::new("take"), "mp4"), Ok("take.mp4".into()));
    }

    #[test]
    fn a_file_the_window_did_not_make_gets_a_fresh_name_beside_it() {
        let dir = scratch("written_fresh_name");
        let shot = dir.join("shot.png");
        let made = MadeHere::default();
        assert_eq!(
            target(&shot, &made),
            (shot.clone(), false),
            "free: as asked"
        );
        std::fs::write(&shot, b"someone else's").unwrap();
        assert_eq!(target(&shot, &made), (dir.join("shot-2.png"), true));
        std::fs::write(dir.join("shot-2.png"), b"x").unwrap();
        assert_eq!(target(&shot, &made), (dir.join("shot-3.png"), true));
        let bare = dir.join("notes");
        std::fs::write(&bare, b"x").unwrap();
        assert_eq!(target(&bare, &made), (dir.join("notes-2"), true));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_the_window_made_is_written_again_until_something_else_changes_it() {
        let dir = scratch("written_made_here");
        let shot = dir.join("shot.png");
        let mut made = MadeHere::default();
        std::fs::write(&shot, b"the window's picture").unwrap();
        made.record(&shot);
        assert_eq!(target(&shot, &made), (shot.clone(), false));
        // Replaced by something else (another size): no longer the window's.
        std::fs::write(&shot, b"a video now, much longer than the picture").unwrap();
        assert!(!made.made(&shot));
        assert_eq!(target(&shot, &made), (dir.join("shot-2.png"), true));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
