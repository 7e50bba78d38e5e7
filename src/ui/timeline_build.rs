//! A folder or several songs become a timeline from the window. The paths (command line, drop,
//! Open dialog, recent files) go through [`LoudscapeApp::start_opening`]: clouds open as before,
//! a single song is a Song, and a folder or two songs or more are one timeline, built by
//! `crate::extract::timeline` on a thread: the tags are read first (`--list-songs`); songs
//! without a year get one remembered from an earlier answer (`years.json` in the state folder,
//! keyed by the song's absolute path) or are listed in a dialog where the user types it, or
//! skips (the songs then placed in order, `--x-by order`); then the build, with a row a song
//! as each finishes and Cancel. The finished timeline goes through the same loading slot as any
//! cloud, so the old view stays until it is installed. What a build keeps between frames
//! (`TimelineBuild`, the song rows, the years book) is owned by `state/timeline_build.rs`'s
//! `TimelineBuilder`, the `timeline_build` field; this file changes it through its methods.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::mpsc::{TryRecvError, channel};

use eframe::egui::{self, RichText};

use crate::extract::timeline::{self, Line, Placement, SongTags};
use crate::extract::{Progress, cache};
use crate::ui::shortcuts::{self, Action};
use crate::ui::state::LoudscapeApp;
use crate::ui::state::loading::{Loading, Shared};
use crate::ui::state::timeline_build::{SongRows, TimelineBuild};

/// The build list's mark of a song done and of one that failed: glyphs the window's font has
/// (the check marks and crosses of Dingbats are not in it: they drew as empty boxes).
pub(super) const DONE: &str = "•";
pub(super) const FAILED: &str = "×";

/// A year as typed: four digits in a plausible range.
pub(super) fn parse_year(text: &str) -> Option<i32> {
    let year: i32 = text.trim().parse().ok()?;
    (1860..=2100).contains(&year).then_some(year)
}

/// Whether the years dialog says "not a year" under `text`: only for a whole entry that is no
/// year (four characters or more, or the field left or Enter pressed), not while the first
/// digits are typed.
pub(super) fn says_not_a_year(text: &str, typing: bool) -> bool {
    let whole = !typing || text.trim().chars().count() >= 4;
    !text.trim().is_empty() && whole && parse_year(text).is_none()
}

/// Whether these paths make a timeline: a folder, or two audio files or more.
pub(super) fn makes_timeline(paths: &[PathBuf]) -> bool {
    let audio = paths
        .iter()
        .filter(|p| !p.is_dir() && crate::extract::is_audio(p))
        .count();
    paths.iter().any(|p| p.is_dir()) || audio >= 2
}

fn name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

impl LoudscapeApp {
    /// Opens what was chosen: clouds and a lone song as before, a folder or several songs as
    /// one timeline.
    pub(super) fn start_opening(&mut self, paths: Vec<PathBuf>) {
        if !makes_timeline(&paths) {
            for path in paths {
                self.start_loading(path);
            }
            return;
        }
        let (songs, clouds): (Vec<PathBuf>, Vec<PathBuf>) = paths
            .into_iter()
            .partition(|p| p.is_dir() || crate::extract::is_audio(p));
        for cloud in clouds {
            self.start_loading(cloud);
        }
        self.start_timeline(songs);
    }

    /// Reads the tags of the songs under `inputs` on a thread (the first step of a build).
    pub(super) fn start_timeline(&mut self, inputs: Vec<PathBuf>) {
        let (sender, receiver) = channel();
        let shared = Shared::default();
        let thread_shared = shared.clone();
        let thread_inputs = inputs.clone();
        let what = describe(&inputs);
        std::thread::spawn(move || {
            let result = crate::extract::find_extractor(Path::new(&what))
                .map_err(|e| e.to_string())
                .and_then(|extractor| {
                    timeline::list_songs(&extractor, &thread_inputs, &thread_shared.cancel)
                        .map_err(|reason| format!("{what}: {reason}"))
                });
            let _ = sender.send(result);
        });
        self.timeline_build.listing(inputs, receiver, shared);
    }

    /// Builds the timeline of `songs` (years known), or in order, on the loading thread.
    fn build_timeline(&mut self, inputs: &[PathBuf], placement: Placement) {
        let (sender, receiver) = channel();
        let shared = Shared::default();
        let thread_shared = shared.clone();
        let what = describe(inputs);
        // A single folder names the build (and the recent files); several songs, a description.
        let label = match inputs {
            [folder] if folder.is_dir() => folder.clone(),
            _ => PathBuf::from(&what),
        };
        let rows = self.timeline_build.start_build(label.clone());
        std::thread::spawn(move || {
            let mut on_song = |line: Line| {
                if let Line::SongDone {
                    song,
                    done,
                    total,
                    failed,
                } = line
                {
                    eprintln!(
                        "loudscape: {what}: song {done} of {total}: {}{}",
                        song.display(),
                        failed
                            .as_deref()
                            .map(|f| format!(" failed: {f}"))
                            .unwrap_or_default()
                    );
                    if let Ok(mut slot) = thread_shared.progress.lock() {
                        *slot = Some(Progress {
                            stage: format!("song {done} of {total}"),
                            fraction: done as f32 / total.max(1) as f32,
                        });
                    }
                    if let Ok(mut rows) = rows.lock() {
                        rows.total = total;
                        rows.rows.push((song, failed));
                    }
                }
            };
            if let Ok(mut slot) = thread_shared.progress.lock() {
                *slot = Some(Progress {
                    stage: "songs".into(),
                    fraction: 0.0,
                });
            }
            let result = crate::extract::find_extractor(Path::new(&what))
                .map_err(|e| e.to_string())
                .and_then(|extractor| {
                    timeline::build(
                        &extractor,
                        &placement,
                        &cache::dir(),
                        &thread_shared.cancel,
                        &mut on_song,
                    )
                    .map_err(|reason| format!("{what}: the timeline failed: {reason}"))
                })
                .and_then(|(ply, hit)| {
                    let how = if hit { "from the cache" } else { "built" };
                    eprintln!("loudscape: {what}: timeline {how}: {}", ply.display());
                    let cloud = crate::data::cloud::load(&ply).map_err(|e| e.to_string())?;
                    for line in cloud.warning_lines() {
                        eprintln!("{line}");
                    }
                    Ok(cloud)
                });
            let _ = sender.send(result);
        });
        self.loading.push(Loading::new(label, receiver, shared));
    }

    /// The timeline build's rows and dialog; called every frame from the Open row.
    pub(super) fn timeline_build_panel(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let mut next = None;
        match self.timeline_build.step_mut() {
            None => {}
            Some(TimelineBuild::Listing {
                inputs,
                receiver,
                shared,
            }) => {
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("reading the tags of {}", describe(inputs)));
                    if ui.small_button("Cancel").clicked() {
                        shared.cancel.store(true, Ordering::Relaxed);
                    }
                });
                ctx.request_repaint_after(std::time::Duration::from_millis(100));
                match receiver.try_recv() {
                    Ok(Ok(songs)) => next = Some(Ok((inputs.clone(), songs))),
                    Ok(Err(message)) => next = Some(Err(message)),
                    Err(TryRecvError::Disconnected) => {
                        next = Some(Err("the tag reader stopped".into()));
                    }
                    Err(TryRecvError::Empty) => {}
                }
            }
            Some(TimelineBuild::AskYears { .. }) => self.years_dialog(&ctx),
        }
        match next {
            Some(Ok((inputs, songs))) => self.listed(inputs, songs),
            Some(Err(message)) => {
                self.timeline_build.end_step();
                if !message.ends_with("cancelled") {
                    self.messages.error(message);
                }
            }
            None => {}
        }
        let rows = self.timeline_build.rows().map(|SongRows { total, rows }| {
            (
                total,
                rows.iter()
                    .map(|(p, f)| (name(p), f.clone()))
                    .collect::<Vec<_>>(),
            )
        });
        let building = self
            .loading
            .iter()
            .any(|l| Some(&l.path) == self.timeline_build.building());
        if let Some((total, rows)) = rows.filter(|_| building) {
            ui.label(RichText::new(format!("Timeline: {} of {total} songs", rows.len())).small());
            for (song, failed) in rows.iter().rev().take(8) {
                match failed {
                    None => ui.label(RichText::new(format!("{DONE} {song}")).small()),
                    Some(reason) => ui
                        .label(
                            RichText::new(format!("{FAILED} {song}: failed"))
                                .small()
                                .weak(),
                        )
                        .on_hover_text(reason.as_str()),
                };
            }
        }
    }

    /// The tags are read: build at once when every song has a year (from its tags or
    /// remembered), else ask.
    fn listed(&mut self, inputs: Vec<PathBuf>, mut songs: Vec<SongTags>) {
        songs.retain(|s| s.tag_error.is_none());
        if songs.is_empty() {
            self.timeline_build.end_step();
            self.messages.error(format!(
                "{}: no audio file to build a timeline of",
                describe(&inputs)
            ));
            return;
        }
        self.timeline_build.fill_remembered_years(&mut songs);
        let missing: Vec<&SongTags> = songs.iter().filter(|s| s.year.is_none()).collect();
        if missing.is_empty() {
            self.timeline_build.end_step();
            self.build_timeline(&inputs, by_year(&songs));
            return;
        }
        eprintln!(
            "loudscape: {}: {} song(s) without a year: {}",
            describe(&inputs),
            missing.len(),
            missing
                .iter()
                .map(|s| name(&s.path))
                .collect::<Vec<_>>()
                .join(", ")
        );
        self.timeline_build.ask_years(inputs, songs);
    }

    /// The dialog listing the songs without a year.
    fn years_dialog(&mut self, ctx: &egui::Context) {
        let Some(TimelineBuild::AskYears {
            inputs,
            songs,
            typed,
            focused,
            enter_refused,
        }) = self.timeline_build.step_mut()
        else {
            return;
        };
        let mut choice = None;
        egui::Window::new("Songs without a year")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label("Their tags give no year. Type one to place them by year:");
                ui.add_space(4.0);
                egui::Grid::new("years").num_columns(2).show(ui, |ui| {
                    for (song, text) in songs.iter().zip(typed.iter_mut()) {
                        if song.year.is_some() {
                            continue;
                        }
                        ui.label(name(&song.path))
                            .on_hover_text(song.path.display().to_string());
                        let field = ui.add(
                            egui::TextEdit::singleline(text)
                                .hint_text("year")
                                .desired_width(60.0),
                        );
                        if !*focused {
                            field.request_focus();
                            *focused = true;
                        }
                        let typing = field.has_focus() && !*enter_refused;
                        if says_not_a_year(text, typing) {
                            ui.label(RichText::new("not a year").small().weak());
                        }
                        ui.end_row();
                    }
                });
                ui.add_space(6.0);
                let all_typed = songs
                    .iter()
                    .zip(typed.iter())
                    .all(|(s, t)| s.year.is_some() || parse_year(t).is_some());
                let some_typed = typed.iter().any(|t| parse_year(t).is_some());
                let with_year = songs.iter().filter(|s| s.year.is_some()).count();
                // Enter builds only when every song has a year: leaving songs out is a click on
                // its own button, never the quiet result of Enter.
                let enter = shortcuts::pressed(ctx, Action::Confirm);
                if enter && !all_typed {
                    if !*enter_refused {
                        eprintln!(
                            "loudscape: Enter: songs still without a year; nothing is built until \
                             they have one or a button says otherwise"
                        );
                    }
                    *enter_refused = true;
                }
                if *enter_refused && !all_typed {
                    let left = songs
                        .iter()
                        .zip(typed.iter())
                        .filter(|(s, t)| s.year.is_none() && parse_year(t).is_none())
                        .count();
                    ui.label(
                        RichText::new(format!(
                            "{left} song(s) still without a year: type them (Tab: next field), \
                             or choose below to leave them out or place all in order"
                        ))
                        .color(crate::ui::style::WARNING),
                    );
                }
                ui.horizontal(|ui| {
                    let label = if all_typed {
                        "Build by year"
                    } else {
                        "Build by year, leaving the others out"
                    };
                    if ui
                        .add_enabled(some_typed || with_year > 0, egui::Button::new(label))
                        .clicked()
                        || (enter && all_typed)
                    {
                        choice = Some(true);
                    }
                    if ui
                        .button("Skip: place in order")
                        .on_hover_text("no years: each song an equal span (--x-by order)")
                        .clicked()
                    {
                        choice = Some(false);
                    }
                    if ui.button("Cancel").clicked() {
                        choice = None;
                        *focused = false;
                        songs.clear();
                    }
                });
            });
        let cancelled = songs.is_empty();
        let inputs = inputs.clone();
        let songs = songs.clone();
        let typed = typed.clone();
        if cancelled {
            self.timeline_build.end_step();
            return;
        }
        match choice {
            Some(true) => {
                let mut answered = Vec::new();
                let mut placed = songs.clone();
                for (song, text) in placed.iter_mut().zip(&typed) {
                    if song.year.is_none()
                        && let Some(year) = parse_year(text)
                    {
                        song.year = Some(year);
                        answered.push((song.path.clone(), year));
                    }
                }
                if let Err(message) = self.timeline_build.remember_years(&answered) {
                    self.messages.error(message);
                }
                self.timeline_build.end_step();
                self.build_timeline(&inputs, by_year(&placed));
            }
            Some(false) => {
                self.timeline_build.end_step();
                let paths = songs.iter().map(|s| s.path.clone()).collect();
                self.build_timeline(&inputs, Placement::InOrder(paths));
            }
            None => {}
        }
    }

    /// Whether a timeline is on its way (the scripted screenshot waits for it).
    pub(super) fn timeline_listing(&self) -> bool {
        self.timeline_build.is_listing()
    }
}

/// The songs with a year, placed by it.
fn by_year(songs: &[SongTags]) -> Placement {
    Placement::ByYear(
        songs
            .iter()
            .filter_map(|s| {
                s.year
                    .map(|y| (s.path.clone(), y, s.title.clone(), s.artist.clone()))
            })
            .collect(),
    )
}

/// "timeline of music/" or "timeline of 3 songs", naming the build in rows and messages.
fn describe(inputs: &[PathBuf]) -> String {
    match inputs {
        [one] => format!("timeline of {}", name(one)),
        many => format!("timeline of {} songs and folders", many.len()),
    }
}

impl LoudscapeApp {
    /// Scripted presses wait for the years dialog's field to have the keyboard.
    pub(super) fn scripted_input_ready(&self) -> bool {
        self.timeline_build.input_ready()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_song_marks_are_in_the_font() {
        let ctx = egui::Context::default();
        let mut output = ctx.run_ui(Default::default(), |_| {});
        output.textures_delta.clear();
        let font = egui::FontId::proportional(11.0);
        for mark in [DONE, FAILED] {
            assert!(
                ctx.fonts_mut(|f| f.has_glyphs(&font, mark)),
                "{mark} is not in the font"
            );
        }
        // The marks drawn before: not in the font, so the check can fail.
        assert!(!ctx.fonts_mut(|f| f.has_glyphs(&font, "✔")));
    }

    #[test]
    fn years_parse() {
        assert_eq!(parse_year(" 1999 "), Some(1999));
        // Said once the entry is whole, not after the first digit.
        assert!(!says_not_a_year("1", true));
        assert!(!says_not_a_year("199", true));
        assert!(!says_not_a_year("", false));
        assert!(!says_not_a_year("1996", true));
        assert!(says_not_a_year("1", false), "the field left with one digit");
        assert!(says_not_a_year("19x6", true));
        assert!(says_not_a_year("3000", true));
        assert_eq!(parse_year("99"), None);
        assert_eq!(parse_year("abcd"), None);
    }

    #[test]
    fn folders_and_several_songs_make_timelines() {
        let dir = std::env::temp_dir().join(format!("loudscape-makes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b, c) = (dir.join("a.wav"), dir.join("b.wav"), dir.join("c.ply"));
        for p in [&a, &b] {
            std::fs::write(p, b"RIFF").unwrap();
        }
        std::fs::write(&c, b"ply\n").unwrap();
        assert!(!makes_timeline(std::slice::from_ref(&a)));
        assert!(!makes_timeline(&[a.clone(), c.clone()]));
        assert!(makes_timeline(&[a.clone(), b.clone()]));
        assert!(makes_timeline(std::slice::from_ref(&dir)));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
