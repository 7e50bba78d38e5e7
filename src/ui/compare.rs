//! A/B compare over the window's view: the titles of the two halves and the Difference view's
//! title and diverging legend, laid out by `annotate::compare` (as compare pictures draw them),
//! painted with egui's painter.

use eframe::egui;

pub use crate::annotate::compare::format_signed;
use crate::render::grid::difference::DifferenceMeasure;
use crate::ui::annotation;

/// Paints the diverging legend in `rect` (a tall strip with its labels to the right).
pub fn paint_diverging_legend(
    painter: &egui::Painter,
    rect: egui::Rect,
    measure: DifferenceMeasure,
    range: f32,
) {
    let shapes = crate::annotate::compare::diverging_legend(annotation::rect(rect), measure, range);
    annotation::paint(painter, &shapes);
}

/// A title at the top left of `rect`.
pub fn paint_title(painter: &egui::Painter, rect: egui::Rect, text: &str) {
    let (shapes, _) = crate::annotate::compare::title(annotation::rect(rect), text);
    annotation::paint(painter, &shapes);
}

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
