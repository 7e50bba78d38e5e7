//! The compare's releases aligned and matched, as the window keeps them (the `alignment` field
//! of `CompareState`): the extractor's comparison of every version's audio, A first (run on a
//! thread by `ui/compare_align.rs`, `extract::align::compare_audio`), the "match loudness"
//! switch and each version's manual nudge; and what follows from them: the time a switch seeks
//! to (the same moment of the music, through each version's own alignment to A), the gain each
//! version plays at, a version's offset for the pictures, and the panel's words.

use std::sync::mpsc::{Receiver, TryRecvError};

use crate::extract::align::{Alignment, Comparison};

/// Which version is heard: 0 is A (the Song slot's cloud), 1 B, 2 C... (at most 8 in all).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) struct Listening(pub(in crate::ui) usize);

impl Listening {
    pub(in crate::ui) const A: Listening = Listening(0);
    pub(in crate::ui) const B: Listening = Listening(1);

    /// The next version of `count` in all (key B: A -> B -> C -> A).
    pub(in crate::ui) fn next(self, count: usize) -> Self {
        Listening((self.0 + 1) % count.max(1))
    }

    /// The version's letter: "A", "B", "C"...
    pub(in crate::ui) fn letter(self) -> char {
        char::from(b'A' + self.0.min(25) as u8)
    }
}

/// The most versions a compare holds, A included (as `loudscape compare` takes).
pub(in crate::ui) const MAX_VERSIONS: usize = 8;

/// One step of the nudge buttons, seconds: -100, -10, +10 and +100 ms.
pub(in crate::ui) const NUDGE_STEPS_S: [f64; 4] = [-0.1, -0.01, 0.01, 0.1];

/// The versions aligned in time and matched in loudness.
pub(in crate::ui) struct CompareAlignment {
    /// The comparison running on a thread, while it runs.
    pub(in crate::ui) receiver: Option<Receiver<Result<Comparison, String>>>,
    /// The versions it was asked for (their clouds, A first), so it is asked once a list.
    pub(in crate::ui) asked_for: Option<Vec<std::path::PathBuf>>,
    pub(in crate::ui) comparison: Option<Comparison>,
    /// Why there is none (no audio, the extractor failed).
    pub(in crate::ui) error: Option<String>,
    /// Each version plays at its matching gain (on by default).
    pub(in crate::ui) match_loudness: bool,
    /// The user's correction of each version's offset, seconds (added to the found one),
    /// indexed as [`Listening`] (A's is never used).
    pub(in crate::ui) nudges_s: Vec<f64>,
}

impl Default for CompareAlignment {
    fn default() -> Self {
        Self {
            receiver: None,
            asked_for: None,
            comparison: None,
            error: None,
            match_loudness: true,
            nudges_s: Vec::new(),
        }
    }
}

impl CompareAlignment {
    /// Waits for `receiver`'s comparison of `versions`.
    pub(in crate::ui) fn start(
        &mut self,
        versions: Vec<std::path::PathBuf>,
        receiver: Receiver<Result<Comparison, String>>,
    ) {
        self.asked_for = Some(versions);
        self.receiver = Some(receiver);
        self.comparison = None;
        self.error = None;
    }

    /// Takes the comparison (or why it failed) once it has come: `Some(true)` when it came now
    /// (the pictures are built again with the version aligned), `Some(false)` when it failed
    /// now, None while it runs or when nothing runs.
    pub(in crate::ui) fn poll(&mut self) -> Option<bool> {
        let receiver = self.receiver.as_ref()?;
        let came = match receiver.try_recv() {
            Ok(Ok(comparison)) => {
                self.comparison = Some(comparison);
                true
            }
            Ok(Err(e)) => {
                self.error = Some(e);
                false
            }
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => {
                self.error = Some("the comparison stopped".into());
                false
            }
        };
        self.receiver = None;
        Some(came)
    }

    /// Whether the comparison runs now ("aligning the versions…").
    pub(in crate::ui) fn aligning(&self) -> bool {
        self.receiver.is_some()
    }

    /// The versions compared, A included (0 before the comparison has come).
    pub(in crate::ui) fn count(&self) -> usize {
        self.comparison.as_ref().map_or(0, |c| c.versions.len())
    }

    /// The nudge of `version`'s offset, seconds.
    pub(in crate::ui) fn nudge_s(&self, version: Listening) -> f64 {
        self.nudges_s.get(version.0).copied().unwrap_or(0.0)
    }

    /// `version`'s alignment against A with its nudge added; None for A itself and before the
    /// comparison has come. A version found unrelated keeps its "not alignable" (the nudge
    /// alone moves nothing).
    pub(in crate::ui) fn alignment(&self, version: Listening) -> Option<Alignment> {
        if version == Listening::A {
            return None;
        }
        let mut alignment = self
            .comparison
            .as_ref()?
            .versions
            .get(version.0)?
            .alignment
            .clone();
        if alignment.alignable {
            let nudge = self.nudge_s(version);
            alignment.offset_s += nudge;
            for segment in &mut alignment.segments {
                segment.offset_s += nudge;
            }
        }
        Some(alignment)
    }

    /// `version`'s offset against A for the pictures (its time of A's moment `t` is
    /// `t + offset`), None when it is not aligned (A itself, no comparison yet, or unrelated).
    pub(in crate::ui) fn offset_s(&self, version: Listening) -> Option<f64> {
        if version == Listening::A {
            return None;
        }
        // Read in place: the panel asks every frame, and alignment() copies the segments.
        let found = &self.comparison.as_ref()?.versions.get(version.0)?.alignment;
        found
            .alignable
            .then_some(found.offset_s + self.nudge_s(version))
    }

    /// The time a switch from `from` to `to` seeks to, `t` being `from`'s time now: the same
    /// moment of the music (A's time of `from`'s `t` through `from`'s own alignment, then
    /// `to`'s time of that through `to`'s), never before the start; the same clock time where
    /// a version is not aligned.
    pub(in crate::ui) fn target_time(&self, from: Listening, to: Listening, t: f64) -> f64 {
        let t_a = self.alignment(from).map_or(t, |a| a.first_time(t));
        let mapped = self.alignment(to).map_or(t_a, |a| a.version_time(t_a));
        mapped.max(0.0)
    }

    /// The gain `version` plays at, dB: its matching gain while "match loudness" is on and
    /// the comparison has one, else 0.
    pub(in crate::ui) fn gain_db(&self, version: Listening) -> f64 {
        if !self.match_loudness {
            return 0.0;
        }
        self.matching_gain_db(version).unwrap_or(0.0)
    }

    /// The matching gain the comparison found for `version`, whether it is applied or not.
    pub(in crate::ui) fn matching_gain_db(&self, version: Listening) -> Option<f64> {
        self.comparison
            .as_ref()?
            .versions
            .get(version.0)?
            .match_gain_db
    }

    /// The gain that brings `version`'s levels to A's loudness (its matching gain less A's),
    /// dB: what the difference's "matched" measure shifts it by; None for A, before the
    /// comparison, or where either has no integrated loudness.
    pub(in crate::ui) fn level_match_db(&self, version: Listening) -> Option<f64> {
        if version == Listening::A {
            return None;
        }
        Some(self.matching_gain_db(version)? - self.matching_gain_db(Listening::A)?)
    }

    /// The legend's words for the "matched" difference: "C -3.8 dB to match A".
    pub(in crate::ui) fn match_words(&self, version: Listening) -> Option<String> {
        let gain = self.level_match_db(version)?;
        Some(format!("{} {gain:+.1} dB to match A", version.letter()))
    }

    /// `versions` cannot be aligned (`reason`: a version without its audio): not asked again
    /// for the same list.
    pub(in crate::ui) fn unavailable(&mut self, versions: Vec<std::path::PathBuf>, reason: String) {
        self.asked_for = Some(versions);
        self.comparison = None;
        self.error = Some(reason);
    }

    /// Plays each version at its matching gain, or each as it is (the panel's checkbox).
    pub(in crate::ui) fn set_match_loudness(&mut self, on: bool) {
        self.match_loudness = on;
    }

    /// Moves `version`'s offset by `delta_s` (a nudge button).
    pub(in crate::ui) fn nudge(&mut self, version: Listening, delta_s: f64) {
        if self.nudges_s.len() <= version.0 {
            self.nudges_s.resize(version.0 + 1, 0.0);
        }
        let nudge = &mut self.nudges_s[version.0];
        // Whole tenths of a millisecond, so ten +10 ms steps are exactly +100 ms.
        *nudge = ((*nudge + delta_s) * 10_000.0).round() / 10_000.0;
    }

    /// The panel's words beside a version's letter: "B -3.8 dB" (the matching gain, struck
    /// out in words when matching is off), or the letter alone before the comparison.
    pub(in crate::ui) fn gain_label(&self, version: Listening) -> String {
        let name = version.letter();
        match self.matching_gain_db(version) {
            Some(gain) if self.match_loudness => format!("{name} {}", signed_db(gain)),
            Some(gain) => format!("{name} (would be {})", signed_db(gain)),
            None => name.to_string(),
        }
    }

    /// The panel's line about `version`'s offset: "B starts 0.731 s later, 86 %" (with the
    /// nudge said when there is one), "B not aligned: <reason>", or None (A, or before the
    /// comparison).
    pub(in crate::ui) fn offset_line(&self, version: Listening) -> Option<String> {
        let alignment = self.alignment(version)?;
        let name = version.letter();
        if !alignment.alignable {
            let reason = alignment
                .reason
                .unwrap_or_else(|| "the versions share no music".into());
            return Some(format!("{name} not aligned: {reason}"));
        }
        let offset = alignment.offset_s;
        let when = if offset.abs() < 0.0005 {
            format!("{name} starts with A")
        } else if offset > 0.0 {
            format!("{name} starts {offset:.3} s later")
        } else {
            format!("{name} starts {:.3} s earlier", -offset)
        };
        let confidence = (alignment.confidence * 100.0).round();
        let nudge = self.nudge_s(version);
        let nudged = if nudge == 0.0 {
            String::new()
        } else {
            format!(" (nudged {:+.0} ms)", nudge * 1000.0)
        };
        Some(format!("{when}, {confidence} %{nudged}"))
    }
}

/// "-3.8 dB" with a true minus sign, "+1.2 dB".
fn signed_db(db: f64) -> String {
    let text = format!("{db:+.1} dB");
    text.replacen('-', "\u{2212}", 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const JSON: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0, "segments": []}},
        {"path": "b.wav", "match_gain_db": -3.8,
         "alignment": {"alignable": true, "offset_s": 0.731, "confidence": 0.86,
                       "segments": []}}]}"#;

    const UNRELATED: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0, "segments": []}},
        {"path": "c.wav", "match_gain_db": -1.5,
         "alignment": {"alignable": false, "offset_s": 0.0, "confidence": 0.1, "segments": [],
                       "reason": "the versions share no music"}}]}"#;

    fn aligned(json: &str) -> CompareAlignment {
        CompareAlignment {
            comparison: Some(Comparison::parse(json).unwrap()),
            ..Default::default()
        }
    }

    #[test]
    fn a_switch_seeks_to_the_same_moment_of_the_music() {
        let state = aligned(JSON);
        assert!((state.target_time(Listening::A, Listening::B, 12.5) - 13.231).abs() < 1e-9);
        assert!((state.target_time(Listening::B, Listening::A, 13.231) - 12.5).abs() < 1e-9);
        // B's first 0.731 s are before A's music: A starts at its beginning.
        assert_eq!(state.target_time(Listening::B, Listening::A, 0.2), 0.0);
        // Nothing aligned yet: the same clock time.
        assert_eq!(
            CompareAlignment::default().target_time(Listening::A, Listening::B, 12.5),
            12.5
        );
        // Unrelated songs: the same clock time too.
        assert_eq!(
            aligned(UNRELATED).target_time(Listening::A, Listening::B, 12.5),
            12.5
        );
    }

    #[test]
    fn each_side_plays_at_its_matching_gain_while_matching_is_on() {
        let mut state = aligned(JSON);
        assert!(state.match_loudness, "on by default");
        assert_eq!(state.gain_db(Listening::A), 0.0);
        assert_eq!(state.gain_db(Listening::B), -3.8);
        assert_eq!(state.gain_label(Listening::B), "B \u{2212}3.8 dB");
        state.match_loudness = false;
        assert_eq!(state.gain_db(Listening::B), 0.0);
        assert_eq!(
            state.gain_label(Listening::B),
            "B (would be \u{2212}3.8 dB)"
        );
        assert_eq!(CompareAlignment::default().gain_db(Listening::B), 0.0);
        assert_eq!(CompareAlignment::default().gain_label(Listening::B), "B");
    }

    #[test]
    fn the_nudge_moves_b_and_is_said() {
        let mut state = aligned(JSON);
        assert_eq!(
            state.offset_line(Listening::B).as_deref(),
            Some("B starts 0.731 s later, 86 %")
        );
        for _ in 0..10 {
            state.nudge(Listening::B, 0.01);
        }
        state.nudge(Listening::B, -0.1);
        state.nudge(Listening::B, -0.01);
        assert_eq!(state.nudge_s(Listening::B), -0.01);
        assert!((state.offset_s(Listening::B).unwrap() - 0.721).abs() < 1e-9);
        assert!((state.target_time(Listening::A, Listening::B, 12.5) - 13.221).abs() < 1e-9);
        assert_eq!(
            state.offset_line(Listening::B).as_deref(),
            Some("B starts 0.721 s later, 86 % (nudged -10 ms)")
        );
    }

    #[test]
    fn an_unrelated_pair_is_said_and_not_moved() {
        let mut state = aligned(UNRELATED);
        state.nudge(Listening::B, 0.1);
        assert_eq!(state.offset_s(Listening::B), None);
        assert_eq!(
            state.offset_line(Listening::B).as_deref(),
            Some("B not aligned: the versions share no music")
        );
        // Loudness is still matched.
        assert_eq!(state.gain_db(Listening::B), -1.5);
    }

    #[test]
    fn a_comparison_arriving_is_taken_once() {
        let mut state = CompareAlignment::default();
        assert_eq!(state.poll(), None);
        let (sender, receiver) = std::sync::mpsc::channel();
        state.start(vec!["a.wav".into(), "b.wav".into()], receiver);
        assert!(state.aligning());
        assert_eq!(state.poll(), None);
        sender.send(Comparison::parse(JSON)).unwrap();
        assert_eq!(state.poll(), Some(true));
        assert!(!state.aligning());
        assert_eq!(state.poll(), None);
        assert!(state.offset_s(Listening::B).is_some());
    }

    /// A, B 0.731 s later and 3.8 dB louder, C 0.25 s earlier and 1.5 dB louder: key B steps
    /// A -> B -> C -> A, each step to the same moment of the music through each version's own
    /// alignment to A, each version at its own gain.
    const THREE: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0, "segments": []}},
        {"path": "b.wav", "match_gain_db": -3.8,
         "alignment": {"alignable": true, "offset_s": 0.731, "confidence": 0.86,
                       "segments": []}},
        {"path": "c.wav", "match_gain_db": -1.5,
         "alignment": {"alignable": true, "offset_s": -0.25, "confidence": 0.9,
                       "segments": []}}]}"#;

    #[test]
    fn key_b_steps_through_every_version_at_the_same_moment() {
        let mut state = aligned(THREE);
        assert_eq!(state.count(), 3);
        let (a, b, c) = (Listening::A, Listening::B, Listening(2));
        assert_eq!(a.next(3), b);
        assert_eq!(b.next(3), c);
        assert_eq!(c.next(3), a);
        assert_eq!(c.letter(), 'C');
        // A 12.5 s -> B 13.231 s -> C 12.25 s -> A 12.5 s.
        let at_b = state.target_time(a, b, 12.5);
        assert!((at_b - 13.231).abs() < 1e-9, "{at_b}");
        let at_c = state.target_time(b, c, at_b);
        assert!((at_c - 12.25).abs() < 1e-9, "{at_c}");
        let at_a = state.target_time(c, a, at_c);
        assert!((at_a - 12.5).abs() < 1e-9, "{at_a}");
        assert_eq!(state.gain_db(c), -1.5);
        assert_eq!(state.gain_label(c), "C \u{2212}1.5 dB");
        assert_eq!(
            state.offset_line(c).as_deref(),
            Some("C starts 0.250 s earlier, 90 %")
        );
        assert_eq!(state.offset_line(a), None, "A is the reference");
        // A nudge moves its own version only.
        state.nudge(c, 0.01);
        assert!((state.offset_s(c).unwrap() + 0.24).abs() < 1e-9);
        assert!((state.offset_s(b).unwrap() - 0.731).abs() < 1e-9);
        assert!((state.target_time(b, c, at_b) - 12.26).abs() < 1e-9);
    }
}
