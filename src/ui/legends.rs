//! Colour legends: the side panel's strips (one painter for every palette: the points' hp map,
//! the surface's, the volume's transfer function, with their ends named below), and the legends
//! of pictures painted over the window's view ([`paint_picture`]): laid out by
//! `annotate::legend`, which headless pictures draw on the CPU.

use eframe::egui::{self, Color32, RichText};

pub use crate::annotate::legend::{
    Key, MARGIN, PictureLegend, diverging_position, picture_legend, picture_name, timeline_name,
    titled_with_reference,
};
use crate::render::colormap::{Colours, HpColourMap};
use crate::render::transfer::TransferPreset;
use crate::ui::annotation;

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

/// Where the colour strip of a picture of `rect` lies (`annotate::legend::key_strip_rect`).
pub fn key_strip_rect(rect: egui::Rect) -> egui::Rect {
    annotation::egui_rect(crate::annotate::legend::key_strip_rect(annotation::rect(
        rect,
    )))
}

/// Paints `legend` over a picture occupying `rect`: the name top left, the key top right (or
/// under the name where they would meet).
pub fn paint_picture(painter: &egui::Painter, rect: egui::Rect, legend: &PictureLegend) {
    let shapes = crate::annotate::legend::layout(annotation::rect(rect), legend);
    annotation::paint(painter, &shapes);
}

/// Paints a view's legend over `rect` and, when given, its axis labels laid out clear of it
/// (as pictures draw them: `annotate::labels_and_legend`).
pub fn paint_with_labels(
    painter: &egui::Painter,
    rect: egui::Rect,
    view: &crate::view::frame_view::FrameView,
    labels: Option<&crate::annotate::axes::AxisLabels>,
    legend: &PictureLegend,
) {
    let area = annotation::rect(rect);
    let shapes = crate::annotate::overlay::labels_and_legend(
        area,
        view,
        labels,
        legend.background,
        crate::annotate::legend::layout(area, legend),
    );
    annotation::paint(painter, &shapes);
}
