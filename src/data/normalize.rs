//! The timeline as heard: each song's y shifted by the gain a playback normalization (a
//! streaming service or a broadcast standard) applies to it, from the song's integrated
//! loudness and true peak in the metadata. Used by `loudscape render --normalize`, `video`
//! and the window's "level as heard" choice (`ui::normalize`). The rules and their sources:
//! docs/DYNAMICS.md ("Streaming normalization"); the same presets as `--normalize` of the report
//! (`preprocess/loudscape_extract/normalization.py`, `PRESETS`).

use crate::data::cloud::{Aabb, DataMode, PointCloud};

/// How a streaming service turns a song up when it is quieter than the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TurnUp {
    /// Only as far as the true peak stays at or below this ceiling (dBTP).
    PeakCeiling(f64),
    /// To the target whatever the peak (the service limits the peaks).
    Free,
    /// Never: the service only turns down.
    Never,
}

/// A playback normalization rule: `gain = target - integrated loudness`, positive gain
/// limited by [`TurnUp`]. Keep in sync with `preprocess/loudscape_extract/normalization.py`
/// (sources in docs/DYNAMICS.md, "Streaming normalization").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamingService {
    pub name: &'static str,
    pub target_lufs: f64,
    pub turn_up: TurnUp,
}

pub const STREAMING_SERVICES: [StreamingService; 5] = [
    StreamingService {
        name: "Spotify (normal)",
        target_lufs: -14.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
    StreamingService {
        name: "Spotify (loud)",
        target_lufs: -11.0,
        turn_up: TurnUp::Free,
    },
    StreamingService {
        name: "Spotify (quiet)",
        target_lufs: -19.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
    StreamingService {
        name: "YouTube",
        target_lufs: -14.0,
        turn_up: TurnUp::Never,
    },
    StreamingService {
        name: "AES TD1008 (track)",
        target_lufs: -16.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
];

/// The playback gain in dB (negative: turned down) `service` applies to a song; None without
/// an integrated loudness, or when turning up needs a true peak the file does not give.
pub fn normalization_gain(
    service: &StreamingService,
    integrated_lufs: Option<f64>,
    true_peak_dbtp: Option<f64>,
) -> Option<f64> {
    let integrated = integrated_lufs.filter(|v| v.is_finite())?;
    let gain = service.target_lufs - integrated;
    if gain <= 0.0 {
        return Some(gain);
    }
    match service.turn_up {
        TurnUp::Free => Some(gain),
        TurnUp::Never => Some(0.0),
        TurnUp::PeakCeiling(ceiling) => {
            let peak = true_peak_dbtp.filter(|v| v.is_finite())?;
            Some(gain.min(ceiling - peak).max(0.0))
        }
    }
}

/// A `--normalize` preset: its key (as in the report's `--normalize`) and its rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preset {
    pub key: &'static str,
    pub service: StreamingService,
}

/// Every preset: the streaming services of [`STREAMING_SERVICES`], then broadcast (EBU R 128
/// at -23 LUFS and ATSC A/85 at -24 LKFS: programmes are brought to the target both ways, a
/// limiter keeping the true peak under the ceiling).
pub const PRESETS: [Preset; 7] = [
    Preset {
        key: "spotify",
        service: STREAMING_SERVICES[0],
    },
    Preset {
        key: "spotify_loud",
        service: STREAMING_SERVICES[1],
    },
    Preset {
        key: "spotify_quiet",
        service: STREAMING_SERVICES[2],
    },
    Preset {
        key: "youtube",
        service: STREAMING_SERVICES[3],
    },
    Preset {
        key: "aes_td1008",
        service: STREAMING_SERVICES[4],
    },
    Preset {
        key: "ebu_r128",
        service: StreamingService {
            name: "EBU R 128 (broadcast)",
            target_lufs: -23.0,
            turn_up: TurnUp::Free,
        },
    },
    Preset {
        key: "atsc_a85",
        service: StreamingService {
            name: "ATSC A/85 (broadcast)",
            target_lufs: -24.0,
            turn_up: TurnUp::Free,
        },
    },
];

/// The key names `--normalize` accepts, for messages.
pub fn preset_names() -> String {
    std::iter::once("none")
        .chain(PRESETS.iter().map(|p| p.key))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `"none"` -> `Ok(None)`; a preset's key -> that preset; anything else an error naming the
/// choices.
pub fn parse_preset(key: &str) -> Result<Option<Preset>, String> {
    if key == "none" {
        return Ok(None);
    }
    PRESETS
        .iter()
        .find(|p| p.key == key)
        .copied()
        .map(Some)
        .ok_or_else(|| format!("normalization '{key}' is not one of {}", preset_names()))
}

/// Metadata key (in each song's object) of the gain a normalized cloud was shifted by.
pub const GAIN_KEY: &str = "normalization_gain_db";
/// Metadata key (in each song's object) of the preset's name.
pub const PRESET_KEY: &str = "normalization";

/// How far (in normalized y units) a gain of `gain_db` moves a point on an axis from
/// `min` to `max` dB over [-1, 1].
pub fn y_shift(gain_db: f64, min: f64, max: f64) -> f32 {
    if max > min {
        (2.0 * gain_db / (max - min)) as f32
    } else {
        0.0
    }
}

/// A copy of the timeline `cloud` as heard under `preset`: each song's points moved on y by
/// the preset's gain for it (clamped to the axis, as the extractor clamps), the y axis
/// titled "…, as heard on <service>", and the gain recorded in each song's object
/// ([`GAIN_KEY`], [`PRESET_KEY`]) for the read-out. A song without an integrated loudness
/// (or a true peak a turn-up needs) stays where it is, its gain recorded as unknown.
///
/// Errors: not a timeline, or a song without a valid point range.
pub fn normalized(cloud: &PointCloud, preset: &Preset) -> Result<PointCloud, String> {
    if cloud.meta.mode != DataMode::Timeline {
        return Err(format!(
            "{}: normalization applies to a timeline, not a song cloud",
            cloud.path.display()
        ));
    }
    let mut out = cloud.clone();
    let (min, max) = (out.meta.axes.y.min, out.meta.axes.y.max);
    for (index, song) in out.meta.songs.iter_mut().enumerate() {
        let range = point_range(&song.extra).filter(|r| r.end <= out.points.len());
        let Some(range) = range else {
            return Err(format!(
                "{}: songs[{index}] has no valid point_offset and point_count",
                cloud.path.display()
            ));
        };
        let metrics = song.metrics.clone().unwrap_or_default();
        let gain = normalization_gain(
            &preset.service,
            metrics.integrated_lufs,
            metrics.true_peak_dbtp,
        );
        if let Some(gain) = gain {
            let shift = y_shift(gain, min, max);
            for point in &mut out.points[range] {
                point.position[1] = (point.position[1] + shift).clamp(-1.0, 1.0);
            }
        }
        song.extra.insert(
            GAIN_KEY.into(),
            gain.map_or(serde_json::Value::Null, |g| {
                serde_json::json!((g * 100.0).round() / 100.0)
            }),
        );
        song.extra
            .insert(PRESET_KEY.into(), preset.service.name.into());
    }
    out.meta.axes.y.label = format!(
        "{}, as heard on {}",
        out.meta.axes.y.label, preset.service.name
    );
    out.bounds = Aabb::from_points(&out.points);
    Ok(out)
}

fn point_range(
    extra: &serde_json::Map<String, serde_json::Value>,
) -> Option<std::ops::Range<usize>> {
    let offset = usize::try_from(extra.get("point_offset")?.as_u64()?).ok()?;
    let count = usize::try_from(extra.get("point_count")?.as_u64()?).ok()?;
    Some(offset..offset.checked_add(count)?)
}

/// The read-out line of a normalized song: "Spotify (normal) gain: -6.0 dB" (or "unknown").
pub fn gain_reading(song: &crate::data::cloud::SongInfo) -> Option<(String, String)> {
    let name = song.extra.get(PRESET_KEY)?.as_str()?;
    let value = match song.extra.get(GAIN_KEY).and_then(|g| g.as_f64()) {
        Some(g) => format!("{g:+.1} dB"),
        None => "unknown (no integrated loudness)".into(),
    };
    Some((format!("{name} gain"), value))
}

/// How a rule turns songs up, in words.
pub fn turn_up_words(turn_up: TurnUp) -> String {
    match turn_up {
        TurnUp::PeakCeiling(c) => format!("turns up to a {c:+.0} dBTP peak"),
        TurnUp::Free => "turns up to the target".into(),
        TurnUp::Never => "never turns up".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::axes::{Axes, Axis};
    use crate::data::cloud::{CloudMeta, Metrics, Point, SongInfo};

    fn song(offset: usize, count: usize, lufs: f64, peak: f64) -> SongInfo {
        let mut extra = serde_json::Map::new();
        extra.insert("point_offset".into(), offset.into());
        extra.insert("point_count".into(), count.into());
        SongInfo {
            metrics: Some(Metrics {
                integrated_lufs: Some(lufs),
                true_peak_dbtp: Some(peak),
                ..Metrics::default()
            }),
            extra,
            ..SongInfo::default()
        }
    }

    /// Two songs of three points, each point at the song's integrated loudness on a
    /// -60 .. 0 LUFS axis: a loud master (-8 LUFS, +0.5 dBTP) and a quiet one (-20 LUFS,
    /// -5 dBTP).
    fn cloud() -> PointCloud {
        let y = |lufs: f64| (2.0 * (lufs + 60.0) / 60.0 - 1.0) as f32;
        let point = |lufs| Point {
            position: [0.0, y(lufs), 0.0],
            scalar: 0.5,
            hp: 0.5,
        };
        let points = vec![point(-8.0); 3]
            .into_iter()
            .chain(vec![point(-20.0); 3])
            .collect::<Vec<_>>();
        let mut axes = Axes::generic([(0.0, 1.0), (-60.0, 0.0), (0.0, 1.0)]);
        axes.y = Axis::linear("momentary loudness (BS.1770, 400 ms)", "LUFS", -60.0, 0.0);
        PointCloud {
            path: "t.ply".into(),
            bounds: Aabb::from_points(&points),
            points,
            meta: CloudMeta {
                mode: DataMode::Timeline,
                axes,
                point_count: Some(6),
                source: None,
                stft: None,
                metrics: None,
                songs: vec![song(0, 3, -8.0, 0.5), song(3, 3, -20.0, -5.0)],
                raw: serde_json::Value::Null,
                warnings: Vec::new(),
            },
        }
    }

    fn heard(cloud: &PointCloud, index: usize) -> f64 {
        let y = f64::from(cloud.points[index].position[1]);
        (y + 1.0) / 2.0 * 60.0 - 60.0
    }

    #[test]
    fn a_loud_master_sits_at_the_target_and_quiet_ones_follow_the_turn_up_rule() {
        let base = cloud();
        let preset = |key| parse_preset(key).unwrap().unwrap();
        // Spotify (normal), -14 LUFS: -8 comes down 6 dB to -14; -20 with a -5 dBTP peak
        // is raised only to a -1 dBTP peak: +4 dB, to -16 (Spotify's own example).
        let spotify = normalized(&base, &preset("spotify")).unwrap();
        assert!((heard(&spotify, 0) - -14.0).abs() < 1e-4);
        assert!((heard(&spotify, 4) - -16.0).abs() < 1e-4);
        // YouTube never turns up: -20 stays at -20.
        let youtube = normalized(&base, &preset("youtube")).unwrap();
        assert!((heard(&youtube, 0) - -14.0).abs() < 1e-4);
        assert!((heard(&youtube, 5) - -20.0).abs() < 1e-4);
        // EBU R 128 brings both to -23 LUFS.
        let ebu = normalized(&base, &preset("ebu_r128")).unwrap();
        assert!((heard(&ebu, 2) - -23.0).abs() < 1e-4 && (heard(&ebu, 3) - -23.0).abs() < 1e-4);
        // The read-out and the axis say what was done.
        assert_eq!(
            gain_reading(&spotify.meta.songs[0]),
            Some(("Spotify (normal) gain".into(), "-6.0 dB".into()))
        );
        assert_eq!(
            spotify.meta.axes.y.label,
            "momentary loudness (BS.1770, 400 ms), as heard on Spotify (normal)"
        );
        assert!(gain_reading(&base.meta.songs[0]).is_none());
    }

    #[test]
    fn presets_parse_by_key_and_song_clouds_are_refused() {
        assert_eq!(parse_preset("none"), Ok(None));
        assert_eq!(
            parse_preset("atsc_a85")
                .unwrap()
                .unwrap()
                .service
                .target_lufs,
            -24.0
        );
        let bad = parse_preset("tidal").unwrap_err();
        assert!(
            bad.contains("tidal") && bad.contains("spotify_loud"),
            "{bad}"
        );
        let mut song_cloud = cloud();
        song_cloud.meta.mode = DataMode::Song;
        assert!(normalized(&song_cloud, &PRESETS[0]).is_err());
        let mut broken = cloud();
        broken.meta.songs[1]
            .extra
            .insert("point_count".into(), 99.into());
        assert!(
            normalized(&broken, &PRESETS[0])
                .unwrap_err()
                .contains("songs[1]")
        );
    }
}
