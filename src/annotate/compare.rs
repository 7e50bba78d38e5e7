//! A/B compare pictures: the titles of the halves and of the difference view, and the
//! difference view's vertical diverging legend (the hp palette read as `0.5 - t / 2`: red where
//! B is louder, white at zero, blue where A is; its signed range at the ends and 0 in the
//! middle), laid out as plain data.

use super::{Anchor, Annotation, Rect, Rgba, Shape, Text};
use crate::render::colormap::HpColourMap;
use crate::render::grid::difference::DifferenceMeasure;

/// Swatches in the diverging strip.
const STEPS: usize = 64;
const TEXT: Rgba = [225, 230, 238, 255];
const SMALL: Rgba = [170, 178, 192, 255];
/// The size of the difference view's legend box (strip and labels), points.
pub const LEGEND_SIZE: [f32; 2] = [160.0, 180.0];

/// The diverging map's colour at `t` in [-1, 1] (B - A over the range).
pub fn diverging_color(t: f32) -> [u8; 3] {
    HpColourMap::Classic
        .points()
        .sample_u8(0.5 - 0.5 * t.clamp(-1.0, 1.0))
}

/// How a signed value prints on the legend: three significant digits, with its sign.
pub fn format_signed(value: f32) -> String {
    if value == 0.0 || value.abs() < 1e-30 {
        return "0".into();
    }
    let digits = (2 - value.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{value:+.digits$}")
}

/// The diverging legend in `rect` (a tall strip with its labels to the right): `+range` at the
/// top ("B louder"), 0 in the middle, `-range` at the bottom ("A louder").
pub fn diverging_legend(rect: Rect, measure: DifferenceMeasure, range: f32) -> Annotation {
    let mut out = Annotation::default();
    out.fill(rect.expand(6.0), 4.0, [12, 14, 20, 200]);
    let strip = Rect::from_min_size(
        [rect.left(), rect.top() + 22.0],
        [14.0, rect.height() - 44.0],
    );
    out.text(Text::new(
        measure.describe(),
        rect.min,
        Anchor::LEFT_TOP,
        13.0,
        TEXT,
    ));
    for i in 0..STEPS {
        let y0 = strip.top() + strip.height() * i as f32 / STEPS as f32;
        let y1 = strip.top() + strip.height() * (i + 1) as f32 / STEPS as f32;
        let t = 1.0 - 2.0 * (i as f32 + 0.5) / STEPS as f32;
        out.fill(
            Rect::from_min_max([strip.left(), y0], [strip.right(), y1 + 0.5]),
            0.0,
            super::rgb(diverging_color(t)),
        );
    }
    out.push(Shape::Frame {
        rect: strip,
        width: 1.0,
        colour: SMALL,
    });
    let label = |y: f32, text: String| {
        Shape::Text(Text::new(
            text,
            [strip.right() + 6.0, y],
            Anchor::LEFT_CENTER,
            12.0,
            SMALL,
        ))
    };
    out.push(label(
        strip.top(),
        format!("{} B louder", format_signed(range)),
    ));
    out.push(label(strip.center()[1], "0 (transparent)".into()));
    out.push(label(
        strip.bottom(),
        format!("{} A louder", format_signed(-range)),
    ));
    out
}

/// A title at the top left of `rect` on a plate; returns it and the plate's box.
pub fn title(rect: Rect, text: &str) -> (Annotation, Rect) {
    let room = (rect.width() - 20.0).max(0.0);
    let text = super::font::fit_text(text, 15.0, room);
    let label = Text::new(
        text,
        [rect.left() + 10.0, rect.top() + 8.0],
        Anchor::LEFT_TOP,
        15.0,
        TEXT,
    );
    let plate = Rect::from_min_size(
        [rect.left() + 4.0, rect.top() + 4.0],
        [label.rect.width() + 12.0, label.rect.height() + 8.0],
    );
    let mut out = Annotation::default();
    out.fill(plate, 4.0, [12, 14, 20, 180]);
    out.text(label);
    (out, plate)
}

/// The difference view's title and legend over `rect`: the legend at the top right, or under
/// the title where the two would meet (a narrow view).
pub fn difference_overlay(
    rect: Rect,
    text: &str,
    legend: Option<(DifferenceMeasure, f32)>,
) -> Annotation {
    let (mut out, plate) = title(rect, text);
    if let Some((measure, range)) = legend {
        let [w, h] = LEGEND_SIZE;
        let mut at = Rect::from_min_size([rect.right() - w - 10.0, rect.top() + 40.0], [w, h]);
        // The legend's labels run up to 110 points right of its strip; its plate 6 around.
        if at.expand(6.0).intersects(&plate.expand(4.0)) {
            at = Rect::from_min_size([rect.right() - w - 10.0, plate.bottom() + 16.0], [w, h]);
        }
        out.extend(diverging_legend(at, measure, range));
    }
    out
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
        assert!(warm[0] > warm[2]);
        assert!(cool[2] > cool[0]);
    }

    #[test]
    fn the_difference_legend_never_covers_the_title() {
        for width in [240.0f32, 320.0, 400.0, 640.0, 1280.0] {
            let rect = Rect::from_min_size([0.0, 0.0], [width, 400.0]);
            let title_text = "B - A: master_loud.flac against master.flac";
            let (_, plate) = title(rect, title_text);
            let out = difference_overlay(rect, title_text, Some((DifferenceMeasure::Density, 6.0)));
            let texts: Vec<&Text> = out.texts().collect();
            for t in &texts[1..] {
                assert!(
                    !t.rect.intersects(&plate),
                    "{width}: '{}' over the title",
                    t.text
                );
            }
            assert!(
                texts[0].rect.right() <= width,
                "{width}: the title runs off"
            );
        }
    }
}
