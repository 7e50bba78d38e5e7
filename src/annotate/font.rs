//! The window's fonts for pictures: Ubuntu Light (egui's proportional font, from the same
//! `epaint_default_fonts` bytes) and, for what it lacks, the fallback fonts of [`FONTS`] (Noto
//! Sans for Hebrew, Arabic, Devanagari, Thai, Armenian and Georgian from data/fonts/, egui's icons
//! and monochrome Noto Emoji), all compiled in: no platform font is looked up. The window's egui
//! gets the same list in the same order (`ui::style::install_fonts`).
//!
//! A line is split into the level runs of the bidirectional algorithm ([`super::bidi`]), each
//! run into font runs (a character's font is the first in [`FONTS`] that has it, as egui picks),
//! and each font run is shaped with harfrust in its run's direction (Arabic joins, marks sit on
//! their letters), kerning included, and hinted with skrifa as egui does, so a label measures
//! and looks the same in a PNG as in the window.

use std::ops::Range;
use std::sync::OnceLock;

use skrifa::MetadataProvider;
use skrifa::instance::{LocationRef, Size};
use skrifa::outline::{DrawSettings, HintingInstance, OutlinePen, SmoothMode, Target};
use unicode_segmentation::UnicodeSegmentation;
use vello_cpu::kurbo::BezPath;

use super::bidi;

/// A font of the fallback list: egui's name for it, its bytes and egui's size tweak.
pub struct FontFile {
    pub name: &'static str,
    pub bytes: &'static [u8],
    /// The size it is drawn at, as a fraction of the text's (egui's `FontTweak::scale`).
    pub scale: f32,
}

/// A script font of data/fonts/, drawn at the text's size.
macro_rules! script_font {
    ($name:literal) => {
        FontFile {
            name: $name,
            bytes: include_bytes!(concat!("../../data/fonts/", $name, ".ttf")),
            scale: 1.0,
        }
    };
}

/// The fonts a character looks for its glyph in, in order: Ubuntu Light, the script fonts,
/// then egui's icons and the emoji (egui's `FontDefinitions::default` order and tweaks, with the
/// script fonts before the last-resort symbol fonts as egui advises).
pub const FONTS: [FontFile; 10] = [
    FontFile {
        name: "Ubuntu-Light",
        bytes: epaint_default_fonts::UBUNTU_LIGHT,
        scale: 1.0,
    },
    script_font!("NotoSansHebrew-Regular"),
    script_font!("NotoSansArabic-Regular"),
    script_font!("NotoSansDevanagari-Regular"),
    script_font!("NotoSansThai-Regular"),
    script_font!("NotoSansArmenian-Regular"),
    script_font!("NotoSansGeorgian-Regular"),
    FontFile {
        name: "egui-icons",
        bytes: epaint_default_fonts::EGUI_ICONS,
        scale: 0.90,
    },
    FontFile {
        name: "NotoEmoji-Regular",
        bytes: epaint_default_fonts::NOTO_EMOJI_REGULAR,
        scale: 0.81,
    },
    FontFile {
        name: "emoji-icon-font",
        bytes: epaint_default_fonts::EMOJI_ICON,
        scale: 0.90,
    },
];

struct Face {
    font: skrifa::FontRef<'static>,
    charmap: skrifa::charmap::Charmap<'static>,
    shaper: harfrust::ShaperData,
    units_per_em: f32,
    ascent: f32,
    descent: f32,
    leading: f32,
    scale: f32,
}

impl Face {
    /// Ascent and row height at `px` (the text's size, before this face's tweak), rounded as
    /// egui rounds them.
    fn row(&self, px: f32) -> (f32, f32) {
        let scale = px * self.scale / self.units_per_em;
        let ascent = (self.ascent * scale).round();
        let descent = (self.descent * scale).round();
        let leading = (self.leading * scale).round();
        (ascent, ascent - descent + leading)
    }
}

fn faces() -> &'static [Face] {
    static FACES: OnceLock<Vec<Face>> = OnceLock::new();
    FACES.get_or_init(|| {
        FONTS
            .iter()
            .map(|file| {
                // The bytes are compiled in and known good (a unit test parses every one).
                let font = skrifa::FontRef::new(file.bytes).expect("a bundled font parses");
                let metrics = font.metrics(Size::unscaled(), LocationRef::default());
                Face {
                    shaper: harfrust::ShaperData::new(&font),
                    charmap: font.charmap(),
                    units_per_em: f32::from(metrics.units_per_em.max(1)),
                    ascent: metrics.ascent,
                    descent: metrics.descent,
                    leading: metrics.leading,
                    scale: file.scale,
                    font,
                }
            })
            .collect()
    })
}

/// The index in [`FONTS`] of the first font with a glyph for `c`; 0 (Ubuntu Light, whose
/// empty box then stands for it) where none has one.
pub fn face_for(c: char) -> usize {
    faces()
        .iter()
        .position(|face| face.charmap.map(c).is_some_and(|g| g.to_u32() != 0))
        .unwrap_or(0)
}

/// A run of text in one direction and one font: its byte range (logical order inside).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FontRun {
    pub range: Range<usize>,
    pub rtl: bool,
    pub face: usize,
}

/// `text`'s runs in visual order, left to right: the bidirectional level runs, each split where
/// the font changes (a grapheme cluster stays in its first character's font, as in egui).
pub fn runs(text: &str) -> Vec<FontRun> {
    let mut out = Vec::new();
    for level_run in bidi::visual_runs(text) {
        let start = out.len();
        let part = &text[level_run.range.clone()];
        for (offset, cluster) in part.grapheme_indices(true) {
            let face = cluster.chars().next().map_or(0, face_for);
            let begin = level_run.range.start + offset;
            let end = begin + cluster.len();
            let in_this_run = out.len() > start;
            match out.last_mut() {
                Some(FontRun { range, face: f, .. }) if in_this_run && *f == face => {
                    range.end = end;
                }
                _ => out.push(FontRun {
                    range: begin..end,
                    rtl: level_run.rtl,
                    face,
                }),
            }
        }
        // A right-to-left run's font runs are seen last first.
        if level_run.rtl {
            out[start..].reverse();
        }
    }
    out
}

/// Pieces of `text` in visual order for a shaper that lays its pieces left to right and guesses
/// each one's direction from its script (egui does: it has no bidirectional algorithm). A run
/// whose guessed direction is its own is one piece; any other (brackets and spaces in a
/// right-to-left run, Arabic-Indic digits in a left-to-right one) is cut into its grapheme
/// clusters, placed in visual order, mirrored where seen right to left.
pub fn guessing_shaper_pieces(text: &str) -> Vec<String> {
    let mut pieces = Vec::new();
    for run in runs(text) {
        let part = &text[run.range.clone()];
        if guessed_rtl(part) == run.rtl {
            pieces.push(part.to_string());
        } else if run.rtl {
            pieces.extend(part.graphemes(true).rev().map(|cluster| {
                let mut chars = cluster.chars();
                let first = chars.next().map(bidi::mirrored);
                first.into_iter().chain(chars).collect::<String>()
            }));
        } else {
            pieces.extend(part.graphemes(true).map(str::to_string));
        }
    }
    pieces
}

/// Whether harfrust guesses `text` right to left (from the script of its first letter that has
/// one), as egui lets it.
fn guessed_rtl(text: &str) -> bool {
    let mut buffer = harfrust::UnicodeBuffer::new();
    buffer.push_str(text);
    buffer.guess_segment_properties();
    buffer.direction() == harfrust::Direction::RightToLeft
}

/// A shaped glyph: its font (index in [`FONTS`]), its id, its origin's x from the text's left
/// and its baseline's distance from the line's top, in the units of the size it was shaped at.
#[derive(Clone, Copy, Debug)]
pub struct Placed {
    pub face: usize,
    pub glyph: u32,
    pub x: f32,
    pub y: f32,
}

/// A line of text shaped at `px` pixels an em: its glyphs in visual order, width and height
/// (egui's row height from Ubuntu Light: ascent, descent and line gap, each rounded), and the
/// baseline's distance from the top.
pub struct Shaped {
    pub glyphs: Vec<Placed>,
    pub width: f32,
    pub height: f32,
    pub baseline: f32,
}

/// Shapes `text` at `px` (the font size in the units wanted: points to measure, pixels to draw).
pub fn shape(text: &str, px: f32) -> Shaped {
    let faces = faces();
    let (baseline, height) = faces[0].row(px);
    let mut x = 0.0;
    let mut glyphs = Vec::with_capacity(text.len());
    for run in runs(text) {
        let face = &faces[run.face];
        let scale = px * face.scale / face.units_per_em;
        // A fallback face is centred on the line as egui centres it.
        let (face_ascent, face_height) = face.row(px);
        let face_baseline = face_ascent + 0.5 * (height - face_height);
        let shaper = face.shaper.shaper(&face.font).build();
        let mut buffer = harfrust::UnicodeBuffer::new();
        buffer.push_str(&text[run.range.clone()]);
        buffer.set_direction(if run.rtl {
            harfrust::Direction::RightToLeft
        } else {
            harfrust::Direction::LeftToRight
        });
        buffer.guess_segment_properties();
        let shaped = shaper.shape(buffer, harfrust::ShapeOptions::new());
        for (info, pos) in shaped.glyph_infos().iter().zip(shaped.glyph_positions()) {
            glyphs.push(Placed {
                face: run.face,
                glyph: info.glyph_id,
                x: x + pos.x_offset as f32 * scale,
                y: face_baseline - pos.y_offset as f32 * scale,
            });
            x += pos.x_advance as f32 * scale;
        }
    }
    Shaped {
        glyphs,
        width: x,
        height,
        baseline,
    }
}

/// The size of `text`'s box at `size` points: its width and egui's row height.
pub fn measure(text: &str, size: f32) -> [f32; 2] {
    let shaped = shape(text, size);
    [shaped.width, shaped.height]
}

/// Outlines glyphs at one pixel size, hinted as egui hints them (smooth, symmetric, linear
/// metrics kept); a font's hinting is set up the first time one of its glyphs is drawn.
pub struct Outliner {
    hinting: Vec<Option<Option<HintingInstance>>>,
    px: f32,
}

impl Outliner {
    pub fn new(px: f32) -> Self {
        Self {
            hinting: (0..FONTS.len()).map(|_| None).collect(),
            px,
        }
    }

    /// Glyph `glyph` of font `face`'s outline in pixels, origin at `(x, y)` (baseline), y down;
    /// None for a glyph without one (a space).
    pub fn outline(&mut self, face: usize, glyph: u32, x: f64, y: f64) -> Option<BezPath> {
        let font = &faces().get(face)?;
        let size = Size::new(self.px * font.scale);
        let outlines = font.font.outline_glyphs();
        let hinting = self.hinting.get_mut(face)?.get_or_insert_with(|| {
            let target = Target::Smooth {
                mode: SmoothMode::Normal,
                symmetric_rendering: true,
                preserve_linear_metrics: true,
            };
            HintingInstance::new(&outlines, size, LocationRef::default(), target).ok()
        });
        let outline = outlines.get(skrifa::GlyphId::new(glyph))?;
        let mut path = BezPath::new();
        let mut pen = Pen {
            path: &mut path,
            x,
            y,
        };
        let drawn = match hinting {
            Some(hinting) => outline.draw(DrawSettings::hinted(hinting, false), &mut pen),
            None => outline.draw(
                DrawSettings::unhinted(size, LocationRef::default()),
                &mut pen,
            ),
        };
        (drawn.is_ok() && !path.elements().is_empty()).then_some(path)
    }
}

/// A skrifa outline into a kurbo path, y flipped to point down, moved to `(x, y)`.
struct Pen<'a> {
    path: &'a mut BezPath,
    x: f64,
    y: f64,
}

impl Pen<'_> {
    fn at(&self, x: f32, y: f32) -> (f64, f64) {
        (self.x + f64::from(x), self.y - f64::from(y))
    }
}

impl OutlinePen for Pen<'_> {
    fn move_to(&mut self, x: f32, y: f32) {
        let p = self.at(x, y);
        self.path.move_to(p);
    }

    fn line_to(&mut self, x: f32, y: f32) {
        let p = self.at(x, y);
        self.path.line_to(p);
    }

    fn quad_to(&mut self, cx0: f32, cy0: f32, x: f32, y: f32) {
        let (c, p) = (self.at(cx0, cy0), self.at(x, y));
        self.path.quad_to(c, p);
    }

    fn curve_to(&mut self, cx0: f32, cy0: f32, cx1: f32, cy1: f32, x: f32, y: f32) {
        let (c0, c1, p) = (self.at(cx0, cy0), self.at(cx1, cy1), self.at(x, y));
        self.path.curve_to(c0, c1, p);
    }

    fn close(&mut self) {
        self.path.close_path();
    }
}

/// `text` cut to at most `width` points at `size`, ending in "…" where cut.
pub fn fit_text(text: &str, size: f32, width: f32) -> String {
    if measure(text, size)[0] <= width {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    let (mut lo, mut hi) = (0usize, chars.len());
    // The longest prefix that fits with its ellipsis.
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        let candidate: String = chars[..mid].iter().collect::<String>() + "…";
        if measure(&candidate, size)[0] <= width {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    let kept: String = chars[..lo].iter().collect();
    format!("{}…", kept.trim_end())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_measures_wider_with_more_letters_and_taller_with_a_larger_size() {
        let [w1, h1] = measure("-30", 12.0);
        let [w2, _] = measure("-30 dB", 12.0);
        let [w3, h3] = measure("-30", 24.0);
        assert!(w1 > 10.0 && w1 < 30.0, "{w1}");
        assert!(w2 > w1 + 10.0);
        assert!((w3 - 2.0 * w1).abs() < 1.0, "{w3} vs {w1}");
        assert!((12.0..=18.0).contains(&h1), "{h1}");
        assert!(h3 > 1.8 * h1);
        assert_eq!(measure("", 12.0)[0], 0.0);
    }

    #[test]
    fn glyphs_have_outlines_and_spaces_none() {
        let shaped = shape("a b", 14.0);
        assert_eq!(shaped.glyphs.len(), 3);
        let mut outliner = Outliner::new(14.0);
        let [a, space, _] = [0, 1, 2].map(|i| shaped.glyphs[i]);
        assert!(outliner.outline(a.face, a.glyph, 0.0, 12.0).is_some());
        assert!(
            outliner
                .outline(space.face, space.glyph, 0.0, 12.0)
                .is_none()
        );
    }

    #[test]
    fn every_bundled_font_parses() {
        assert_eq!(faces().len(), FONTS.len());
    }

    /// The characters of `text` (spaces aside) that no font has: drawn as the empty box.
    fn boxes(text: &str) -> Vec<char> {
        let shaped = shape(text, 14.0);
        let mut missing: Vec<char> = text
            .chars()
            .filter(|c| !c.is_whitespace() && faces()[face_for(*c)].charmap.map(*c).is_none())
            .collect();
        if shaped.glyphs.iter().any(|g| g.glyph == 0) && missing.is_empty() {
            missing.push('\u{FFFD}');
        }
        missing
    }

    #[test]
    fn hebrew_arabic_and_emoji_find_glyphs_not_the_empty_box() {
        // Ubuntu Light alone drew every one of these as the box (glyph 0).
        for text in [
            "שלום 2020 (2000)",
            "مرحبا بالعالم",
            "🎵🔊😀",
            "नमस्ते",
            "สวัสดี",
            "Բարեւ",
            "გამარჯობა",
            "Ünïcödé Ελληνικά Кириллица",
        ] {
            assert_eq!(boxes(text), Vec::<char>::new(), "{text}");
            let shaped = shape(text, 14.0);
            assert!(shaped.glyphs.iter().all(|g| g.glyph != 0), "{text}");
        }
        // Something nothing covers still is a box, and says so.
        assert!(
            shape("\u{10FFFD}", 14.0)
                .glyphs
                .iter()
                .all(|g| g.glyph == 0)
        );
    }

    #[test]
    fn arabic_letters_join_and_hebrew_reads_right_to_left() {
        // Joined forms differ from the isolated letters: "بب" is not two isolated beh.
        let isolated = shape("ب", 14.0).glyphs[0].glyph;
        let joined = shape("ببب", 14.0);
        assert_eq!(joined.glyphs.len(), 3);
        assert!(
            joined.glyphs.iter().all(|g| g.glyph != isolated),
            "{isolated}"
        );
        // The first letter of a right-to-left word is drawn rightmost.
        let shin = shape("ש", 14.0).glyphs[0].glyph;
        let word = shape("שלום", 14.0);
        let rightmost = word
            .glyphs
            .iter()
            .max_by(|a, b| a.x.total_cmp(&b.x))
            .expect("glyphs");
        assert_eq!(rightmost.glyph, shin);
        // In "שלום 2020 (2000)" the year comes first, left to right, the word last.
        let title = shape("שלום 2020 (2000)", 14.0);
        let digits: Vec<u32> = "0123456789"
            .chars()
            .map(|c| shape(&c.to_string(), 14.0).glyphs[0].glyph)
            .collect();
        let seen: String = title
            .glyphs
            .iter()
            .filter(|g| g.face == 0)
            .filter_map(|g| digits.iter().position(|d| *d == g.glyph))
            .map(|d| char::from(b'0' + d as u8))
            .collect();
        assert_eq!(seen, "20002020");
        assert_eq!(title.glyphs.last().expect("glyphs").glyph, shin);
    }

    #[test]
    fn pieces_for_a_guessing_shaper_come_out_in_visual_order() {
        let joined = |text: &str| guessing_shaper_pieces(text).concat();
        // The word stays in logical order (the shaper reverses it), the rest is placed.
        assert_eq!(
            guessing_shaper_pieces("שלום 2020 (2000)"),
            ["(", "2000", ")", " ", "2020", " ", "שלום"]
        );
        assert_eq!(guessing_shaper_pieces("Song (1984)"), ["Song (1984)"]);
        assert_eq!(joined("Best of שלום (1999)"), "Best of (1999) שלום");
        // Arabic-Indic digits guess right to left but read left to right: one piece each.
        assert_eq!(guessing_shaper_pieces("١٢"), ["١", "٢"]);
        assert!(guessing_shaper_pieces("").is_empty());
    }
}
