//! The window's font for pictures: Ubuntu Light (egui's proportional font, from the same
//! `epaint_default_fonts` bytes), shaped with harfrust (kerning included) and hinted with skrifa
//! as egui does, so a label measures and looks the same in a PNG as in the window.

use std::sync::OnceLock;

use skrifa::MetadataProvider;
use skrifa::instance::{LocationRef, Size};
use skrifa::outline::{DrawSettings, HintingInstance, OutlinePen, SmoothMode, Target};
use vello_cpu::kurbo::BezPath;

/// The font's bytes.
const FONT: &[u8] = epaint_default_fonts::UBUNTU_LIGHT;

struct Face {
    font: skrifa::FontRef<'static>,
    shaper: harfrust::ShaperData,
    units_per_em: f32,
    ascent: f32,
    descent: f32,
    leading: f32,
}

fn face() -> &'static Face {
    static FACE: OnceLock<Face> = OnceLock::new();
    FACE.get_or_init(|| {
        // The bytes are compiled in and known good.
        let font = skrifa::FontRef::new(FONT).expect("the bundled font parses");
        let metrics = font.metrics(Size::unscaled(), LocationRef::default());
        Face {
            shaper: harfrust::ShaperData::new(&font),
            units_per_em: f32::from(metrics.units_per_em.max(1)),
            ascent: metrics.ascent,
            descent: metrics.descent,
            leading: metrics.leading,
            font,
        }
    })
}

/// A shaped glyph: its id and its origin's x from the text's left, in the units of the size
/// it was shaped at.
#[derive(Clone, Copy, Debug)]
pub struct Placed {
    pub glyph: u32,
    pub x: f32,
}

/// A line of text shaped at `px` pixels an em: its glyphs, width and height (egui's row height:
/// ascent, descent and line gap, each rounded), and the baseline's distance from the top.
pub struct Shaped {
    pub glyphs: Vec<Placed>,
    pub width: f32,
    pub height: f32,
    pub baseline: f32,
}

/// Shapes `text` at `px` (the font size in the units wanted: points to measure, pixels to draw).
pub fn shape(text: &str, px: f32) -> Shaped {
    let face = face();
    let scale = px / face.units_per_em;
    let shaper = face.shaper.shaper(&face.font).build();
    let mut buffer = harfrust::UnicodeBuffer::new();
    buffer.push_str(text);
    buffer.guess_segment_properties();
    let shaped = shaper.shape(buffer, harfrust::ShapeOptions::new());
    let mut x = 0.0;
    let mut glyphs = Vec::with_capacity(shaped.len());
    for (info, pos) in shaped.glyph_infos().iter().zip(shaped.glyph_positions()) {
        glyphs.push(Placed {
            glyph: info.glyph_id,
            x: x + pos.x_offset as f32 * scale,
        });
        x += pos.x_advance as f32 * scale;
    }
    let ascent = (face.ascent * scale).round();
    let descent = (face.descent * scale).round();
    let leading = (face.leading * scale).round();
    Shaped {
        glyphs,
        width: x,
        height: ascent - descent + leading,
        baseline: ascent,
    }
}

/// The size of `text`'s box at `size` points: its width and egui's row height.
pub fn measure(text: &str, size: f32) -> [f32; 2] {
    let shaped = shape(text, size);
    [shaped.width, shaped.height]
}

/// Outlines glyphs at one pixel size, hinted as egui hints them (smooth, symmetric, linear
/// metrics kept).
pub struct Outliner {
    hinting: Option<HintingInstance>,
    px: f32,
}

impl Outliner {
    pub fn new(px: f32) -> Self {
        let face = face();
        let target = Target::Smooth {
            mode: SmoothMode::Normal,
            symmetric_rendering: true,
            preserve_linear_metrics: true,
        };
        let hinting = HintingInstance::new(
            &face.font.outline_glyphs(),
            Size::new(px),
            LocationRef::default(),
            target,
        )
        .ok();
        Self { hinting, px }
    }

    /// Glyph `glyph`'s outline in pixels, origin at `(x, y)` (baseline), y down; None for a glyph
    /// without one (a space).
    pub fn outline(&self, glyph: u32, x: f64, y: f64) -> Option<BezPath> {
        let outlines = face().font.outline_glyphs();
        let outline = outlines.get(skrifa::GlyphId::new(glyph))?;
        let mut path = BezPath::new();
        let mut pen = Pen {
            path: &mut path,
            x,
            y,
        };
        let drawn = match &self.hinting {
            Some(hinting) => outline.draw(DrawSettings::hinted(hinting, false), &mut pen),
            None => outline.draw(
                DrawSettings::unhinted(Size::new(self.px), LocationRef::default()),
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
        let outliner = Outliner::new(14.0);
        assert!(
            outliner
                .outline(shaped.glyphs[0].glyph, 0.0, 12.0)
                .is_some()
        );
        assert!(
            outliner
                .outline(shaped.glyphs[1].glyph, 0.0, 12.0)
                .is_none()
        );
    }
}
