//! Picture annotation (`annotate`: labels, legends, titles, the loudness strip as plain data)
//! painted with egui's painter, so the window shows what pictures draw.

use eframe::egui::{self, Color32, FontId, Stroke};

use crate::annotate::{Annotation, Rect, Rgba, Shape};

/// An egui rectangle as annotation's.
pub fn rect(r: egui::Rect) -> Rect {
    Rect::from_min_max([r.min.x, r.min.y], [r.max.x, r.max.y])
}

/// An annotation rectangle as egui's.
pub fn egui_rect(r: Rect) -> egui::Rect {
    egui::Rect::from_min_max(
        egui::pos2(r.min[0], r.min[1]),
        egui::pos2(r.max[0], r.max[1]),
    )
}

pub fn colour(c: Rgba) -> Color32 {
    Color32::from_rgba_unmultiplied(c[0], c[1], c[2], c[3])
}

fn pos(p: [f32; 2]) -> egui::Pos2 {
    egui::pos2(p[0], p[1])
}

/// Paints `annotation` with `painter`, shape after shape.
pub fn paint(painter: &egui::Painter, annotation: &Annotation) {
    for shape in &annotation.shapes {
        match shape {
            Shape::Fill {
                rect,
                radius,
                colour: c,
            } => {
                painter.rect_filled(egui_rect(*rect), *radius, colour(*c));
            }
            Shape::Frame {
                rect,
                width,
                colour: c,
            } => {
                painter.rect_stroke(
                    egui_rect(*rect),
                    0.0,
                    Stroke::new(*width, colour(*c)),
                    egui::StrokeKind::Outside,
                );
            }
            Shape::Line {
                points,
                width,
                colour: c,
            } => {
                let stroke = Stroke::new(*width, colour(*c));
                if let [a, b] = points.as_slice() {
                    painter.line_segment([pos(*a), pos(*b)], stroke);
                } else {
                    painter.add(egui::Shape::line(
                        points.iter().map(|p| pos(*p)).collect(),
                        stroke,
                    ));
                }
            }
            Shape::Text(text) => {
                // In visual order, as pictures draw it (a Hebrew title right to left).
                let job = super::style::bidi_job(
                    &text.text,
                    FontId::proportional(text.size),
                    colour(text.colour),
                );
                let galley = painter.layout_job(job);
                painter.galley(pos(text.rect.min), galley, colour(text.colour));
            }
        }
    }
}
