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

/// The window's fonts: egui's, with the fallback fonts pictures draw with
/// ([`crate::annotate::font::FONTS`]: Hebrew, Arabic, Devanagari, Thai, Armenian and Georgian,
/// egui's icons and its monochrome emoji) in the same order and at the same sizes, so a title
/// in any of these scripts reads in the window as in a picture. All are compiled in; no platform
/// font is looked up.
pub(crate) fn install_fonts(ctx: &egui::Context) {
    ctx.set_fonts(font_definitions());
}

fn font_definitions() -> egui::FontDefinitions {
    use crate::annotate::font::FONTS;
    let mut fonts = egui::FontDefinitions::default();
    for file in &FONTS {
        let data = egui::FontData::from_static(file.bytes).tweak(egui::FontTweak {
            scale: file.scale,
            ..Default::default()
        });
        fonts
            .font_data
            .insert(file.name.to_string(), std::sync::Arc::new(data));
    }
    let names = || FONTS.iter().map(|file| file.name.to_string());
    fonts
        .families
        .insert(egui::FontFamily::Proportional, names().collect());
    let monospace = std::iter::once("Hack".to_string()).chain(names()).collect();
    fonts
        .families
        .insert(egui::FontFamily::Monospace, monospace);
    fonts
}

/// `text` laid out for egui in `font` and `colour` as it is seen: egui has no bidirectional
/// algorithm and guesses each font run's direction from its script, so the text goes in as
/// pieces in visual order ([`crate::annotate::font::guessing_shaper_pieces`]), one section
/// each, line by line. A Hebrew title with a year reads "(2000) 2020 םולש" left to right, as in
/// pictures.
/// `Color32::PLACEHOLDER` takes the widget's text colour.
pub(crate) fn bidi_job(text: &str, font: egui::FontId, colour: Color32) -> egui::text::LayoutJob {
    let mut job = egui::text::LayoutJob::default();
    let format = egui::TextFormat::simple(font, colour);
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            job.append("\n", 0.0, format.clone());
        }
        for piece in crate::annotate::font::guessing_shaper_pieces(line) {
            job.append(&piece, 0.0, format.clone());
        }
    }
    job
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The characters of `text` laid out by egui with the window's fonts, left to right as
    /// drawn, and whether any was drawn as the empty box.
    fn seen_in_window(text: &str) -> (String, bool) {
        let ctx = egui::Context::default();
        install_fonts(&ctx);
        let mut seen = (String::new(), false);
        // Fonts set now take effect at the next frame.
        for _ in 0..2 {
            let mut output = ctx.run_ui(egui::RawInput::default(), |ui| {
                let font = egui::FontId::proportional(14.0);
                let job = bidi_job(text, font.clone(), Color32::WHITE);
                let galley = ui.ctx().fonts_mut(|f| f.layout_job(job));
                let mut glyphs: Vec<(f32, char)> = galley
                    .rows
                    .iter()
                    .flat_map(|row| row.row.glyphs.iter())
                    // egui follows a right-to-left word's first glyph with zero-width,
                    // undrawn stand-ins for its other letters (one glyph a character).
                    .filter(|g| g.advance_width > 0.0)
                    .map(|g| (g.pos.x, g.chr))
                    .collect();
                glyphs.sort_by(|a, b| a.0.total_cmp(&b.0));
                let missing = text
                    .chars()
                    .any(|c| !ui.ctx().fonts_mut(|f| f.has_glyph(&font, c)));
                seen = (glyphs.into_iter().map(|(_, c)| c).collect(), missing);
            });
            // No renderer takes the font atlas here.
            output.textures_delta.clear();
        }
        seen
    }

    #[test]
    fn the_window_shows_hebrew_right_to_left_with_its_numbers_in_order() {
        // Plain egui drew this as "2020 (2000)" after the word, the year's brackets reversed.
        let (seen, missing) = seen_in_window("שלום 2020 (2000)");
        assert_eq!(seen, "(2000) 2020 םולש");
        assert!(!missing);
        assert_eq!(seen_in_window("Song (1984)").0, "Song (1984)");
    }

    #[test]
    fn the_window_has_glyphs_for_arabic_and_emoji() {
        for text in ["مرحبا", "🎵😀", "नमस्ते", "שלום"] {
            assert!(!seen_in_window(text).1, "{text}");
        }
    }
}
