//! A timeline build's state, owned by [`TimelineBuilder`] (the `timeline_build` field of
//! `LoudscapeApp`): where the build is ([`TimelineBuild`]: tags being read, or the years dialog
//! with what was typed), the song rows as they finish ([`Rows`], shared with the build's thread),
//! the build's name in the loading rows, and the years the user typed ([`YearBook`], read from
//! and saved to `years.json` in the state folder, keyed by the song's absolute path). The build
//! itself (the threads, the dialog, the rows drawn) is `ui/timeline_build.rs`; it changes this
//! state through [`TimelineBuilder`]'s methods.

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
#[derive(Clone, Default)]
pub(in crate::ui) struct SongRows {
    pub(in crate::ui) rows: Vec<(PathBuf, Option<String>)>,
    pub(in crate::ui) total: usize,
}

/// Shared song rows of the build on its way.
pub(in crate::ui) type Rows = Arc<Mutex<SongRows>>;

/// The owner of a timeline build's state between frames.
#[derive(Default)]
pub(in crate::ui) struct TimelineBuilder {
    /// Where the build is before its songs are extracted (None: no listing or dialog).
    step: Option<TimelineBuild>,
    /// The songs of the build being extracted, a row each as they finish.
    rows: Rows,
    /// The loading row of the build being extracted.
    building: Option<PathBuf>,
    /// Years typed for songs whose tags lack one.
    years: YearBook,
}

impl TimelineBuilder {
    pub(in crate::ui) fn new(years: YearBook) -> Self {
        Self {
            years,
            ..Default::default()
        }
    }

    /// The tags of `inputs` are being read on a thread that answers on `receiver`.
    pub(in crate::ui) fn listing(
        &mut self,
        inputs: Vec<PathBuf>,
        receiver: Receiver<Result<Vec<SongTags>, String>>,
        shared: Shared,
    ) {
        self.step = Some(TimelineBuild::Listing {
            inputs,
            receiver,
            shared,
        });
    }

    /// Asks for the years `songs` lack (nothing typed yet).
    pub(in crate::ui) fn ask_years(&mut self, inputs: Vec<PathBuf>, songs: Vec<SongTags>) {
        let typed = vec![String::new(); songs.len()];
        self.step = Some(TimelineBuild::AskYears {
            inputs,
            songs,
            typed,
            focused: false,
            enter_refused: false,
        });
    }

    /// The listing or the dialog is over (built, failed or cancelled).
    pub(in crate::ui) fn end_step(&mut self) {
        self.step = None;
    }

    /// Where the build is, for the panel's widgets to edit (the years typed, the dialog's
    /// focus, the listing's Cancel).
    pub(in crate::ui) fn step_mut(&mut self) -> Option<&mut TimelineBuild> {
        self.step.as_mut()
    }

    /// Whether the tags are being read (the scripted screenshot waits for it).
    pub(in crate::ui) fn is_listing(&self) -> bool {
        matches!(self.step, Some(TimelineBuild::Listing { .. }))
    }

    /// Whether scripted key presses may go on: not while the tags are read, and in the years
    /// dialog once its field has the keyboard.
    pub(in crate::ui) fn input_ready(&self) -> bool {
        match &self.step {
            Some(TimelineBuild::Listing { .. }) => false,
            Some(TimelineBuild::AskYears { focused, .. }) => *focused,
            None => true,
        }
    }

    /// The build named `label` starts extracting: its rows start empty. Returns the rows for
    /// its thread to fill.
    pub(in crate::ui) fn start_build(&mut self, label: PathBuf) -> Rows {
        if let Ok(mut rows) = self.rows.lock() {
            *rows = SongRows::default();
        }
        self.building = Some(label);
        self.rows.clone()
    }

    /// The loading row of the build being extracted.
    pub(in crate::ui) fn building(&self) -> Option<&PathBuf> {
        self.building.as_ref()
    }

    /// The songs in all and the rows so far (song, why it failed).
    pub(in crate::ui) fn rows(&self) -> Option<SongRows> {
        self.rows.lock().ok().map(|rows| rows.clone())
    }

    /// Gives the songs without a year in their tags the one typed for them before.
    pub(in crate::ui) fn fill_remembered_years(&self, songs: &mut [SongTags]) {
        for song in songs {
            if song.year.is_none() {
                song.year = self.years.get(&song.path);
            }
        }
    }

    /// Keeps the years typed in the dialog for the next build (`years.json`).
    pub(in crate::ui) fn remember_years(&mut self, years: &[(PathBuf, i32)]) -> Result<(), String> {
        self.years.remember(years)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn song(path: &str, year: Option<i32>) -> SongTags {
        SongTags {
            path: PathBuf::from(path),
            year,
            title: String::new(),
            artist: String::new(),
            tag_error: None,
        }
    }

    /// The steps of a build as its owner keeps them: the listing holds scripted key presses,
    /// the years dialog until its field has the keyboard; a new build's rows start empty.
    #[test]
    fn a_builds_steps_and_rows_are_kept_by_its_owner() {
        let mut build = TimelineBuilder::new(YearBook::load(None));
        assert!(build.input_ready() && !build.is_listing());
        let (_sender, receiver) = std::sync::mpsc::channel();
        build.listing(vec![PathBuf::from("music")], receiver, Shared::default());
        assert!(build.is_listing() && !build.input_ready());
        build.ask_years(vec![PathBuf::from("music")], vec![song("a.wav", None)]);
        assert!(!build.is_listing() && !build.input_ready());
        if let Some(TimelineBuild::AskYears { focused, typed, .. }) = build.step_mut() {
            assert_eq!(typed.len(), 1, "a field a song");
            *focused = true;
        }
        assert!(build.input_ready(), "the field has the keyboard");
        build.end_step();
        assert!(build.step_mut().is_none() && build.input_ready());

        let rows = build.start_build(PathBuf::from("music"));
        rows.lock()
            .unwrap()
            .rows
            .push((PathBuf::from("a.wav"), None));
        assert_eq!(build.rows().map(|r| r.rows.len()), Some(1));
        build.start_build(PathBuf::from("more"));
        assert_eq!(build.rows().map(|r| r.rows.len()), Some(0));
        assert_eq!(build.building(), Some(&PathBuf::from("more")));
    }

    /// A year typed once fills in the song's missing tag next time; a tagged year stays.
    #[test]
    fn remembered_years_fill_only_missing_tags() {
        let mut build = TimelineBuilder::new(YearBook::load(None));
        let here = std::env::current_dir().unwrap();
        build
            .remember_years(&[(here.join("a.wav"), 1984), (here.join("b.wav"), 1990)])
            .unwrap();
        let mut songs = vec![
            song("a.wav", None),
            song("b.wav", Some(2001)),
            song("c.wav", None),
        ];
        build.fill_remembered_years(&mut songs);
        let years: Vec<_> = songs.iter().map(|s| s.year).collect();
        assert_eq!(years, [Some(1984), Some(2001), None]);
    }

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
