//! A/B compare in pictures: the titles of the two halves, the diverging legend of the
//! Difference view, and the headless overlay that draws them (with the axis labels) into a
//! render target.
//!
//! The diverging legend is painted here until the shared one in `legends.rs` lands: a vertical
//! strip of the Difference view's map (the hp palette read as `0.5 - t / 2`: red where B is
//! louder, white at zero, blue where A is), its signed range at the ends and 0 in the middle.

use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Stroke};

use crate::render::colormap::HpColourMap;
use crate::render::grid::difference::DifferenceMeasure;

/// Swatches in the diverging strip.
const STEPS: usize = 64;
const TEXT: Color32 = Color32::from_rgb(225, 230, 238);
const SMALL: Color32 = Color32::from_rgb(170, 178, 192);

/// The diverging map's colour at `t` in [-1, 1] (B - A over the range).
pub fn diverging_color(t: f32) -> Color32 {
    let [r, g, b] = HpColourMap::Classic
        .points()
        .sample_u8(0.5 - 0.5 * t.clamp(-1.0, 1.0));
    Color32::from_rgb(r, g, b)
}

/// How a signed value prints on the legend: three significant digits, with its sign.
pub fn format_signed(value: f32) -> String {
    if value == 0.0 || value.abs() < 1e-30 {
        return "0".into();
    }
    let digits = (2 - value.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{value:+.digits$}")
}

/// Paints the diverging legend in `rect` (a tall strip with its labels to the right):
/// `+range` at the top ("B louder"), 0 in the middle, `-range` at the bottom ("A louder").
pub fn paint_diverging_legend(
    painter: &egui::Painter,
    rect: Rect,
    measure: DifferenceMeasure,
    range: f32,
) {
    painter.rect_filled(
        rect.expand(6.0),
        4.0,
        Color32::from_rgba_unmultiplied(12, 14, 20, 200),
    );
    let strip = Rect::from_min_size(
        rect.min + egui::vec2(0.0, 22.0),
        egui::vec2(14.0, rect.height() - 44.0),
    );
    painter.text(
        rect.min,
        Align2::LEFT_TOP,
        measure.describe(),
        FontId::proportional(13.0),
        TEXT,
    );
    for i in 0..STEPS {
        let y0 = strip.top() + strip.height() * i as f32 / STEPS as f32;
        let y1 = strip.top() + strip.height() * (i + 1) as f32 / STEPS as f32;
        let t = 1.0 - 2.0 * (i as f32 + 0.5) / STEPS as f32;
        painter.rect_filled(
            Rect::from_x_y_ranges(strip.x_range(), y0..=y1 + 0.5),
            0.0,
            diverging_color(t),
        );
    }
    painter.rect_stroke(
        strip,
        0.0,
        Stroke::new(1.0, SMALL),
        egui::StrokeKind::Outside,
    );
    let label = |y: f32, text: String| {
        painter.text(
            Pos2::new(strip.right() + 6.0, y),
            Align2::LEFT_CENTER,
            text,
            FontId::proportional(12.0),
            SMALL,
        );
    };
    label(strip.top(), format!("{} B louder", format_signed(range)));
    label(strip.center().y, "0 (transparent)".into());
    label(
        strip.bottom(),
        format!("{} A louder", format_signed(-range)),
    );
}

/// A title at the top left of `rect`.
pub fn paint_title(painter: &egui::Painter, rect: Rect, text: &str) {
    let galley = painter.layout_no_wrap(text.to_owned(), FontId::proportional(15.0), TEXT);
    painter.rect_filled(
        Rect::from_min_size(
            rect.min + egui::vec2(4.0, 4.0),
            galley.size() + egui::vec2(12.0, 8.0),
        ),
        4.0,
        Color32::from_rgba_unmultiplied(12, 14, 20, 180),
    );
    painter.text(
        rect.min + egui::vec2(10.0, 8.0),
        Align2::LEFT_TOP,
        text,
        FontId::proportional(15.0),
        TEXT,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_values_print_with_their_sign() {
        assert_eq!(format_signed(0.0), "0");
        assert_eq!(format_signed(0.25), "+0.250");
        assert_eq!(format_signed(-12.5), "-12.5");
    }

    #[test]
    fn the_map_is_warm_above_zero_and_cool_below() {
        let warm = diverging_color(1.0);
        let cool = diverging_color(-1.0);
        assert!(warm.r() > warm.b());
        assert!(cool.b() > cool.r());
    }
}
