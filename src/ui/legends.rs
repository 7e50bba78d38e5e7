//! Colour legends: the side panel's strips (one painter for every palette: the points' hp map,
//! the surface's, the volume's transfer function, with their ends named below), and the legends
//! painted into pictures ([`paint_picture`]: the colour key with its title and ticks, the
//! song's or timeline's name; [`paint_diverging`]: a diverging map over a signed range, for
//! difference views). Headless renders and screenshots draw them through
//! `crate::ui::screenshot::draw_overlay`.

use eframe::egui::{self, Color32, RichText};

use crate::data::cloud::{DataMode, PointCloud};
use crate::render::colormap::{Background, Colours, DensityColourMap, HpColourMap, Ramp};
use crate::render::scene::{RenderSettings, ViewKind};
use crate::render::transfer::TransferPreset;

/// Swatches per strip.
const STEPS: usize = 50;

/// A 200 x 12 point strip of `colour(t)` for t from 0 to 1, then the names of its two ends,
/// `gap` points apart.
fn strip(ui: &mut egui::Ui, colour: impl Fn(usize) -> [u8; 3], ends: (&str, f32, &str)) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(200.0, 12.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    for i in 0..STEPS {
        let [r, g, b] = colour(i);
        let x0 = rect.left() + rect.width() * i as f32 / STEPS as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / STEPS as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, rect.y_range()),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
    let (left, gap, right) = ends;
    ui.horizontal(|ui| {
        ui.label(RichText::new(left).small());
        ui.add_space(gap);
        ui.label(RichText::new(right).small());
    });
}

/// Position of swatch `i` on [0, 1].
fn at(i: usize) -> f32 {
    i as f32 / (STEPS - 1) as f32
}

/// The points' hp map.
pub(super) fn hp(ui: &mut egui::Ui, map: HpColourMap) {
    let ramp = map.points();
    strip(
        ui,
        |i| ramp.sample_u8(at(i)),
        ("percussive", 60.0, "harmonic (hp)"),
    );
}

/// The surface's colour by mean hp.
pub(super) fn surface(ui: &mut egui::Ui, map: HpColourMap) {
    ui.label(RichText::new("Surface colour (mean hp)").small());
    let ramp = map.surface();
    strip(
        ui,
        |i| ramp.sample_u8(at(i)),
        ("percussive", 60.0, "harmonic"),
    );
}

/// The transfer function's colour over density 0..1, faded toward the background where it is
/// transparent.
pub(super) fn transfer(ui: &mut egui::Ui, preset: TransferPreset, colours: &Colours) {
    let colours = colours.legend(preset, STEPS);
    strip(
        ui,
        |i| {
            let [r, g, b, _] = colours[i];
            [r, g, b]
        },
        ("density 0", 120.0, "1"),
    );
}

// ---------------------------------------------------------------------------------------------
// Legends in pictures: the colour key, the name of what is shown and the background's ink,
// painted over the 3D view (headless renders, screenshots). The window's side panel keeps the
// small strips above; these carry their own titles and tick values, since a picture travels
// without the panel.

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
    /// A diverging map over a signed range, zero at the map's centre: see [`paint_diverging`].
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
    timeline_name_in(cloud, &crate::extract::cache::dir())
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
        DataMode::Song | DataMode::Generic => cloud
            .meta
            .source
            .as_ref()
            .and_then(|s| s.path.as_deref())
            .map(file_name)
            .unwrap_or_else(|| file_name(&cloud.path.to_string_lossy())),
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
    PictureLegend {
        name: picture_name(cloud),
        detail,
        key,
        background: colours.background,
    }
}

/// Size of the colour strip in a picture, in points.
pub const KEY_SIZE: egui::Vec2 = egui::vec2(220.0, 14.0);
/// Margin between the picture's edge and the legend.
pub const MARGIN: f32 = 14.0;
/// The narrowest key strip: room for its end labels and the middle tick between them.
const KEY_MIN_WIDTH: f32 = 180.0;

/// Where the colour strip of a picture of `rect` lies (top right, under the key's title):
/// [`KEY_SIZE`], narrower in narrow pictures (at most 30 % of the width, at least
/// `KEY_MIN_WIDTH`) so the name keeps its room; [`paint_picture`] moves it under the name where
/// the two would still meet.
pub fn key_strip_rect(rect: egui::Rect) -> egui::Rect {
    // Never narrower than its end labels need ("0 percussive" ... "harmonic 1").
    let width = KEY_SIZE
        .x
        .min((rect.width() * 0.3).max(KEY_MIN_WIDTH))
        .min(rect.width() - 2.0 * MARGIN)
        .max(0.0);
    let size = egui::vec2(width, KEY_SIZE.y);
    egui::Rect::from_min_size(
        egui::pos2(rect.right() - MARGIN - size.x, rect.top() + MARGIN + 18.0),
        size,
    )
}

fn colour(c: [u8; 3]) -> Color32 {
    Color32::from_rgb(c[0], c[1], c[2])
}

/// Paints `legend` over a picture occupying `rect`: the name top left, the key top right.
pub fn paint_picture(painter: &egui::Painter, rect: egui::Rect, legend: &PictureLegend) {
    let ink = colour(legend.background.ink(true));
    let soft = colour(legend.background.ink(false));
    let top_left = rect.min + egui::vec2(MARGIN, MARGIN);
    let name = painter.text(
        top_left,
        egui::Align2::LEFT_TOP,
        &legend.name,
        egui::FontId::proportional(16.0),
        ink,
    );
    let detail = painter.text(
        top_left + egui::vec2(0.0, 21.0),
        egui::Align2::LEFT_TOP,
        &legend.detail,
        egui::FontId::proportional(12.0),
        soft,
    );
    let mut strip = key_strip_rect(rect);
    // A picture too narrow for the name and the key side by side (a half of a compare
    // picture) gets the key under the name, at least wide enough for its end labels.
    let text_right = if legend.detail.is_empty() {
        name.right()
    } else {
        name.right().max(detail.right())
    };
    if text_right + 2.0 * MARGIN > strip.left() {
        let width = KEY_SIZE.x.min(rect.width() - 2.0 * MARGIN).max(0.0);
        let below = if legend.detail.is_empty() {
            name.bottom()
        } else {
            detail.bottom()
        };
        strip = egui::Rect::from_min_size(
            egui::pos2(rect.right() - MARGIN - width, below + 22.0),
            egui::vec2(width, KEY_SIZE.y),
        );
    }
    match &legend.key {
        Key::Hp { ramp, title } => {
            paint_strip(painter, strip, |t| ramp.sample_u8(t), legend.background);
            let ends = [(0.0, "0 percussive"), (0.5, "0.5"), (1.0, "harmonic 1")];
            paint_key_text(painter, strip, title, &ends, legend.background);
        }
        Key::Density { preset, colours } => {
            let colours_at = colours.legend(*preset, STRIP_STEPS);
            paint_strip(
                painter,
                strip,
                |t| {
                    let i = ((t * (STRIP_STEPS - 1) as f32).round() as usize).min(STRIP_STEPS - 1);
                    let [r, g, b, _] = colours_at[i];
                    [r, g, b]
                },
                legend.background,
            );
            let ticks = [
                (0.0, "0"),
                (0.25, "0.25"),
                (0.5, "0.5"),
                (0.75, "0.75"),
                (1.0, "1"),
            ];
            paint_key_text(
                painter,
                strip,
                "density (loudness / its 99th percentile)",
                &ticks,
                legend.background,
            );
        }
        Key::Diverging { ramp, range, title } => {
            paint_diverging(painter, strip, ramp, *range, title, legend.background);
        }
    }
}

/// Swatches per strip in pictures.
const STRIP_STEPS: usize = 110;

/// A strip of `colour_at(t)`, t from 0 at the left to 1 at the right, with a hairline frame in
/// the background's soft ink.
fn paint_strip(
    painter: &egui::Painter,
    strip: egui::Rect,
    colour_at: impl Fn(f32) -> [u8; 3],
    background: Background,
) {
    for i in 0..STRIP_STEPS {
        let t = (i as f32 + 0.5) / STRIP_STEPS as f32;
        let x0 = strip.left() + strip.width() * i as f32 / STRIP_STEPS as f32;
        let x1 = strip.left() + strip.width() * (i + 1) as f32 / STRIP_STEPS as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, strip.y_range()),
            0.0,
            colour(colour_at(t)),
        );
    }
    painter.rect_stroke(
        strip,
        0.0,
        egui::Stroke::new(1.0, colour(background.ink(false))),
        egui::StrokeKind::Outside,
    );
}

/// The key's title above the strip and tick labels (position in [0, 1], text) below it.
fn paint_key_text(
    painter: &egui::Painter,
    strip: egui::Rect,
    title: &str,
    ticks: &[(f32, &str)],
    background: Background,
) {
    let ink = colour(background.ink(true));
    let soft = colour(background.ink(false));
    // Over the strip from its left end; a title longer than the strip (a narrow picture) ends
    // at the strip's right end instead of running off the picture.
    let galley = painter.layout_no_wrap(title.to_owned(), egui::FontId::proportional(13.0), ink);
    let size = galley.size();
    let left = if size.x > strip.width() {
        strip.right() - size.x
    } else {
        strip.left()
    };
    painter.galley(egui::pos2(left, strip.top() - 4.0 - size.y), galley, ink);
    for (at, text) in ticks {
        let x = strip.left() + strip.width() * at;
        painter.line_segment(
            [
                egui::pos2(x, strip.bottom()),
                egui::pos2(x, strip.bottom() + 4.0),
            ],
            egui::Stroke::new(1.0, soft),
        );
        let align = if *at <= 0.0 {
            egui::Align2::LEFT_TOP
        } else if *at >= 1.0 {
            egui::Align2::RIGHT_TOP
        } else {
            egui::Align2::CENTER_TOP
        };
        painter.text(
            egui::pos2(x, strip.bottom() + 5.0),
            align,
            *text,
            egui::FontId::proportional(11.0),
            soft,
        );
    }
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
pub fn paint_diverging(
    painter: &egui::Painter,
    strip: egui::Rect,
    ramp: &Ramp,
    range: (f32, f32),
    title: &str,
    background: Background,
) {
    let (lo, hi) = if range.0 <= range.1 {
        range
    } else {
        (range.1, range.0)
    };
    paint_strip(
        painter,
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
    paint_key_text(painter, strip, title, &ticks, background);
}

/// How the y axis of `mode` is titled in pictures, with its reference: an older timeline's
/// "level" in dB is the frame's RMS level in dBFS (newer ones name their measure and unit,
/// e.g. LUFS, and pass through); a song's is each STFT bin's level in dB re a full-scale sine
/// (see docs/FORMAT.md). Other titles pass through.
pub fn titled_with_reference(mode: DataMode, axis: usize, unit: &str, title: String) -> String {
    if axis != 1 || unit != "dB" {
        return title;
    }
    let reference = match mode {
        DataMode::Timeline => "dBFS RMS",
        DataMode::Song => "dB re FS sine",
        DataMode::Generic => return title,
    };
    match title.strip_suffix(" (dB)") {
        Some("level") if mode == DataMode::Song => format!("bin level ({reference})"),
        Some(name) => format!("{name} ({reference})"),
        None => title,
    }
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
