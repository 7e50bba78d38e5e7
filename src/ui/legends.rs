//! Colour legends of the side panel: one strip painter for every palette (the points' hp
//! palette, the surface's warm-to-cool gradient, the volume's transfer function), with its ends
//! named below.

use eframe::egui::{self, Color32, RichText};

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

/// The points' hp palette.
pub(super) fn hp(ui: &mut egui::Ui) {
    strip(
        ui,
        |i| crate::render::palette::hp_color_u8(at(i)),
        ("percussive", 60.0, "harmonic (hp)"),
    );
}

/// The surface's colour by mean hp (the CPU mirror of shaders/surface/draw.wgsl's gradient).
pub(super) fn surface(ui: &mut egui::Ui) {
    ui.label(RichText::new("Surface colour (mean hp)").small());
    strip(
        ui,
        |i| crate::render::surface::draw::warm_cool(at(i)).map(|c| (c * 255.0).round() as u8),
        ("percussive", 60.0, "harmonic"),
    );
}

/// The transfer function's colour over density 0..1, darkened where it is transparent.
pub(super) fn transfer(ui: &mut egui::Ui, preset: TransferPreset) {
    let colours = preset.legend(STEPS);
    strip(
        ui,
        |i| {
            let [r, g, b, _] = colours[i];
            [r, g, b]
        },
        ("density 0", 120.0, "1"),
    );
}
