//! The compare's releases aligned in time and matched in loudness, in the window: once every
//! version is loaded and their audio is known, `loudscape-extract compare --json` runs on a
//! thread for all of them, A first (`extract::align::compare_audio`, never on the UI thread)
//! while the panel says "aligning the versions…"; its answer moves the version beside A onto
//! A's time in the pictures (the scene is built again), makes key B switch to the same moment
//! of the music, and sets the gain each version plays at (the quietest one's loudness). The
//! panel's part: each version's offset and its confidence, the "match loudness" switch and the
//! nudge of the version beside A. What is kept and decided is `state/alignment.rs`.

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

/// Runs the comparison of the versions' audio (A first) on a thread.
fn align_on_thread(versions: Vec<PathBuf>) -> Receiver<Result<Comparison, String>> {
    let (sender, receiver) = channel();
    let spawned = std::thread::Builder::new()
        .name("compare-align".into())
        .spawn(move || {
            let _ = sender.send(compare_audio(&versions, "quietest"));
        });
    // No thread: the receiver's sender is gone, which the state tells as an error.
    if let Err(e) = spawned {
        log::warn!("no thread for the alignment: {e}");
    }
    receiver
}

/// `version`'s cloud with its time moved onto A's by the alignment (through its time map's
/// segments where it has several) and, `matched`, its levels by the gain that brings it to A's
/// loudness (the cloud itself, not a copy, where neither applies).
/// The window does this on a thread ([`BMoves`], `compare_scene.rs`); the tests call it here.
#[cfg(test)]
pub(super) fn aligned_b<'a>(
    alignment: &CompareAlignment,
    version: Listening,
    b: &'a PointCloud,
    matched: bool,
) -> Cow<'a, PointCloud> {
    BMoves::of(alignment, version, matched).apply(b)
}

/// What [`aligned_b`] reads of the alignment for one version, owned: the scene is prepared on
/// a thread (`compare_scene.rs`).
pub(super) struct BMoves {
    /// Whether the version moves at all (aligned in time or matched in level).
    moves: bool,
    alignment: Option<crate::extract::align::Alignment>,
    gain: Option<f64>,
}

impl BMoves {
    pub(super) fn of(alignment: &CompareAlignment, version: Listening, matched: bool) -> Self {
        let offset = alignment.offset_s(version);
        let gain = alignment.level_match_db(version).filter(|_| matched);
        let moves = offset.is_some() || gain.is_some();
        Self {
            moves,
            alignment: moves.then(|| alignment.alignment(version)).flatten(),
            gain,
        }
    }

    /// `b` moved (a copy), or `b` itself where nothing moves it.
    pub(super) fn apply<'a>(&self, b: &'a PointCloud) -> Cow<'a, PointCloud> {
        if !self.moves {
            return Cow::Borrowed(b);
        }
        let mut moved = b.clone();
        // A time map of several segments (a cut, an edit) moves each point by its own
        // segment's offset; one segment moves the time axis alone (the nudge is in the
        // alignment already).
        if let Some(alignment) = &self.alignment {
            alignment.move_onto_first(&mut moved, 0.0);
        }
        if let Some(gain) = self.gain {
            crate::data::compare::match_in_level(&mut moved, gain);
        }
        Cow::Owned(moved)
    }
}

impl LoudscapeApp {
    /// Starts the comparison once every version has loaded (again when the list changed),
    /// takes its answer, and sets the heard version's gain (0 dB without a compare).
    pub(super) fn poll_alignment(&mut self, ctx: &egui::Context) {
        // A's points so far while it is extracted are not its cloud yet (no source length to
        // check its audio by): the comparison waits for the whole.
        let previewing = self.previewing();
        let Some(state) = self.compare.as_mut() else {
            self.audio.set_gain_db(0.0);
            return;
        };
        let clouds: Option<Vec<&PointCloud>> =
            state.versions.iter().map(|v| v.loaded.as_deref()).collect();
        if let (Some(song), Some(clouds)) = (self.song.as_ref(), clouds)
            && !clouds.is_empty()
            && !previewing
        {
            let mut asked: Vec<PathBuf> = vec![song.cloud.path.clone()];
            asked.extend(clouds.iter().map(|c| c.path.clone()));
            if state.alignment.asked_for.as_ref() != Some(&asked) {
                // The sources held against their clouds: another song where a version's audio
                // was would be aligned with A as if it were that version. The player's track
                // is A's (picked by hand, perhaps) only while A is heard.
                let a_audio = match self.audio.track_path() {
                    Some(path) if state.listening == Listening::A => Ok(path),
                    _ => playback::checked_source(&song.cloud),
                };
                let sources: Result<Vec<PathBuf>, _> = std::iter::once(a_audio)
                    .chain(clouds.iter().map(|c| playback::checked_source(c)))
                    .collect();
                match sources {
                    Ok(sources) => state.alignment.start(asked, align_on_thread(sources)),
                    Err(e) => {
                        state
                            .alignment
                            .unavailable(asked, format!("nothing to align: {e}"));
                        self.messages.warn(format!(
                            "compare: versions not aligned (nothing to align: {e})"
                        ));
                    }
                }
            }
        }
        match state.alignment.poll() {
            Some(true) => {
                // The pictures again, with the version beside A on A's time; one not aligned
                // is drawn as it was (its levels matched or not is the scene's own key), and
                // building its scene again only held the window up.
                if state.alignment.offset_s(state.beside).is_some() {
                    state.rebuild_scene();
                }
                let count = state.alignment.count();
                let lines: Vec<String> = (1..count)
                    .filter_map(|i| state.alignment.offset_line(Listening(i)))
                    .collect();
                let gains: Vec<String> = (0..count)
                    .map(|i| {
                        let version = Listening(i);
                        format!(
                            "{} {:+.1} dB",
                            version.letter(),
                            state.alignment.gain_db(version)
                        )
                    })
                    .collect();
                // A log line, as loads are told: tests read it.
                eprintln!(
                    "compare: aligned ({}); gains {}",
                    lines.join("; "),
                    gains.join(", ")
                );
            }
            Some(false) => {
                let error = state.alignment.error.clone().unwrap_or_default();
                self.messages
                    .warn(format!("compare: versions not aligned ({error})"));
            }
            None => {}
        }
        if state.alignment.aligning() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        let gain = state.alignment.gain_db(state.listening);
        self.audio.set_gain_db(gain);
    }

    /// The panel's alignment lines, the same rows from the moment the compare is shown to the
    /// comparison's answer and after, so nothing below them moves when it comes (a click on a
    /// view button went to the wrong row): a line a version ("aligning the versions…" while it
    /// runs, its offset and confidence or why not aligned after, each cut to one line with the
    /// whole on hover), the nudge of the version beside A (enabled once it is aligned) and
    /// "match loudness".
    pub(super) fn alignment_controls(&mut self, ui: &mut egui::Ui) {
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        let count = state.count();
        let beside = state.beside;
        let alignment = &mut state.alignment;
        let height = ui.spacing().interact_size.y;
        for i in 1..count {
            let (text, colour) = alignment_line(alignment, Listening(i));
            one_row(ui, height, |ui| {
                if alignment.aligning() && i == 1 {
                    ui.add(egui::Spinner::new().size(height));
                }
                let mut shown = egui::RichText::new(text.as_str());
                if let Some(colour) = colour {
                    shown = shown.color(colour);
                }
                ui.add(egui::Label::new(shown).truncate())
                    .on_hover_text(text.as_str());
            });
        }
        let before = alignment.nudge_s(beside);
        let aligned = alignment.offset_s(beside).is_some();
        one_row(ui, height, |ui| {
            ui.add_enabled(
                aligned,
                egui::Label::new(format!("nudge {}", beside.letter())),
            );
            for step in NUDGE_STEPS_S {
                let label = format!("{:+.0}", step * 1000.0);
                if ui
                    .add_enabled(aligned, egui::Button::new(label).small())
                    .on_hover_text("moves its offset against A by this many milliseconds")
                    .on_disabled_hover_text("once the versions are aligned")
                    .clicked()
                {
                    alignment.nudge(beside, step);
                }
            }
        });
        let mut match_loudness = alignment.match_loudness;
        one_row(ui, height, |ui| {
            if ui
                .checkbox(&mut match_loudness, "match loudness")
                .on_hover_text("each version plays at the gain that brings it to the quietest one")
                .changed()
            {
                alignment.set_match_loudness(match_loudness);
            }
        });
        if alignment.nudge_s(beside) != before {
            // The pictures again, with the version moved.
            state.rebuild_scene();
            ui.ctx().request_repaint();
        }
    }
}

/// One row of the alignment lines, `height` high whatever it holds.
fn one_row(ui: &mut egui::Ui, height: f32, add: impl FnOnce(&mut egui::Ui)) {
    ui.horizontal(|ui| {
        ui.set_height(height);
        add(ui);
    });
}

/// `version`'s alignment line and its colour (a warning's when the comparison failed).
fn alignment_line(alignment: &CompareAlignment, version: Listening) -> (String, Option<Color32>) {
    let letter = version.letter();
    if alignment.aligning() {
        let text = if version == Listening::B {
            "aligning the versions…".to_string()
        } else {
            format!("{letter}: aligning…")
        };
        return (text, None);
    }
    if let Some(line) = alignment.offset_line(version) {
        return (line, None);
    }
    match &alignment.error {
        Some(error) if version == Listening::B => (
            format!("not aligned: {error}"),
            Some(Color32::from_rgb(230, 180, 90)),
        ),
        Some(_) => (format!("{letter} not aligned"), None),
        None if alignment.comparison.is_some() => (format!("{letter} not aligned"), None),
        None => (format!("{letter}: aligned once the versions are in"), None),
    }
}

/// What the switch line adds after "listening to B at 13.231 s": the moment of the version it
/// came from and the offset of the version switched to (or from, for A): " (from A 12.500 s,
/// B aligned +0.731 s)"; nothing while that version is not aligned.
pub(super) fn switch_words(
    alignment: &CompareAlignment,
    from_version: Listening,
    to: Listening,
    from: Option<f64>,
) -> String {
    let moved = if to == Listening::A { from_version } else { to };
    let (Some(offset), Some(from)) = (alignment.offset_s(moved), from) else {
        return String::new();
    };
    format!(
        " (from {} {from:.3} s, {} aligned {offset:+.3} s)",
        from_version.letter(),
        moved.letter()
    )
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::sync::mpsc::channel;

    use super::*;

    /// A, B 0.731 s later at -3.8 dB, C at +2.0 dB (A is not the quietest: C's matching gain
    /// is 0, A's -2.0).
    const JSON: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "match_gain_db": -2.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0, "segments": []}},
        {"path": "b.wav", "match_gain_db": -5.8,
         "alignment": {"alignable": true, "offset_s": 0.731, "confidence": 0.86,
                       "segments": []}},
        {"path": "c.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 0.9,
                       "segments": []}}]}"#;

    /// The compare section's height as the panel draws it (at the side panel's width) with
    /// `state`.
    fn section_height(state: crate::ui::state::compare_window::CompareState) -> f32 {
        let mut app = LoudscapeApp::new(
            crate::ui::app::WindowOptions {
                screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
                ..Default::default()
            },
            None,
        );
        app.compare = Some(state);
        let ctx = egui::Context::default();
        let mut height = 0.0;
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| {
            ui.set_max_width(crate::ui::app::side_panel_width(1280.0));
            let top = ui.cursor().min.y;
            app.compare_controls(ui);
            height = ui.cursor().min.y - top;
        });
        output.textures_delta.clear();
        height
    }

    /// A compare of A and B shown, its alignment `step`ped.
    fn compare_shown(
        step: impl FnOnce(&mut CompareAlignment),
    ) -> crate::ui::state::compare_window::CompareState {
        let cloud = || {
            PointCloud::synthetic(
                crate::data::synthetic::synthetic_song(50, 7),
                crate::data::cloud::DataMode::Song,
            )
        };
        let mut state = crate::ui::state::compare_window::CompareState::new(PathBuf::from("b.ply"));
        state.versions[0].loaded = Some(std::sync::Arc::new(cloud()));
        state.clouds = Some(std::sync::Arc::new((cloud(), cloud())));
        step(&mut state.alignment);
        state
    }

    /// The comparison answering `json` for A and B.
    fn answered(json: &'static str) -> impl FnOnce(&mut CompareAlignment) {
        move |alignment| {
            let (sender, receiver) = channel();
            alignment.start(
                vec![PathBuf::from("a.ply"), PathBuf::from("b.ply")],
                receiver,
            );
            sender
                .send(Comparison::parse(json).map_err(|e| e.to_string()))
                .unwrap();
            assert_eq!(alignment.poll(), Some(true), "{json}");
        }
    }

    /// Nothing in the side panel moves when the comparison comes (or fails): the alignment
    /// lines take the same rows before, while and after it runs; a long reason is cut to one
    /// line (the panel moved down about 30 px, and a click aimed at Surface while "aligning the
    /// versions…" was shown landed on another row).
    #[test]
    fn the_compare_section_keeps_its_height_while_the_versions_are_aligned() {
        const ALIGNED: &str = r#"{"match": "quietest", "versions": [
            {"path": "a.wav", "match_gain_db": -2.0,
             "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0}},
            {"path": "b.wav", "match_gain_db": -5.8,
             "alignment": {"alignable": true, "offset_s": 0.731, "confidence": 0.86}}]}"#;
        const UNRELATED: &str = r#"{"match": "quietest", "versions": [
            {"path": "a.wav", "match_gain_db": 0.0,
             "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0}},
            {"path": "b.wav", "match_gain_db": -15.7,
             "alignment": {"alignable": false, "offset_s": 0.0, "confidence": 0.0,
              "reason": "the versions share no music: 0 % of A found in B (at least 40 % needed)"}}]}"#;
        let aligning = section_height(compare_shown(|alignment| {
            let (sender, receiver) = channel();
            alignment.start(
                vec![PathBuf::from("a.ply"), PathBuf::from("b.ply")],
                receiver,
            );
            std::mem::forget(sender);
        }));
        assert!(aligning > 0.0);
        for (what, height) in [
            ("before it starts", section_height(compare_shown(|_| {}))),
            ("aligned", section_height(compare_shown(answered(ALIGNED)))),
            (
                "not related",
                section_height(compare_shown(answered(UNRELATED))),
            ),
            (
                "failed",
                section_height(compare_shown(|alignment| {
                    let (sender, receiver) = channel();
                    alignment.start(vec![PathBuf::from("a.ply")], receiver);
                    sender
                        .send(Err(
                            "comparing failed: ModuleNotFoundError: No module named \
                               'loudscape_extract' and a great deal more"
                                .into(),
                        ))
                        .unwrap();
                    assert_eq!(alignment.poll(), Some(false));
                })),
            ),
            (
                "nothing to align",
                section_height(compare_shown(|alignment| {
                    alignment.unavailable(
                        vec![PathBuf::from("a.ply")],
                        "nothing to align: b.ply names no audio file that is there".into(),
                    )
                })),
            ),
        ] {
            assert_eq!(
                height, aligning,
                "{what}: the section is {height} px high, \
                 {aligning} px while aligning"
            );
        }
    }

    /// The difference's "matched" measure moves the version's level axes by the gain that
    /// brings it to A's loudness (its matching gain less A's), and says so.
    #[test]
    fn the_matched_measure_moves_a_versions_levels_by_its_gain_against_a() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format/song_v2.ply");
        let cloud = crate::data::cloud::load(&path).unwrap();
        let axes = &cloud.meta.axes;
        assert_eq!((axes.y.unit.as_str(), axes.x.unit.as_str()), ("dB", "s"));
        let alignment = CompareAlignment {
            comparison: Some(Comparison::parse(JSON).unwrap()),
            ..Default::default()
        };
        let (b, c) = (Listening::B, Listening(2));
        let aligned = aligned_b(&alignment, b, &cloud, false);
        assert!((aligned.meta.axes.x.min - (axes.x.min - 0.731)).abs() < 1e-9);
        assert_eq!(aligned.meta.axes.y.min, axes.y.min, "levels as they are");
        let matched = aligned_b(&alignment, b, &cloud, true);
        assert!((matched.meta.axes.y.min - (axes.y.min - 3.8)).abs() < 1e-9);
        assert!((matched.meta.axes.y.max - (axes.y.max - 3.8)).abs() < 1e-9);
        assert!((matched.meta.axes.x.min - (axes.x.min - 0.731)).abs() < 1e-9);
        assert_eq!(
            alignment.match_words(b).as_deref(),
            Some("B -3.8 dB to match A")
        );
        let matched = aligned_b(&alignment, c, &cloud, true);
        assert!((matched.meta.axes.y.max - (axes.y.max + 2.0)).abs() < 1e-9);
        assert_eq!(
            alignment.match_words(c).as_deref(),
            Some("C +2.0 dB to match A")
        );
        assert_eq!(alignment.match_words(Listening::A), None);
        // Nothing to move before the comparison: the cloud itself.
        let none = CompareAlignment::default();
        assert!(matches!(
            aligned_b(&none, b, &cloud, true),
            Cow::Borrowed(_)
        ));
    }

    /// A version with an edit (two segments of the time map) is moved point by point, each by
    /// its own segment's offset, not by the one overall offset.
    #[test]
    fn a_time_map_of_several_segments_moves_each_point_by_its_own() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format/song_v2.ply");
        let cloud = crate::data::cloud::load(&path).unwrap();
        let x = cloud.meta.axes.x.clone();
        let mid = (x.min + x.max) / 2.0;
        // B has a tenth of its length inserted in the middle: the second segment is that later.
        let gap = (x.max - x.min) / 10.0;
        let json = format!(
            r#"{{"match": "quietest", "versions": [
            {{"path": "a.wav", "match_gain_db": 0.0,
             "alignment": {{"alignable": true, "offset_s": 0.0, "confidence": 1.0}}}},
            {{"path": "b.wav", "match_gain_db": 0.0,
             "alignment": {{"alignable": true, "offset_s": 0.1, "confidence": 0.9,
              "segments": [
               {{"start_s": {lo}, "end_s": {mid}, "offset_s": 0.1, "correlation": 0.9}},
               {{"start_s": {mid}, "end_s": {hi}, "offset_s": {late}, "correlation": 0.9}}]}}}}]}}"#,
            lo = x.min,
            hi = x.max,
            late = 0.1 + gap,
        );
        let alignment = CompareAlignment {
            comparison: Some(Comparison::parse(&json).unwrap()),
            ..Default::default()
        };
        let moved = aligned_b(&alignment, Listening::B, &cloud, false);
        let axis = &moved.meta.axes.x;
        let (mut early, mut late) = (0, 0);
        for (p, q) in cloud.points.iter().zip(&moved.points) {
            let t_b = x.value_at(f64::from(p.position[0]));
            let t_a = axis.value_at(f64::from(q.position[0]));
            if t_b <= mid + 0.1 {
                assert!((t_b - t_a - 0.1).abs() < 1e-3, "{t_b} -> {t_a}");
                early += 1;
            } else if t_b >= mid + 0.1 + gap {
                assert!((t_b - t_a - 0.1 - gap).abs() < 1e-3, "{t_b} -> {t_a}");
                late += 1;
            }
        }
        assert!(early > 0 && late > 0, "{early} and {late} points checked");
    }
}
