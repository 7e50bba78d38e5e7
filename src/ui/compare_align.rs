//! The compare's releases aligned in time and matched in loudness, in the window: once B is
//! loaded and both songs' audio is known, `loudscape-extract compare --json` runs on a thread
//! (`extract::align::compare_audio`, never on the UI thread) while the panel says "aligning A
//! and B…"; its answer moves B's time onto A's in the pictures (the scene is built again), makes
//! key B switch to the same moment of the music, and sets the gain each side plays at. The
//! panel's part: the offset and its confidence, the "match loudness" switch and the nudge. What
//! is kept and decided is `state/alignment.rs`.

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use eframe::egui::{self, Color32};

use crate::data::cloud::PointCloud;
use crate::extract::align::{Comparison, compare_audio};
use crate::playback;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::alignment::{CompareAlignment, NUDGE_STEPS_S};
use crate::ui::state::compare_window::Listening;

/// Runs the comparison of A's and B's audio on a thread.
fn align_on_thread(a: PathBuf, b: PathBuf) -> Receiver<Result<Comparison, String>> {
    let (sender, receiver) = channel();
    let spawned = std::thread::Builder::new()
        .name("compare-align".into())
        .spawn(move || {
            let _ = sender.send(compare_audio(&[a, b], "quietest"));
        });
    // No thread: the receiver's sender is gone, which the state tells as an error.
    if let Err(e) = spawned {
        log::warn!("no thread for the alignment: {e}");
    }
    receiver
}

/// B's cloud with its time moved onto A's by the alignment (B itself, not a copy, before one
/// has come).
pub(super) fn aligned_b<'a>(
    alignment: &CompareAlignment,
    b: &'a PointCloud,
) -> Cow<'a, PointCloud> {
    match alignment.offset_s() {
        Some(offset) => Cow::Owned(crate::data::compare::aligned_in_time(b, offset)),
        None => Cow::Borrowed(b),
    }
}

impl LoudscapeApp {
    /// Starts the comparison once a pair is there, takes its answer, and sets the heard side's
    /// gain (0 dB without a compare).
    pub(super) fn poll_alignment(&mut self, ctx: &egui::Context) {
        let Some(state) = self.compare.as_mut() else {
            self.audio.set_gain_db(0.0);
            return;
        };
        if let (Some(song), Some(b)) = (self.song.as_ref(), state.b_loaded.as_ref()) {
            let pair = (song.cloud.path.clone(), b.path.clone());
            if state.alignment.asked_for.as_ref() != Some(&pair) {
                // The sources held against their clouds: another song where B's audio was
                // would be aligned with A as if it were B.
                let a_audio = self
                    .audio
                    .track_path()
                    .map(Ok)
                    .unwrap_or_else(|| playback::checked_source(&song.cloud));
                match (a_audio, playback::checked_source(b)) {
                    (Ok(a), Ok(b)) => {
                        state.alignment.start(pair, align_on_thread(a, b));
                    }
                    (Err(e), _) | (_, Err(e)) => {
                        state.alignment.asked_for = Some(pair);
                        state.alignment.error = Some(format!("nothing to align: {e}"));
                        self.messages.warn(format!(
                            "compare: A and B not aligned (nothing to align: {e})"
                        ));
                    }
                }
            }
        }
        match state.alignment.poll() {
            Some(true) => {
                // The pictures again, with B on A's time.
                state.built_for = None;
                let line = state.alignment.offset_line().unwrap_or_default();
                // A log line, as loads are told: tests read it.
                eprintln!(
                    "compare: aligned ({line}); gains A {:+.1} dB, B {:+.1} dB",
                    state.alignment.gain_db(Listening::A),
                    state.alignment.gain_db(Listening::B)
                );
            }
            Some(false) => {
                let error = state.alignment.error.clone().unwrap_or_default();
                self.messages
                    .warn(format!("compare: A and B not aligned ({error})"));
            }
            None => {}
        }
        if state.alignment.aligning() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        let gain = state.alignment.gain_db(state.listening);
        self.audio.set_gain_db(gain);
    }

    /// The panel's alignment lines: "aligning A and B…", the offset and its confidence (or why
    /// not aligned), "match loudness" and the nudge of B's offset.
    pub(super) fn alignment_controls(&mut self, ui: &mut egui::Ui) {
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        let alignment = &mut state.alignment;
        if alignment.aligning() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("aligning A and B…");
            });
            return;
        }
        if let Some(error) = &alignment.error {
            ui.colored_label(
                Color32::from_rgb(230, 180, 90),
                format!("not aligned: {error}"),
            );
        }
        if alignment.comparison.is_none() {
            return;
        }
        if let Some(line) = alignment.offset_line() {
            ui.label(line);
        }
        let before = alignment.nudge_s;
        if alignment.offset_s().is_some() {
            ui.horizontal_wrapped(|ui| {
                ui.label("nudge");
                for step in NUDGE_STEPS_S {
                    let label = format!("{:+.0}", step * 1000.0);
                    if ui
                        .small_button(label)
                        .on_hover_text("moves B's offset against A by this many milliseconds")
                        .clicked()
                    {
                        alignment.nudge(step);
                    }
                }
            });
        }
        ui.checkbox(&mut alignment.match_loudness, "match loudness")
            .on_hover_text("each side plays at the gain that brings it to the quieter one");
        if alignment.nudge_s != before {
            // The pictures again, with B moved.
            state.built_for = None;
            ui.ctx().request_repaint();
        }
    }
}

/// What the switch line adds after "listening to B at 13.231 s": the moment of the other side
/// it came from and B's offset (" (from A 12.500 s, B aligned +0.731 s)"), or nothing while
/// nothing is aligned.
pub(super) fn switch_words(
    alignment: &CompareAlignment,
    to: Listening,
    from: Option<f64>,
) -> String {
    let (Some(offset), Some(from)) = (alignment.offset_s(), from) else {
        return String::new();
    };
    let other = if to == Listening::A { "B" } else { "A" };
    format!(" (from {other} {from:.3} s, B aligned {offset:+.3} s)")
}
