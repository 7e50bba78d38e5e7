//! Releases aligned and matched: the app's side of `loudscape-extract compare --json`
//! (docs/COMPARE.md, "Releases"). The extractor aligns every version to the first (an offset,
//! a time map of segments, a confidence, or "not alignable") and finds the gain that matches each
//! one's integrated loudness; this module runs it and reads its JSON, so the window and the
//! `compare` command use the same numbers.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde::Deserialize;

use super::locate;

/// One stretch of A whose music the version has at a constant offset.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Segment {
    pub start_s: f64,
    pub end_s: f64,
    pub offset_s: f64,
    pub correlation: f64,
}

/// How a version's time maps onto the first version's.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Alignment {
    pub alignable: bool,
    pub offset_s: f64,
    pub confidence: f64,
    #[serde(default)]
    pub segments: Vec<Segment>,
    #[serde(default)]
    pub reason: Option<String>,
}

impl Alignment {
    /// `cloud` (this version's) moved onto the first version's time, `nudge_s` added to the
    /// offset: through the time map's segments where it has several (a cut, an edit: each point
    /// by its own segment's offset), else by the one offset (the time axis alone). Not
    /// alignable: left as it is. The window, `render`/`video --compare --align` and the sheet's
    /// small multiples all move a version this way.
    pub fn move_onto_first(&self, cloud: &mut crate::data::cloud::PointCloud, nudge_s: f64) {
        if !self.alignable {
            return;
        }
        if self.segments.len() > 1 {
            crate::data::compare::align_by_map(cloud, |t| self.first_time(t) - nudge_s);
        } else {
            crate::data::compare::align_in_time(cloud, self.offset_s + nudge_s);
        }
    }

    /// The version's time of the music that plays at `t_a` in the first version: the
    /// segment holding `t_a` (else the nearest one) gives the offset; `t_a` itself when the
    /// pair is not alignable.
    pub fn version_time(&self, t_a: f64) -> f64 {
        if !self.alignable {
            return t_a;
        }
        let distance = |s: &Segment| {
            if (s.start_s..=s.end_s).contains(&t_a) {
                0.0
            } else {
                (t_a - s.start_s).abs().min((t_a - s.end_s).abs())
            }
        };
        let offset = self
            .segments
            .iter()
            .min_by(|a, b| distance(a).total_cmp(&distance(b)))
            .map_or(self.offset_s, |s| s.offset_s);
        t_a + offset
    }

    /// The first version's time of the music at `t_v` in this version (the inverse map):
    /// the segment whose stretch in this version holds `t_v`, else the nearest.
    pub fn first_time(&self, t_v: f64) -> f64 {
        if !self.alignable {
            return t_v;
        }
        let distance = |s: &Segment| {
            let (lo, hi) = (s.start_s + s.offset_s, s.end_s + s.offset_s);
            if (lo..=hi).contains(&t_v) {
                0.0
            } else {
                (t_v - lo).abs().min((t_v - hi).abs())
            }
        };
        let offset = self
            .segments
            .iter()
            .min_by(|a, b| distance(a).total_cmp(&distance(b)))
            .map_or(self.offset_s, |s| s.offset_s);
        t_v - offset
    }
}

/// One version of a comparison.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Version {
    pub path: String,
    pub alignment: Alignment,
    /// The gain that brings the version to the matching loudness (None: no integrated
    /// loudness, e.g. silence).
    pub match_gain_db: Option<f64>,
}

/// `loudscape-extract compare --json`'s output.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Comparison {
    #[serde(rename = "match")]
    pub matched_to: String,
    pub versions: Vec<Version>,
}

impl Comparison {
    /// Parses the extractor's JSON.
    pub fn parse(json: &str) -> Result<Comparison, String> {
        let parsed: Comparison = serde_json::from_str(json)
            .map_err(|e| format!("the extractor's comparison is not readable ({e})"))?;
        if parsed.versions.len() < 2 {
            return Err("the extractor's comparison has fewer than 2 versions".into());
        }
        Ok(parsed)
    }

    /// The legend's words for version `i` (1 = B): "B -3.8 dB to match A", or why not.
    pub fn gain_words(&self, i: usize) -> String {
        let letter = char::from(b'A' + i.min(25) as u8);
        match self.versions.get(i).and_then(|v| v.match_gain_db) {
            Some(gain) if self.matched_to == "quietest" => {
                format!("{letter} {gain:+.1} dB to match the quietest")
            }
            Some(gain) => format!("{letter} {gain:+.1} dB to {}", self.matched_to),
            None => format!("{letter} not matched (no integrated loudness)"),
        }
    }
}

/// Runs `loudscape-extract compare VERSIONS --json -q [--match M]` and reads its answer.
/// The versions are audio files (a cloud's source, [`crate::playback::checked_source`]).
pub fn compare_audio(versions: &[PathBuf], matched_to: &str) -> Result<Comparison, String> {
    let extractor = locate::extractor().map_err(|looked| locate::not_found(&looked))?;
    let mut command = Command::new(&extractor);
    command.arg("compare").arg("--json").arg("-q");
    command.arg("--match").arg(matched_to);
    command.arg("--");
    for version in versions {
        command.arg(absolute(version));
    }
    let output = command
        .output()
        .map_err(|e| format!("cannot run {}: {e}", extractor.display()))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        return Err(format!("comparing failed: {}", last.trim()));
    }
    Comparison::parse(&String::from_utf8_lossy(&output.stdout))
}

/// An absolute path, so a name starting with `-` is never read as an option.
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    const JSON: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "offset_s": 0.0, "match_gain_db": -0.3,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0, "segments": []}},
        {"path": "b.wav", "offset_s": 0.0, "match_gain_db": -2.04,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 0.9, "segments": [
            {"start_s": 0.0, "end_s": 30.0, "offset_s": 0.0, "correlation": 1.0},
            {"start_s": 32.0, "end_s": 58.0, "offset_s": -2.0, "correlation": 0.95}]}},
        {"path": "c.wav", "offset_s": null, "match_gain_db": null,
         "alignment": {"alignable": false, "offset_s": 0.0, "confidence": 0.0, "segments": [],
                       "reason": "the versions share no music"}}]}"#;

    #[test]
    fn reads_the_extractor_json_and_maps_time_both_ways() {
        let c = Comparison::parse(JSON).unwrap();
        assert_eq!(c.versions.len(), 3);
        let b = &c.versions[1].alignment;
        assert_eq!(b.version_time(10.0), 10.0);
        assert_eq!(b.version_time(40.0), 38.0);
        assert_eq!(b.first_time(38.0), 40.0);
        assert_eq!(b.first_time(10.0), 10.0);
        let unrelated = &c.versions[2].alignment;
        assert_eq!(unrelated.version_time(12.5), 12.5);
        assert_eq!(c.gain_words(1), "B -2.0 dB to match the quietest");
        assert_eq!(c.gain_words(2), "C not matched (no integrated loudness)");
    }

    #[test]
    fn refuses_what_is_not_a_comparison() {
        assert!(Comparison::parse("{}").is_err());
        assert!(Comparison::parse(r#"{"match": "quietest", "versions": []}"#).is_err());
    }
}
