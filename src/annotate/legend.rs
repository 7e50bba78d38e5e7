//! The legends of pictures: the name of what is shown (top left) and the colour key with its
//! title and ticks (top right, or under the name where the two would meet), laid out as plain
//! data; and the diverging key of difference views. The window's side panel keeps its own small
//! strips (`ui::legends`).

pub use super::axes::titled_with_reference;
use super::{Anchor, Annotation, Rect, Shape, Text, rgb};
use crate::data::cloud::{DataMode, PointCloud};
use crate::render::colormap::{Background, Colours, DensityColourMap, Ramp};
use crate::render::scene::{RenderSettings, ViewKind};
use crate::render::transfer::TransferPreset;

/// What a picture's colour key shows.
#[derive(Clone, Debug, PartialEq)]
pub enum Key {
    /// A two-ended hp map: percussive (hp 0) to harmonic (hp 1).
    Hp { ramp: Ramp, title: String },
    /// The volume's transfer function over the normalized density, opacity shown as in the
    /// picture (faded toward the background where it is transparent).
    Density {
        preset: TransferPreset,
        colours: Colours,
    },
    /// A diverging map over a signed range, zero at the map's centre: see [`diverging`].
    Diverging {
        ramp: Ramp,
        range: (f32, f32),
        title: String,
    },
}

/// A picture's legend: its name (top left) and its colour key (top right).
#[derive(Clone, Debug, PartialEq)]
pub struct PictureLegend {
    /// The song's or the timeline's name.
    pub name: String,
    /// A second, smaller line under the name (the view and its settings).
    pub detail: String,
    pub key: Key,
    pub background: Background,
}

/// A timeline's name: its file's, or for one built in the window (a `timeline-<key>.ply` in the
/// cloud cache, a name that says nothing) the folder its songs share ("music/"), or "songs" where
/// they share none.
pub fn timeline_name(cloud: &PointCloud) -> String {
    #[cfg(not(target_arch = "wasm32"))]
    let cache = crate::extract::cache::dir();
    // A web page has no cloud cache: the file's own name.
    #[cfg(target_arch = "wasm32")]
    let cache = std::path::PathBuf::new();
    timeline_name_in(cloud, &cache)
}

/// [`timeline_name`] with the cloud cache at `cache`.
fn timeline_name_in(cloud: &PointCloud, cache: &std::path::Path) -> String {
    let file = cloud
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let same = |a: &std::path::Path, b: &std::path::Path| {
        a == b
            || std::fs::canonicalize(a)
                .is_ok_and(|a| std::fs::canonicalize(b).is_ok_and(|b| a == b))
    };
    let in_cache = cloud
        .path
        .parent()
        .is_some_and(|folder| same(folder, cache));
    if !(file.starts_with("timeline-") && in_cache) {
        return file;
    }
    let folders: Vec<std::path::PathBuf> = cloud
        .meta
        .songs
        .iter()
        .filter_map(|s| s.open_path()?.parent().map(|p| p.to_path_buf()))
        .collect();
    let Some(first) = folders.first() else {
        return file;
    };
    let mut common = first.clone();
    for folder in &folders[1..] {
        while !folder.starts_with(&common) {
            if !common.pop() {
                break;
            }
        }
    }
    match common.file_name() {
        Some(name) => format!("{}/", name.to_string_lossy()),
        None => "songs".to_string(),
    }
}

/// The name of what `cloud` shows: the song's file name, or the timeline's size and years.
pub fn picture_name(cloud: &PointCloud) -> String {
    let file_name = |path: &str| {
        std::path::Path::new(path)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.to_string())
    };
    match cloud.meta.mode {
        DataMode::Timeline => {
            let songs = &cloud.meta.songs;
            let years: Vec<i32> = songs.iter().filter_map(|s| s.year).collect();
            let span = match (years.iter().min(), years.iter().max()) {
                (Some(a), Some(b)) if a != b => format!(", {a}\u{2013}{b}"),
                (Some(a), _) => format!(", {a}"),
                _ => String::new(),
            };
            let name = timeline_name(cloud);
            format!("{name}: timeline of {} songs{span}", songs.len())
        }
        DataMode::Song | DataMode::Generic => {
            let source = cloud.meta.source.as_ref();
            // A tagged song by its tag, as the timeline names it: "Title — Artist".
            let tagged = source
                .and_then(|s| s.title.as_deref())
                .map(str::trim)
                .filter(|t| !t.is_empty());
            if let Some(title) = tagged {
                let artist = source
                    .and_then(|s| s.artist.as_deref())
                    .map(str::trim)
                    .filter(|a| !a.is_empty());
                return match artist {
                    Some(artist) => format!("{title} \u{2014} {artist}"),
                    None => title.to_string(),
                };
            }
            source
                .and_then(|s| s.path.as_deref())
                .map(file_name)
                .unwrap_or_else(|| file_name(&cloud.path.to_string_lossy()))
        }
    }
}

/// The legend of a picture of `cloud` drawn with `settings`.
pub fn picture_legend(cloud: &PointCloud, settings: &RenderSettings) -> PictureLegend {
    let colours = settings.colours;
    let hp_title = |what: &str| format!("{what} colour: hp ({})", colours.hp.name());
    let (key, detail) = match settings.view {
        ViewKind::Points => (
            Key::Hp {
                ramp: colours.hp.points(),
                title: hp_title("point"),
            },
            "points".to_string(),
        ),
        ViewKind::Surface => (
            Key::Hp {
                ramp: colours.hp.surface(),
                title: hp_title("surface"),
            },
            format!(
                "isosurface at density {:.2}, {}",
                settings.surface.iso_value,
                settings.surface.method.short_name()
            ),
        ),
        ViewKind::Volume if settings.volume.hp_tint => (
            Key::Hp {
                ramp: colours.hp.points(),
                title: hp_title("volume"),
            },
            format!(
                "volume, {} transfer function, tinted by hp",
                settings.volume.preset.name()
            ),
        ),
        ViewKind::Volume => (
            Key::Density {
                preset: settings.volume.preset,
                colours,
            },
            format!(
                "volume, {} transfer function, {} colours",
                settings.volume.preset.name(),
                match colours.density {
                    DensityColourMap::Preset => settings.volume.preset.name(),
                    other => other.name(),
                }
            ),
        ),
    };
    // Songs a normalization left where they were are named (data/normalize.rs).
    let detail = match crate::data::normalize::left_out_note(cloud) {
        Some(note) => format!("{detail}; {note}"),
        None => detail,
    };
    PictureLegend {
        name: picture_name(cloud),
        detail,
        key,
        background: colours.background,
    }
}

/// Size of the colour strip in a picture, in points.
pub const KEY_SIZE: [f32; 2] = [220.0, 14.0];
/// Margin between the picture's edge and the legend.
pub const MARGIN: f32 = 14.0;
/// The narrowest key strip: room for its end labels and the middle tick between them.
const KEY_MIN_WIDTH: f32 = 180.0;
/// Font sizes: the name, the detail line, the key's title, its ticks.
const NAME_SIZE: f32 = 16.0;
const DETAIL_SIZE: f32 = 12.0;
const KEY_TITLE_SIZE: f32 = 13.0;
const KEY_TICK_SIZE: f32 = 11.0;
/// Swatches per strip in pictures.
const STRIP_STEPS: usize = 110;

/// Where the colour strip of a picture of `rect` lies (top right, under the key's title):
/// [`KEY_SIZE`], narrower in narrow pictures (at most 30 % of the width, at least
/// `KEY_MIN_WIDTH`) so the name keeps its room; [`layout`] moves it under the name where
/// the two would still meet.
pub fn key_strip_rect(rect: Rect) -> Rect {
    // Never narrower than its end labels need ("0 percussive" ... "harmonic 1").
    let width = KEY_SIZE[0]
        .min((rect.width() * 0.3).max(KEY_MIN_WIDTH))
        .min(rect.width() - 2.0 * MARGIN)
        .max(0.0);
    Rect::from_min_size(
        [rect.right() - MARGIN - width, rect.top() + MARGIN + 18.0],
        [width, KEY_SIZE[1]],
    )
}

pub use super::font::fit_text;

/// The legend over a picture occupying `rect`: the name top left, the key top right, or under
/// the name where the key's block (title, strip, ticks) would come within a margin of it. The
/// name and the key's title are cut to the picture's width; tick labels that would meet one
/// already placed drop their words ("0 percussive" -> "0") or, failing that, are left out.
pub fn layout(rect: Rect, legend: &PictureLegend) -> Annotation {
    let ink = rgb(legend.background.ink(true));
    let soft = rgb(legend.background.ink(false));
    let room = (rect.width() - 2.0 * MARGIN).max(0.0);
    let top_left = [rect.left() + MARGIN, rect.top() + MARGIN];
    let mut out = Annotation::default();
    let name = out.text(Text::new(
        fit_text(&legend.name, NAME_SIZE, room),
        top_left,
        Anchor::LEFT_TOP,
        NAME_SIZE,
        ink,
    ));
    let mut text_block = name;
    if !legend.detail.is_empty() {
        let detail = out.text(Text::new(
            fit_text(&legend.detail, DETAIL_SIZE, room),
            [top_left[0], top_left[1] + 21.0],
            Anchor::LEFT_TOP,
            DETAIL_SIZE,
            soft,
        ));
        text_block = Rect::from_min_max(
            text_block.min,
            [text_block.right().max(detail.right()), detail.bottom()],
        );
    }
    let beside = key_layout(key_strip_rect(rect), rect, legend);
    let fits_beside = beside
        .bounds
        .is_some_and(|b| !b.intersects(&text_block.expand(MARGIN)));
    if fits_beside {
        out.extend(beside.shapes);
        return out;
    }
    // Too narrow for the name and the key side by side (a half of a compare picture): the key
    // under the name, its title clear of the name's last line.
    let width = KEY_SIZE[0].min(room);
    let title_height = super::font::measure("Hg", KEY_TITLE_SIZE)[1];
    let top = (text_block.bottom() + 22.0).max(text_block.bottom() + 6.0 + title_height + 4.0);
    let strip = Rect::from_min_size([rect.right() - MARGIN - width, top], [width, KEY_SIZE[1]]);
    out.extend(key_layout(strip, rect, legend).shapes);
    out
}

/// A key laid out around its strip, and the box of all it draws.
struct KeyLayout {
    shapes: Annotation,
    bounds: Option<Rect>,
}

fn key_layout(strip: Rect, rect: Rect, legend: &PictureLegend) -> KeyLayout {
    let background = legend.background;
    let mut shapes = Annotation::default();
    match &legend.key {
        Key::Hp { ramp, title } => {
            strip_shapes(&mut shapes, strip, |t| ramp.sample_u8(t), background);
            let ends = [(0.0, "0 percussive"), (0.5, "0.5"), (1.0, "harmonic 1")];
            key_text(&mut shapes, strip, rect, title, &ends, background);
        }
        Key::Density { preset, colours } => {
            let colours_at = colours.legend(*preset, STRIP_STEPS);
            strip_shapes(
                &mut shapes,
                strip,
                |t| {
                    let i = ((t * (STRIP_STEPS - 1) as f32).round() as usize).min(STRIP_STEPS - 1);
                    let [r, g, b, _] = colours_at[i];
                    [r, g, b]
                },
                background,
            );
            let ticks = [
                (0.0, "0"),
                (0.25, "0.25"),
                (0.5, "0.5"),
                (0.75, "0.75"),
                (1.0, "1"),
            ];
            let title = "density (loudness / its 99th percentile)";
            key_text(&mut shapes, strip, rect, title, &ticks, background);
        }
        Key::Diverging { ramp, range, title } => {
            shapes.extend(diverging_in(strip, rect, ramp, *range, title, background));
        }
    }
    let bounds = shapes.shapes.iter().fold(None::<Rect>, |acc, shape| {
        let r = match shape {
            Shape::Text(t) => t.rect,
            Shape::Fill { rect, .. } | Shape::Frame { rect, .. } => *rect,
            Shape::Line { .. } => return acc,
        };
        Some(acc.map_or(r, |a| {
            Rect::from_min_max(
                [a.left().min(r.left()), a.top().min(r.top())],
                [a.right().max(r.right()), a.bottom().max(r.bottom())],
            )
        }))
    });
    KeyLayout { shapes, bounds }
}

/// A strip of `colour_at(t)`, t from 0 at the left to 1 at the right, with a hairline frame in
/// the background's soft ink.
fn strip_shapes(
    out: &mut Annotation,
    strip: Rect,
    colour_at: impl Fn(f32) -> [u8; 3],
    background: Background,
) {
    for i in 0..STRIP_STEPS {
        let t = (i as f32 + 0.5) / STRIP_STEPS as f32;
        let x0 = strip.left() + strip.width() * i as f32 / STRIP_STEPS as f32;
        let x1 = strip.left() + strip.width() * (i + 1) as f32 / STRIP_STEPS as f32;
        out.fill(
            Rect::from_min_max([x0, strip.top()], [x1 + 0.5, strip.bottom()]),
            0.0,
            rgb(colour_at(t)),
        );
    }
    out.push(Shape::Frame {
        rect: strip,
        width: 1.0,
        colour: rgb(background.ink(false)),
    });
}

/// A tick label's short form: its number alone ("0 percussive" -> "0"), or None when it has
/// no words to drop.
fn short_tick(text: &str) -> Option<&str> {
    let mut words = text.split_whitespace();
    let first = words.next()?;
    words.next()?;
    text.split_whitespace()
        .find(|w| w.trim_start_matches(['+', '-']).parse::<f32>().is_ok())
        .or(Some(first))
}

/// The key's title above the strip and tick labels (position in [0, 1], text) below it: the
/// title from the strip's left end, or ending at its right end where longer than the strip,
/// cut to the picture's width; the ends' ticks first, then the inner ones, each left out where
/// it would meet one already placed.
fn key_text(
    out: &mut Annotation,
    strip: Rect,
    rect: Rect,
    title: &str,
    ticks: &[(f32, &str)],
    background: Background,
) {
    let ink = rgb(background.ink(true));
    let soft = rgb(background.ink(false));
    let room = (rect.width() - 2.0 * MARGIN).max(0.0).max(strip.width());
    let title = fit_text(title, KEY_TITLE_SIZE, room);
    let size = super::font::measure(&title, KEY_TITLE_SIZE);
    let left = if size[0] > strip.width() {
        strip.right() - size[0]
    } else {
        strip.left()
    };
    out.text(Text::new(
        title,
        [left, strip.top() - 4.0 - size[1]],
        Anchor::LEFT_TOP,
        KEY_TITLE_SIZE,
        ink,
    ));
    let ends = ticks.iter().filter(|(at, _)| *at <= 0.0 || *at >= 1.0);
    let inner = ticks.iter().filter(|(at, _)| *at > 0.0 && *at < 1.0);
    let tick_text = |at: f32, text: &str| {
        let anchor = if at <= 0.0 {
            Anchor::LEFT_TOP
        } else if at >= 1.0 {
            Anchor::RIGHT_TOP
        } else {
            Anchor::CENTER_TOP
        };
        let x = strip.left() + strip.width() * at;
        Text::new(text, [x, strip.bottom() + 5.0], anchor, KEY_TICK_SIZE, soft)
    };
    let mut placed: Vec<(f32, Text)> = Vec::new();
    let ends: Vec<(f32, &str)> = ends.copied().collect();
    // The ends in their short forms where the long ones would meet.
    let long: Vec<Text> = ends.iter().map(|(at, t)| tick_text(*at, t)).collect();
    let crowded = long.len() == 2 && long[0].rect.expand(2.0).intersects(&long[1].rect);
    for ((at, text), long) in ends.iter().zip(long) {
        let text = if crowded {
            tick_text(*at, short_tick(text).unwrap_or(text))
        } else {
            long
        };
        placed.push((*at, text));
    }
    for (at, text) in inner {
        let text = tick_text(*at, text);
        if !placed
            .iter()
            .any(|(_, p)| p.rect.expand(2.0).intersects(&text.rect))
        {
            placed.push((*at, text));
        }
    }
    for (at, text) in placed {
        let x = strip.left() + strip.width() * at;
        out.line([x, strip.bottom()], [x, strip.bottom() + 4.0], 1.0, soft);
        out.text(text);
    }
}

/// A caption centred near the bottom of a picture occupying `rect` (a video's song under its
/// timeline sweep), on a plate of the background's colour; its size grows with the picture's
/// height (14 to 64 points).
pub fn caption(rect: Rect, text: &str, background: Background) -> Annotation {
    let size = (rect.height() / 22.0).clamp(14.0, 64.0);
    let label = Text::new(
        fit_text(text, size, (rect.width() - size).max(0.0)),
        [rect.center()[0], rect.bottom() - size * 2.2],
        Anchor::CENTER_TOP,
        size,
        rgb(background.ink(true)),
    );
    let mut out = Annotation::default();
    out.fill(
        label.rect.expand(size * 0.3),
        size * 0.2,
        super::axes::label_plate(background),
    );
    out.text(label);
    out
}

/// Where a value lands on a diverging map for the signed range `range` (lo, hi): zero at the
/// map's centre, the larger magnitude of the two ends at the map's end on its side, so equal
/// magnitudes get equal saturation on both sides (a range of -2..6 uses t from 0.33 to 1).
pub fn diverging_position(value: f32, range: (f32, f32)) -> f32 {
    let extent = range.0.abs().max(range.1.abs());
    if extent <= 0.0 || !extent.is_finite() {
        return 0.5;
    }
    (0.5 + 0.5 * value / extent).clamp(0.0, 1.0)
}

/// The legend of a diverging map (the A/B difference view): a strip from `range.0` to
/// `range.1` (signed, e.g. -6..6 dB where B is quieter..louder than A) coloured by `ramp` with
/// zero at its centre ([`diverging_position`]), ticks at both ends and at zero, and `title`
/// (name the quantity and its unit, e.g. "B - A, density") above it. `strip` is the strip's
/// rectangle; text goes 18 points above and 16 below it, in `background`'s ink.
pub fn diverging(
    strip: Rect,
    ramp: &Ramp,
    range: (f32, f32),
    title: &str,
    background: Background,
) -> Annotation {
    let room = strip.expand2(MARGIN + 400.0, 0.0);
    diverging_in(strip, room, ramp, range, title, background)
}

fn diverging_in(
    strip: Rect,
    rect: Rect,
    ramp: &Ramp,
    range: (f32, f32),
    title: &str,
    background: Background,
) -> Annotation {
    let (lo, hi) = if range.0 <= range.1 {
        range
    } else {
        (range.1, range.0)
    };
    let mut out = Annotation::default();
    strip_shapes(
        &mut out,
        strip,
        |t| ramp.sample_u8(diverging_position(lo + (hi - lo) * t, (lo, hi))),
        background,
    );
    let number = |v: f32| {
        if v == 0.0 {
            "0".to_string()
        } else if v.abs() >= 10.0 {
            format!("{v:+.0}")
        } else {
            format!("{v:+.1}")
        }
    };
    let (lo_text, hi_text) = (number(lo), number(hi));
    let mut ticks: Vec<(f32, &str)> = vec![(0.0, lo_text.as_str()), (1.0, hi_text.as_str())];
    if lo < 0.0 && hi > 0.0 {
        ticks.push((-lo / (hi - lo), "0"));
    }
    key_text(&mut out, strip, rect, title, &ticks, background);
    out
}

#[cfg(test)]
mod picture_tests {
    use super::*;

    #[test]
    fn diverging_positions_put_zero_at_the_centre() {
        assert_eq!(diverging_position(0.0, (-6.0, 6.0)), 0.5);
        assert_eq!(diverging_position(6.0, (-6.0, 6.0)), 1.0);
        assert_eq!(diverging_position(-6.0, (-6.0, 6.0)), 0.0);
        assert!((diverging_position(-2.0, (-2.0, 6.0)) - 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(diverging_position(1.0, (0.0, 0.0)), 0.5);
    }

    #[test]
    fn the_level_axis_names_its_reference() {
        assert_eq!(
            titled_with_reference(DataMode::Timeline, 1, "dB", "level (dB)".into()),
            "level (dBFS RMS)"
        );
        assert_eq!(
            titled_with_reference(DataMode::Song, 1, "dB", "level (dB)".into()),
            "bin level (dB re FS sine)"
        );
        assert_eq!(
            titled_with_reference(DataMode::Timeline, 2, "dB", "PSR (dB)".into()),
            "PSR (dB)"
        );
        let loudness = "momentary loudness (BS.1770, 400 ms) (LUFS)";
        assert_eq!(
            titled_with_reference(DataMode::Timeline, 1, "LUFS", loudness.into()),
            loudness
        );
    }

    #[test]
    fn a_timeline_built_in_the_window_is_named_by_its_songs_folder() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut cloud = crate::data::cloud::load(&repo.join("data/demo_timeline.ply")).unwrap();
        let cache = std::path::Path::new("/nonexistent/cache/loudscape/clouds");
        for (i, song) in cloud.meta.songs.iter_mut().enumerate() {
            song.path = Some(format!("/music/My Albums/disc {}/song{i}.flac", i % 2));
            song.path_bytes = None;
        }
        cloud.path = cache.join("timeline-41b95712d880b9b1.ply");
        assert_eq!(timeline_name_in(&cloud, cache), "My Albums/");
        // Elsewhere, its file's own name is the one chosen by whoever saved it.
        cloud.path = std::path::PathBuf::from("/somewhere/timeline-41b95712d880b9b1.ply");
        assert_eq!(
            timeline_name_in(&cloud, cache),
            "timeline-41b95712d880b9b1.ply"
        );
        cloud.path = cache.join("my-years.ply");
        assert_eq!(timeline_name_in(&cloud, cache), "my-years.ply");
    }
}

#[cfg(test)]
mod name_tests {
    use super::picture_name;

    #[test]
    fn a_tagged_song_is_named_by_its_tag_as_in_the_timeline() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply");
        let mut cloud = crate::data::cloud::load(&path).expect("the demo song loads");
        assert_eq!(picture_name(&cloud), "demo_song.flac");
        let source = cloud.meta.source.as_mut().expect("a song has a source");
        source.title = Some("שלום 2020".into());
        assert_eq!(picture_name(&cloud), "שלום 2020");
        let source = cloud.meta.source.as_mut().unwrap();
        source.artist = Some("Ensemble".into());
        assert_eq!(picture_name(&cloud), "שלום 2020 \u{2014} Ensemble");
        // Blank tags are no name.
        let source = cloud.meta.source.as_mut().unwrap();
        source.title = Some("  ".into());
        assert_eq!(picture_name(&cloud), "demo_song.flac");
    }
}
