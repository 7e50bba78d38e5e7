//! The compare's releases aligned and matched, as the window keeps them (the `alignment` field
//! of `CompareState`): the extractor's comparison of A's and B's audio (run on a thread by
//! `ui/compare_align.rs`, `extract::align::compare_audio`), the "match loudness" switch and the
//! manual nudge of B's offset; and what follows from them: the time a switch seeks to (the
//! same moment of the music), the gain each side plays at, B's offset for the pictures, and the
//! panel's words.

use std::sync::mpsc::{Receiver, TryRecvError};

use crate::extract::align::{Alignment, Comparison};

/// Which song is heard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::ui) enum Listening {
    A,
    B,
}

impl Listening {
    /// The other song (key B).
    pub(in crate::ui) fn other(self) -> Self {
        match self {
            Listening::A => Listening::B,
            Listening::B => Listening::A,
        }
    }
}

/// One step of the nudge buttons, seconds: -100, -10, +10 and +100 ms.
pub(in crate::ui) const NUDGE_STEPS_S: [f64; 4] = [-0.1, -0.01, 0.01, 0.1];

/// A and B aligned in time and matched in loudness.
pub(in crate::ui) struct CompareAlignment {
    /// The comparison running on a thread, while it runs.
    pub(in crate::ui) receiver: Option<Receiver<Result<Comparison, String>>>,
    /// The pair it was asked for (A's and B's audio), so it is asked once a pair.
    pub(in crate::ui) asked_for: Option<(std::path::PathBuf, std::path::PathBuf)>,
    pub(in crate::ui) comparison: Option<Comparison>,
    /// Why there is none (no audio, the extractor failed).
    pub(in crate::ui) error: Option<String>,
    /// Each side plays at its matching gain (on by default).
    pub(in crate::ui) match_loudness: bool,
    /// The user's correction of B's offset, seconds (added to the found one).
    pub(in crate::ui) nudge_s: f64,
}

impl Default for CompareAlignment {
    fn default() -> Self {
        Self {
            receiver: None,
            asked_for: None,
            comparison: None,
            error: None,
            match_loudness: true,
            nudge_s: 0.0,
        }
    }
}

/// Which version of the comparison a side is.
fn index(side: Listening) -> usize {
    match side {
        Listening::A => 0,
        Listening::B => 1,
    }
}

impl CompareAlignment {
    /// Waits for `receiver`'s comparison of `pair`.
    pub(in crate::ui) fn start(
        &mut self,
        pair: (std::path::PathBuf, std::path::PathBuf),
        receiver: Receiver<Result<Comparison, String>>,
    ) {
        self.asked_for = Some(pair);
        self.receiver = Some(receiver);
        self.comparison = None;
        self.error = None;
    }

    /// Takes the comparison (or why it failed) once it has come: `Some(true)` when it came now
    /// (the pictures are built again with B aligned), `Some(false)` when it failed now, None
    /// while it runs or when nothing runs.
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

    /// Whether the comparison runs now ("aligning A and B…").
    pub(in crate::ui) fn aligning(&self) -> bool {
        self.receiver.is_some()
    }

    /// B's alignment against A with the nudge added; None before the comparison has come.
    /// A pair found unrelated keeps its "not alignable" (the nudge alone moves nothing).
    pub(in crate::ui) fn b_alignment(&self) -> Option<Alignment> {
        let mut alignment = self.comparison.as_ref()?.versions.get(1)?.alignment.clone();
        if alignment.alignable {
            alignment.offset_s += self.nudge_s;
            for segment in &mut alignment.segments {
                segment.offset_s += self.nudge_s;
            }
        }
        Some(alignment)
    }

    /// B's offset against A for the pictures (B's time of A's moment `t` is `t + offset`),
    /// None when B is not aligned (no comparison yet, or an unrelated pair).
    pub(in crate::ui) fn offset_s(&self) -> Option<f64> {
        // Read in place: the panel asks every frame, and b_alignment copies the segments.
        let found = &self.comparison.as_ref()?.versions.get(1)?.alignment;
        found.alignable.then_some(found.offset_s + self.nudge_s)
    }

    /// The time a switch to `to` seeks to, `t` being the time of the side heard now: the same
    /// moment of the music (A -> B: B's time of A's `t`; B -> A: A's time of B's `t`), never
    /// before the start; `t` itself while nothing is aligned.
    pub(in crate::ui) fn target_time(&self, to: Listening, t: f64) -> f64 {
        let Some(alignment) = self.b_alignment() else {
            return t;
        };
        let mapped = match to {
            Listening::B => alignment.version_time(t),
            Listening::A => alignment.first_time(t),
        };
        mapped.max(0.0)
    }

    /// The gain `side` plays at, dB: its matching gain while "match loudness" is on and the
    /// comparison has one, else 0.
    pub(in crate::ui) fn gain_db(&self, side: Listening) -> f64 {
        if !self.match_loudness {
            return 0.0;
        }
        self.matching_gain_db(side).unwrap_or(0.0)
    }

    /// The matching gain the comparison found for `side`, whether it is applied or not.
    pub(in crate::ui) fn matching_gain_db(&self, side: Listening) -> Option<f64> {
        self.comparison
            .as_ref()?
            .versions
            .get(index(side))?
            .match_gain_db
    }

    /// Moves B's offset by `delta_s` (a nudge button).
    pub(in crate::ui) fn nudge(&mut self, delta_s: f64) {
        // Whole tenths of a millisecond, so ten +10 ms steps are exactly +100 ms.
        self.nudge_s = ((self.nudge_s + delta_s) * 10_000.0).round() / 10_000.0;
    }

    /// The panel's words beside a side's name: "B -3.8 dB" (the matching gain, struck out in
    /// words when matching is off), or the name alone before the comparison.
    pub(in crate::ui) fn gain_label(&self, side: Listening) -> String {
        let name = if side == Listening::A { "A" } else { "B" };
        match self.matching_gain_db(side) {
            Some(gain) if self.match_loudness => format!("{name} {}", signed_db(gain)),
            Some(gain) => format!("{name} (would be {})", signed_db(gain)),
            None => name.to_string(),
        }
    }

    /// The panel's line about the offset: "B starts 0.731 s later, 86 %" (with the nudge
    /// said when there is one), "not aligned: <reason>", or None before the comparison.
    pub(in crate::ui) fn offset_line(&self) -> Option<String> {
        let alignment = self.b_alignment()?;
        if !alignment.alignable {
            let reason = alignment
                .reason
                .unwrap_or_else(|| "the versions share no music".into());
            return Some(format!("not aligned: {reason}"));
        }
        let offset = alignment.offset_s;
        let when = if offset.abs() < 0.0005 {
            "B starts with A".to_string()
        } else if offset > 0.0 {
            format!("B starts {offset:.3} s later")
        } else {
            format!("B starts {:.3} s earlier", -offset)
        };
        let confidence = (alignment.confidence * 100.0).round();
        let nudged = if self.nudge_s == 0.0 {
            String::new()
        } else {
            format!(" (nudged {:+.0} ms)", self.nudge_s * 1000.0)
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
        assert!((state.target_time(Listening::B, 12.5) - 13.231).abs() < 1e-9);
        assert!((state.target_time(Listening::A, 13.231) - 12.5).abs() < 1e-9);
        // B's first 0.731 s are before A's music: A starts at its beginning.
        assert_eq!(state.target_time(Listening::A, 0.2), 0.0);
        // Nothing aligned yet: the same clock time.
        assert_eq!(
            CompareAlignment::default().target_time(Listening::B, 12.5),
            12.5
        );
        // Unrelated songs: the same clock time too.
        assert_eq!(aligned(UNRELATED).target_time(Listening::B, 12.5), 12.5);
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
            state.offset_line().as_deref(),
            Some("B starts 0.731 s later, 86 %")
        );
        for _ in 0..10 {
            state.nudge(0.01);
        }
        state.nudge(-0.1);
        state.nudge(-0.01);
        assert_eq!(state.nudge_s, -0.01);
        assert!((state.offset_s().unwrap() - 0.721).abs() < 1e-9);
        assert!((state.target_time(Listening::B, 12.5) - 13.221).abs() < 1e-9);
        assert_eq!(
            state.offset_line().as_deref(),
            Some("B starts 0.721 s later, 86 % (nudged -10 ms)")
        );
    }

    #[test]
    fn an_unrelated_pair_is_said_and_not_moved() {
        let mut state = aligned(UNRELATED);
        state.nudge(0.1);
        assert_eq!(state.offset_s(), None);
        assert_eq!(
            state.offset_line().as_deref(),
            Some("not aligned: the versions share no music")
        );
        // Loudness is still matched.
        assert_eq!(state.gain_db(Listening::B), -1.5);
    }

    #[test]
    fn a_comparison_arriving_is_taken_once() {
        let mut state = CompareAlignment::default();
        assert_eq!(state.poll(), None);
        let (sender, receiver) = std::sync::mpsc::channel();
        state.start(("a.wav".into(), "b.wav".into()), receiver);
        assert!(state.aligning());
        assert_eq!(state.poll(), None);
        sender.send(Comparison::parse(JSON)).unwrap();
        assert_eq!(state.poll(), Some(true));
        assert!(!state.aligning());
        assert_eq!(state.poll(), None);
        assert!(state.offset_s().is_some());
    }
}
