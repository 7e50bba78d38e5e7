//! The loudness strip under the 3D view in Song mode: laid out by `annotate::strip` (as a video
//! draws it), painted with egui; clicking or dragging on it seeks.

use eframe::egui::{self, Align2, Color32, FontId, Pos2, Sense, Vec2};

pub use crate::annotate::strip::*;
use crate::playback::format_clock;
use crate::ui::annotation;

/// The window's side of the strip: painting and seeking.
impl LoudnessStrip {
    /// Draws the strip at the full width of `ui`, the playhead at `playhead_s`; returns the
    /// time to seek to when the strip was clicked or dragged.
    pub fn show(&self, ui: &mut egui::Ui, playhead_s: f64) -> Option<f64> {
        let curves = self.curves()?;
        let (rect, response) = ui.allocate_exact_size(
            Vec2::new(ui.available_width(), STRIP_HEIGHT),
            Sense::click_and_drag(),
        );
        let painter = ui.painter_at(rect);
        self.paint(&painter, rect, Some(playhead_s));
        let plot = annotation::egui_rect(Self::plot_rect(annotation::rect(rect)));
        let duration = self.duration_s();
        let small = FontId::proportional(SMALL);
        if let Some(pos) = response.hover_pos() {
            let t = time_of_x(pos.x, plot.left(), plot.right(), duration);
            let index = ((t - curves.short_term_start_s) * curves.rate_hz).round();
            let at = |values: &[Option<f32>]| {
                (index >= 0.0)
                    .then(|| values.get(index as usize).copied().flatten())
                    .flatten()
            };
            let mut text = format_clock(t);
            if let Some(v) = at(&curves.short_term_lufs) {
                text.push_str(&format!("  short-term {v:.1} LUFS"));
            }
            if let Some(v) = at(&curves.psr_db) {
                text.push_str(&format!("  PSR {v:.1} dB"));
            }
            painter.text(
                Pos2::new(plot.right() - 4.0, plot.top() + 2.0),
                Align2::RIGHT_TOP,
                text,
                small,
                Color32::from_gray(220),
            );
        }
        let seek = (response.clicked() || response.dragged())
            .then(|| response.interact_pointer_pos())
            .flatten()
            .map(|p| time_of_x(p.x, plot.left(), plot.right(), duration));
        if seek.is_some() {
            ui.ctx().request_repaint();
        }
        seek
    }

    /// Paints the strip into `rect` with `painter`.
    pub fn paint(&self, painter: &egui::Painter, rect: egui::Rect, playhead_s: Option<f64>) {
        annotation::paint(painter, &self.layout(annotation::rect(rect), playhead_s));
    }
}
