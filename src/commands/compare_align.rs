//! `--align`, `--offset SECONDS` and `--match-loudness` of `render A --compare B` and
//! `video A --compare B`: B's cloud moved onto A's time (and, matched, onto A's loudness) before
//! both go onto the union axes, and the legend's words for it ("B aligned +0.731 s, -3.8 dB to
//! match A"). `--align` runs the extractor's comparison of the two songs' audio
//! (`extract::align::compare_audio`, docs/COMPARE.md "Releases"); `--offset` alone needs no
//! audio, and with `--align` it is added to the offset found (a nudge).

use anyhow::bail;
use loudscape::data::cloud::PointCloud;
use loudscape::data::compare::{align_in_time, aligned_words, match_in_level};
use loudscape::extract::align::compare_audio;
use loudscape::playback::checked_source;

use super::render::DrawArgs;

/// B as it is drawn against A: moved in time and level as asked, and what the legend says of it.
pub struct AlignedB {
    pub cloud: PointCloud,
    /// "B aligned +0.731 s, -3.8 dB to match A"; None when B is drawn as it is.
    pub note: Option<String>,
    /// B's offset against A in seconds (found and nudged), where B was moved in time.
    pub offset_s: Option<f64>,
    /// The gain B's levels were moved by, in dB, where they were matched to A's.
    pub gain_db: Option<f64>,
}

/// What is asked of B: `--align`, `--offset SECONDS`, `--match-loudness` (of `render`, `video`
/// and `page`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AlignAsk {
    pub align: bool,
    pub offset: Option<f64>,
    pub match_loudness: bool,
}

impl AlignAsk {
    /// The flags of `render` and `video`.
    pub fn of(draw: &DrawArgs) -> Self {
        Self {
            align: draw.align,
            offset: draw.offset,
            match_loudness: draw.match_loudness,
        }
    }

    /// Checks the flags before any work: `--match-loudness` needs the comparison (`--align`),
    /// and none of them means anything without `--compare` (`compared`: B is given); an offset
    /// is a finite number of seconds.
    pub fn check(&self, compared: bool) -> anyhow::Result<()> {
        let asked = self.align || self.offset.is_some() || self.match_loudness;
        if asked && !compared {
            bail!("--align, --offset and --match-loudness need a second cloud: --compare B");
        }
        if self.match_loudness && !self.align {
            bail!(
                "--match-loudness needs --align (the matching gain comes from comparing the audio)"
            );
        }
        if let Some(offset) = self.offset
            && (!offset.is_finite() || offset.abs() > 3600.0)
        {
            bail!("--offset {offset} is not a number of seconds between -3600 and 3600");
        }
        Ok(())
    }
}

// Here rather than in render.rs beside DrawArgs, so that render.rs does not import this file,
// which imports DrawArgs from it.
impl DrawArgs {
    /// Checks the flags before any work: `--match-loudness` needs the comparison (`--align`), and
    /// none of them means anything without `--compare`; an offset is a finite number of seconds.
    pub fn check_alignment(&self) -> anyhow::Result<()> {
        AlignAsk::of(self).check(self.compare.is_some())
    }
}

/// B moved as `draw` asks (see the module's words); `a` and `b` are the loaded clouds.
pub fn align_b(a: &PointCloud, b: PointCloud, draw: &DrawArgs) -> anyhow::Result<AlignedB> {
    align_b_as(a, b, AlignAsk::of(draw))
}

/// B moved as `ask` says (see the module's words); `a` and `b` are the loaded clouds.
pub fn align_b_as(a: &PointCloud, b: PointCloud, ask: AlignAsk) -> anyhow::Result<AlignedB> {
    if !ask.align && ask.offset.is_none() {
        return Ok(AlignedB {
            cloud: b,
            note: None,
            offset_s: None,
            gain_db: None,
        });
    }
    let mut found = None;
    let mut map = None;
    let mut gain = None;
    if ask.align {
        let audio = |cloud: &PointCloud| {
            checked_source(cloud).map_err(|e| {
                anyhow::anyhow!("{}: --align needs its audio: {e}", cloud.path.display())
            })
        };
        let versions = [audio(a)?, audio(&b)?];
        let comparison = compare_audio(&versions, "quietest").map_err(anyhow::Error::msg)?;
        let (first, version) = (&comparison.versions[0], &comparison.versions[1]);
        if version.alignment.alignable {
            found = Some(version.alignment.offset_s);
            map = Some(version.alignment.clone());
        } else {
            let reason = version
                .alignment
                .reason
                .as_deref()
                .unwrap_or("no shared music");
            eprintln!(
                "warning: {}: not aligned with {} ({reason}); drawn on its own clock",
                b.path.display(),
                a.path.display()
            );
        }
        // The gain that brings B to A's loudness: B's matching gain less A's.
        if let (Some(gain_a), Some(gain_b)) = (first.match_gain_db, version.match_gain_db) {
            gain = Some(gain_b - gain_a);
        }
    }
    let offset = match (found, ask.offset) {
        (None, None) => None,
        (found, nudge) => Some(found.unwrap_or(0.0) + nudge.unwrap_or(0.0)),
    };
    let mut cloud = b;
    match (map, offset) {
        (Some(map), _) => map.move_onto_first(&mut cloud, ask.offset.unwrap_or(0.0)),
        (None, Some(offset)) => align_in_time(&mut cloud, offset),
        (None, None) => {}
    }
    let matched = if ask.match_loudness { gain } else { None };
    if ask.match_loudness && matched.is_none() {
        eprintln!(
            "warning: {}: no integrated loudness to match (silence?); levels drawn as they are",
            cloud.path.display()
        );
    }
    if let Some(gain) = matched {
        match_in_level(&mut cloud, gain);
    }
    Ok(AlignedB {
        cloud,
        note: aligned_words(offset, matched),
        offset_s: offset,
        gain_db: matched,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use loudscape::data::cloud::DataMode;
    use loudscape::data::synthetic::synthetic_song;
    use loudscape::extract::align::Alignment;

    /// The time of every point of `cloud`, in seconds of its own axis.
    fn times(cloud: &PointCloud) -> Vec<f64> {
        let x = &cloud.meta.axes.x;
        cloud
            .points
            .iter()
            .map(|p| x.value_at(f64::from(p.position[0])))
            .collect()
    }

    /// An alignment as the extractor writes it (`extract::align`'s JSON).
    fn alignment(json: &str) -> Alignment {
        serde_json::from_str(json).expect("an alignment")
    }

    /// A version with an edit (2 s more from its 10 s on, 0.5 s later before): `render` and
    /// the sheet move each point by its own segment's offset, as the window does, and a nudge
    /// moves every point by itself; one segment moves the time axis alone.
    #[test]
    fn a_version_with_an_edit_moves_by_its_segments_and_the_nudge() {
        let b = PointCloud::synthetic(synthetic_song(5_000, 3), DataMode::Song);
        let own = times(&b);
        let map = alignment(
            r#"{"alignable": true, "offset_s": 0.5, "confidence": 0.9, "segments": [
                {"start_s": 0.0, "end_s": 9.5, "offset_s": 0.5, "correlation": 0.9},
                {"start_s": 9.5, "end_s": 40.0, "offset_s": 2.5, "correlation": 0.9}]}"#,
        );
        for nudge in [0.0, 0.1] {
            let mut moved = b.clone();
            map.move_onto_first(&mut moved, nudge);
            for (t_b, t_a) in own.iter().zip(times(&moved)) {
                let expected = map.first_time(*t_b) - nudge;
                assert!((t_a - expected).abs() < 1e-3, "{t_b} s went to {t_a} s");
            }
            // Both segments are in use: the points after the edit moved 2 s more.
            let later = own.iter().zip(times(&moved)).filter(|(b, a)| *b - *a > 2.4);
            assert!(later.count() > 100);
        }
        let one = alignment(r#"{"alignable": true, "offset_s": 0.731, "confidence": 0.9}"#);
        let mut moved = b.clone();
        one.move_onto_first(&mut moved, 0.0);
        assert_eq!(
            moved.points, b.points,
            "one offset moves the axis, not the points"
        );
        assert!((b.meta.axes.x.min - moved.meta.axes.x.min - 0.731).abs() < 1e-9);
        let unrelated = alignment(r#"{"alignable": false, "offset_s": 3.0, "confidence": 0.1}"#);
        let mut kept = b.clone();
        unrelated.move_onto_first(&mut kept, 0.0);
        assert_eq!(kept.meta.axes.x, b.meta.axes.x);
    }
}
