//! `--align`, `--offset SECONDS` and `--match-loudness` of `render A --compare B` and
//! `video A --compare B`: B's cloud moved onto A's time (and, matched, onto A's loudness) before
//! both go onto the union axes, and the legend's words for it ("B aligned +0.731 s, -3.8 dB to
//! match A"). `--align` runs the extractor's comparison of the two songs' audio
//! (`extract::align::compare_audio`, docs/COMPARE.md "Releases"); `--offset` alone needs no
//! audio, and with `--align` it is added to the offset found (a nudge).

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
}

/// B moved as `draw` asks (see the module's words); `a` and `b` are the loaded clouds.
pub fn align_b(a: &PointCloud, b: PointCloud, draw: &DrawArgs) -> anyhow::Result<AlignedB> {
    if !draw.align && draw.offset.is_none() {
        return Ok(AlignedB {
            cloud: b,
            note: None,
        });
    }
    let mut found = None;
    let mut gain = None;
    if draw.align {
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
    let offset = match (found, draw.offset) {
        (None, None) => None,
        (found, nudge) => Some(found.unwrap_or(0.0) + nudge.unwrap_or(0.0)),
    };
    let mut cloud = b;
    if let Some(offset) = offset {
        align_in_time(&mut cloud, offset);
    }
    let matched = if draw.match_loudness { gain } else { None };
    if draw.match_loudness && matched.is_none() {
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
    })
}
