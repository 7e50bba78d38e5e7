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
/// limited by [`TurnUp`]. The extractor reads the same presets from
/// `preprocess/loudscape_extract/normalization_presets.json`; the test
/// `presets_match_the_extractors_file` holds [`PRESETS`] equal to it (sources in
/// docs/DYNAMICS.md, "Streaming normalization").
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

/// What `--normalize` and the window's "level as heard" choose: the files as mastered
/// (`none`) or a preset, by its key. Parsed once where it enters (`clap::ValueEnum`); the
/// window hands it to `video` under the same key.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Normalization {
    /// The files as mastered: no shift (`none`).
    #[default]
    AsMastered,
    /// Each song shifted by the gain this preset applies to it.
    Preset(Preset),
}

impl Normalization {
    /// `none`, then every preset of [`PRESETS`] in order.
    pub const ALL: [Normalization; 1 + PRESETS.len()] = [
        Normalization::AsMastered,
        Normalization::Preset(PRESETS[0]),
        Normalization::Preset(PRESETS[1]),
        Normalization::Preset(PRESETS[2]),
        Normalization::Preset(PRESETS[3]),
        Normalization::Preset(PRESETS[4]),
        Normalization::Preset(PRESETS[5]),
        Normalization::Preset(PRESETS[6]),
    ];

    /// The command-line key: `none` or the preset's (`spotify`, `ebu_r128`, ...).
    pub fn key(self) -> &'static str {
        match self {
            Normalization::AsMastered => "none",
            Normalization::Preset(preset) => preset.key,
        }
    }

    /// The preset; None as mastered.
    pub fn preset(self) -> Option<Preset> {
        match self {
            Normalization::AsMastered => None,
            Normalization::Preset(preset) => Some(preset),
        }
    }

    /// The choice of `key` (any case); None for a key that is none of them.
    pub fn parse(key: &str) -> Option<Self> {
        crate::parse_value(key)
    }
}

command_line_names!(Normalization, |choice| choice.key());

/// Metadata key (in each song's object) of the gain a normalized cloud was shifted by.
pub const GAIN_KEY: &str = "normalization_gain_db";
/// Metadata key (in each song's object) of the preset's name.
pub const PRESET_KEY: &str = "normalization";
/// Metadata key (in each song's object) of why the song was left where it is, when the preset
/// gives it no gain ([`no_gain_reason`]).
pub const LEFT_OUT_KEY: &str = "normalization_left_out";

/// Why `service` gives a song no gain (see [`normalization_gain`]): no integrated loudness
/// (a silent or near-silent song, or metrics the file does not give), or a turn-up that needs
/// the true peak the file does not give.
pub fn no_gain_reason(
    service: &StreamingService,
    integrated_lufs: Option<f64>,
    true_peak_dbtp: Option<f64>,
) -> Option<&'static str> {
    if normalization_gain(service, integrated_lufs, true_peak_dbtp).is_some() {
        return None;
    }
    if integrated_lufs.is_some_and(f64::is_finite) {
        Some("no true peak to limit its turn-up by")
    } else {
        Some("no integrated loudness")
    }
}

/// A song a normalized cloud leaves where it was.
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    /// Its title, else its file's name, else `songs[INDEX]`.
    pub song: String,
    /// Its file, as recorded, where it has a title too (titles repeat).
    pub file: Option<String>,
    pub reason: String,
}

/// The songs of a cloud made by [`normalized`] that were not moved, in file order.
pub fn left_out(cloud: &PointCloud) -> Vec<LeftOut> {
    cloud
        .meta
        .songs
        .iter()
        .enumerate()
        .filter_map(|(index, song)| {
            let reason = song.extra.get(LEFT_OUT_KEY)?.as_str()?.to_string();
            let file_name = song.path.as_deref().and_then(|p| {
                std::path::Path::new(p)
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
            });
            let title = Some(song.title.trim())
                .filter(|t| !t.is_empty())
                .map(str::to_string);
            let file = title.as_ref().and(song.path.clone());
            let name = title
                .or(file_name)
                .unwrap_or_else(|| format!("songs[{index}]"));
            Some(LeftOut {
                song: name,
                file,
                reason,
            })
        })
        .collect()
}

/// Most lines [`left_out_lines`] gives one song each.
pub const LEFT_OUT_LINES: usize = 10;

/// The warning lines about the songs `cloud` (made by [`normalized`]) leaves unmoved: one a
/// song, `warning: FILE: SONG was not normalized (PRESET): REASON`, at most [`LEFT_OUT_LINES`],
/// then one line counting the rest.
pub fn left_out_lines(cloud: &PointCloud) -> Vec<String> {
    let left = left_out(cloud);
    let preset = cloud
        .meta
        .songs
        .iter()
        .find_map(|s| s.extra.get(PRESET_KEY)?.as_str())
        .unwrap_or("normalization");
    let file = cloud.path.display();
    let mut lines: Vec<String> = left
        .iter()
        .take(LEFT_OUT_LINES)
        .map(|l| {
            let song = match &l.file {
                Some(path) => format!("{} ({path})", l.song),
                None => l.song.clone(),
            };
            format!(
                "warning: {file}: {} was not normalized ({preset}): {}; it is drawn as \
                 mastered",
                crate::data::cloud::one_line(&song),
                l.reason
            )
        })
        .collect();
    if left.len() > LEFT_OUT_LINES {
        lines.push(format!(
            "warning: {file}: {} more songs were not normalized ({preset})",
            left.len() - LEFT_OUT_LINES
        ));
    }
    lines
}

/// The legend's note on the songs `cloud` (made by [`normalized`]) leaves unmoved, or None
/// where there are none: "1 song not normalized (no integrated loudness): Hum", the reason
/// given where all share it, the names listed (the legend cuts what does not fit).
pub fn left_out_note(cloud: &PointCloud) -> Option<String> {
    let left = left_out(cloud);
    let first = left.first()?;
    let count = match left.len() {
        1 => "1 song".to_string(),
        n => format!("{n} songs"),
    };
    let reason = if left.iter().all(|l| l.reason == first.reason) {
        format!(" ({})", first.reason)
    } else {
        String::new()
    };
    let names: Vec<String> = left
        .iter()
        .map(|l| crate::data::cloud::one_line(&l.song))
        .collect();
    Some(format!(
        "{count} not normalized{reason}: {}",
        names.join(", ")
    ))
}

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
/// (or a true peak a turn-up needs) stays where it is, its gain recorded as unknown and the
/// reason as [`LEFT_OUT_KEY`]: [`left_out_lines`] and [`left_out_note`] say so.
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
        match no_gain_reason(
            &preset.service,
            metrics.integrated_lufs,
            metrics.true_peak_dbtp,
        ) {
            Some(reason) => song.extra.insert(LEFT_OUT_KEY.into(), reason.into()),
            None => song.extra.remove(LEFT_OUT_KEY),
        };
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
        None => format!(
            "unknown ({})",
            song.extra
                .get(LEFT_OUT_KEY)
                .and_then(|r| r.as_str())
                .unwrap_or("no integrated loudness")
        ),
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
        let preset = |key| Normalization::parse(key).unwrap().preset().unwrap();
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

    /// A song without an integrated loudness (a -75 dB sine: the gate leaves nothing) and one
    /// without the true peak a turn-up needs stay where they are, each with its reason, said on
    /// one warning line each and in the legend's note; a song that moved is not named.
    #[test]
    fn songs_left_where_they_are_are_named_with_their_reason() {
        let mut base = cloud();
        base.meta.songs[0].title = "Hum".into();
        base.meta.songs[0].metrics = Some(Metrics::default());
        base.meta.songs[1].path = Some("/music/quiet.flac".into());
        base.meta.songs[1].metrics.as_mut().unwrap().true_peak_dbtp = None;
        let spotify = normalized(&base, &PRESETS[0]).unwrap();
        assert!(
            (heard(&spotify, 0) - -8.0).abs() < 1e-4,
            "moved without a loudness"
        );
        assert!(
            (heard(&spotify, 3) - -20.0).abs() < 1e-4,
            "turned up without a peak"
        );
        assert_eq!(
            left_out(&spotify),
            [
                LeftOut {
                    song: "Hum".into(),
                    file: None,
                    reason: "no integrated loudness".into()
                },
                LeftOut {
                    song: "quiet.flac".into(),
                    file: None,
                    reason: "no true peak to limit its turn-up by".into()
                }
            ]
        );
        assert_eq!(
            left_out_lines(&spotify),
            [
                "warning: t.ply: Hum was not normalized (Spotify (normal)): no integrated \
                 loudness; it is drawn as mastered",
                "warning: t.ply: quiet.flac was not normalized (Spotify (normal)): no true peak \
                 to limit its turn-up by; it is drawn as mastered"
            ]
        );
        assert_eq!(
            left_out_note(&spotify).as_deref(),
            Some("2 songs not normalized: Hum, quiet.flac")
        );
        assert_eq!(
            gain_reading(&spotify.meta.songs[1]).unwrap().1,
            "unknown (no true peak to limit its turn-up by)"
        );
        // A title names the song, its file follows on stderr (titles repeat).
        let mut titled = base.clone();
        titled.meta.songs[0].path = Some("songs/hum.flac".into());
        let lines = left_out_lines(&normalized(&titled, &PRESETS[0]).unwrap());
        assert!(
            lines[0].contains(": Hum (songs/hum.flac) was not"),
            "{lines:?}"
        );
        // EBU R 128 turns up freely: only the song without a loudness is left.
        let ebu = normalized(&base, &PRESETS[5]).unwrap();
        assert_eq!(
            left_out_note(&ebu).as_deref(),
            Some("1 song not normalized (no integrated loudness): Hum")
        );
        // Many: ten lines and one counting the rest.
        let mut many = cloud();
        many.meta.songs = (0..13).map(|_| song(0, 3, -8.0, 0.5)).collect();
        for song in &mut many.meta.songs {
            song.metrics = None;
        }
        let lines = left_out_lines(&normalized(&many, &PRESETS[0]).unwrap());
        assert_eq!(lines.len(), LEFT_OUT_LINES + 1);
        assert!(
            lines[0].contains("songs[0] was not normalized"),
            "{lines:?}"
        );
        assert!(lines[10].contains("3 more songs"), "{lines:?}");
        // Nothing left out, nothing said.
        let all = normalized(&cloud(), &PRESETS[0]).unwrap();
        assert!(left_out_lines(&all).is_empty() && left_out_note(&all).is_none());
    }

    #[test]
    fn presets_match_the_extractors_file() {
        let file: serde_json::Value = serde_json::from_str(include_str!(
            "../../preprocess/loudscape_extract/normalization_presets.json"
        ))
        .expect("normalization_presets.json is JSON");
        let group = |name: &str| file[name].as_array().cloned().unwrap_or_default();
        let entries: Vec<serde_json::Value> = group("services")
            .into_iter()
            .chain(group("broadcast"))
            .collect();
        let from_file: Vec<(String, String, f64, String)> = entries
            .iter()
            .map(|e| {
                let turn_up = match (e["turn_up"].as_str(), e["ceiling_dbtp"].as_f64()) {
                    (Some("peak"), Some(ceiling)) => format!("{:?}", TurnUp::PeakCeiling(ceiling)),
                    (Some("free"), None) => format!("{:?}", TurnUp::Free),
                    (Some("never"), None) => format!("{:?}", TurnUp::Never),
                    other => format!("unknown turn-up {other:?}"),
                };
                let text = |key: &str| e[key].as_str().unwrap_or("").to_string();
                (
                    text("key"),
                    text("name"),
                    e["target_lufs"].as_f64().unwrap_or(f64::NAN),
                    turn_up,
                )
            })
            .collect();
        let in_rust: Vec<(String, String, f64, String)> = PRESETS
            .iter()
            .map(|p| {
                let s = p.service;
                (
                    p.key.into(),
                    s.name.into(),
                    s.target_lufs,
                    format!("{:?}", s.turn_up),
                )
            })
            .collect();
        assert_eq!(in_rust, from_file);
        let services: Vec<String> = group("services")
            .iter()
            .map(|e| e["name"].as_str().unwrap_or("").to_string())
            .collect();
        let names: Vec<String> = STREAMING_SERVICES.iter().map(|s| s.name.into()).collect();
        assert_eq!(
            services, names,
            "STREAMING_SERVICES are the file's services, in order"
        );
    }

    #[test]
    fn presets_parse_by_key_and_song_clouds_are_refused() {
        assert_eq!(
            Normalization::parse("none"),
            Some(Normalization::AsMastered)
        );
        let atsc = Normalization::parse("atsc_a85").unwrap();
        assert_eq!(atsc.preset().unwrap().service.target_lufs, -24.0);
        assert_eq!(crate::value_name(&atsc), "atsc_a85");
        assert_eq!(Normalization::parse("tidal"), None);
        // Every preset is a choice, under its own key, once.
        let keys: Vec<&str> = Normalization::ALL.iter().map(|n| n.key()).collect();
        let mut unique = keys.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), keys.len());
        assert!(PRESETS.iter().all(|p| keys.contains(&p.key)));
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
