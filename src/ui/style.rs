//! What the window's panels and its status area share of their look: the panels' frame and the
//! warning colour (also the in-view notices').

use eframe::egui::{self, Color32};

/// The colour of an error line.
pub(super) const ERROR: Color32 = Color32::from_rgb(240, 120, 100);
/// The colour of a warning line.
pub(super) const WARNING: Color32 = Color32::from_rgb(230, 190, 110);

/// The frame of the window's panels: egui's own, without its fill. The window is cleared to the
/// panels' colour ([`eframe::App::clear_color`]), so the fill would paint every panel pixel a
/// second time; on a software rasterizer (lavapipe, llvmpipe) egui's per-pixel shading of those
/// rectangles was a third of every frame's cost (docs/PERFORMANCE.md), on a GPU it is nothing.
/// The picture is the same.
pub(super) fn panel_frame(style: &egui::Style) -> egui::Frame {
    egui::Frame::side_top_panel(style).fill(Color32::TRANSPARENT)
}
