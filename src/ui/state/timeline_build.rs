//! A timeline build's state, kept in the Open row (`OpenPanel` in `state/open.rs`): where the
//! build is ([`TimelineBuild`]: tags being read, or the years dialog with what was typed), the
//! song rows as they finish ([`Rows`], shared with the build's thread) and the years the user
//! typed ([`YearBook`], read from and saved to `years.json` in the state folder, keyed by the
//! song's absolute path). The build itself (the threads, the dialog, the rows drawn) is
//! `ui/timeline_build.rs`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};

use crate::extract::timeline::SongTags;
use crate::ui::state::loading::Shared;

/// Years typed by the user, by song (absolute path), kept in `years.json` beside the recent
/// files.
#[derive(Default)]
pub(in crate::ui) struct YearBook {
    years: BTreeMap<PathBuf, i32>,
    store: Option<PathBuf>,
}

impl YearBook {
    pub(in crate::ui) fn load(store: Option<PathBuf>) -> Self {
        let years = store
            .as_ref()
            .and_then(|s| std::fs::read(s).ok())
            .and_then(|b| serde_json::from_slice::<BTreeMap<PathBuf, i32>>(&b).ok())
            .unwrap_or_default();
        Self { years, store }
    }

    pub(in crate::ui) fn get(&self, song: &Path) -> Option<i32> {
        self.years.get(&absolute(song)).copied()
    }

    /// Remembers `years` and saves the book (written beside and renamed).
    pub(in crate::ui) fn remember(&mut self, years: &[(PathBuf, i32)]) -> Result<(), String> {
        for (song, year) in years {
            self.years.insert(absolute(song), *year);
        }
        let Some(store) = &self.store else {
            return Ok(());
        };
        let fail = |e: std::io::Error| format!("{}: cannot keep the years: {e}", store.display());
        if let Some(dir) = store.parent() {
            std::fs::create_dir_all(dir).map_err(fail)?;
        }
        let text = serde_json::to_vec_pretty(&self.years).map_err(|e| e.to_string())?;
        let temporary = store.with_extension(format!("json.{}.tmp", std::process::id()));
        std::fs::write(&temporary, text).map_err(fail)?;
        std::fs::rename(&temporary, store).map_err(|e| {
            let _ = std::fs::remove_file(&temporary);
            fail(e)
        })
    }
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}

/// Where a timeline build is.
pub(in crate::ui) enum TimelineBuild {
    /// Reading the tags.
    Listing {
        inputs: Vec<PathBuf>,
        receiver: Receiver<Result<Vec<SongTags>, String>>,
        shared: Shared,
    },
    /// Asking for the years the tags lack: the songs and the text typed for each.
    AskYears {
        inputs: Vec<PathBuf>,
        songs: Vec<SongTags>,
        typed: Vec<String>,
        focused: bool,
        /// Enter was pressed with songs still without a year: the dialog says what Enter
        /// does instead of leaving them out unasked.
        enter_refused: bool,
    },
}

/// The songs of a build as they finish (shown a row each).
#[derive(Default)]
pub(in crate::ui) struct SongRows {
    pub(in crate::ui) rows: Vec<(PathBuf, Option<String>)>,
    pub(in crate::ui) total: usize,
}

/// Shared song rows of the build on its way.
pub(in crate::ui) type Rows = Arc<Mutex<SongRows>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn years_are_remembered_across_loads() {
        let dir = std::env::temp_dir().join(format!("loudscape-years-{}", std::process::id()));
        let store = dir.join("years.json");
        let mut book = YearBook::load(Some(store.clone()));
        book.remember(&[(dir.join("a.wav"), 1984)]).unwrap();
        let again = YearBook::load(Some(store));
        assert_eq!(again.get(&dir.join("a.wav")), Some(1984));
        assert_eq!(again.get(&dir.join("b.wav")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
