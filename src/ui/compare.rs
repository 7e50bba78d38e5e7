//! A/B compare over the window's view: a title and, in the Difference view, its diverging
//! legend, laid out by `annotate::compare` (as compare pictures draw them), painted with egui's
//! painter.

use eframe::egui;

pub use crate::annotate::compare::format_signed;
use crate::render::grid::difference::DifferenceMeasure;
use crate::ui::annotation;

/// The Difference view's title and, when given, its legend (top right, or under the title in a
/// narrow view).
pub fn paint_difference(
    painter: &egui::Painter,
    rect: egui::Rect,
    text: &str,
    legend: Option<(DifferenceMeasure, f32)>,
) {
    let shapes = crate::annotate::compare::difference_overlay(annotation::rect(rect), text, legend);
    annotation::paint(painter, &shapes);
}
