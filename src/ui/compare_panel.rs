//! The compare section of the side panel: B's field and the "Compare with…" dialog, loading
//! and error lines, the layout (A only, side by side, difference), the difference measure and
//! the A/B listening switch. What it decides from the state (the typed path, the dialog's
//! answer, which side can be heard) is `state/compare_window.rs`.

use std::path::PathBuf;
use std::task::Poll;
use std::time::Duration;

use eframe::egui::{self, Color32, RichText};

use crate::render::grid::difference::DifferenceMeasure;
use crate::ui::compare_window::COMPARE_FIELD;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::compare_window::{CompareLayout, CompareState, Listening, typed_path};

impl LoudscapeApp {
    /// The compare section of the side panel.
    pub(super) fn compare_controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(6.0);
        ui.label(RichText::new("Compare (A/B)").strong());
        let mut start = None;
        ui.horizontal_wrapped(|ui| {
            let field = &mut self.open.compare_path;
            let edit = ui.add(
                egui::TextEdit::singleline(field)
                    .id(egui::Id::unique(COMPARE_FIELD))
                    .hint_text("B: song or cloud")
                    .desired_width(130.0),
            );
            let entered = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            start = typed_path(field, entered);
            let open = self.compare.as_ref().is_none_or(|c| c.dialog.is_none());
            if ui
                .add_enabled(
                    open && self.song.is_some(),
                    egui::Button::new("Compare with…"),
                )
                .on_hover_text("B beside the song (A); or drop a file with Shift held")
                .clicked()
            {
                if !crate::ui::open::dialogs_available() {
                    self.messages.warn(format!(
                        "{}: type B's path in the compare field and press Enter",
                        crate::ui::open::NO_DIALOG
                    ));
                    return;
                }
                self.compare
                    .get_or_insert_with(|| CompareState::new(PathBuf::new()))
                    .await_dialog(crate::ui::open::open_dialog(false));
            }
        });
        if let Some(state) = self.compare.as_mut() {
            match state.poll_dialog() {
                Poll::Ready(picked) => start = start.or(picked),
                Poll::Pending => ui.ctx().request_repaint_after(Duration::from_millis(100)),
            }
        }
        if let Some(path) = start {
            if self.song.is_some() {
                self.compare_with(path);
            } else {
                self.messages
                    .warn("open a song (A) first, then compare it with B".to_string());
            }
        }
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        if state.receiver.is_some() {
            ui.horizontal_wrapped(|ui| {
                ui.spinner();
                ui.label(format!("loading B: {}", state.path.display()));
            });
        }
        if let Some(error) = &state.error {
            ui.colored_label(Color32::from_rgb(240, 120, 100), error);
        }
        if state.clouds.is_none() {
            return;
        }
        ui.horizontal_wrapped(|ui| {
            for (layout, name) in [
                (CompareLayout::Off, "A only"),
                (CompareLayout::SideBySide, "Side by side"),
                (CompareLayout::Difference, "Difference"),
            ] {
                if ui
                    .add(egui::Button::selectable(state.layout == layout, name))
                    .clicked()
                {
                    state.layout = layout;
                    // The view changes: draw it now (a build is announced first).
                    ui.ctx().request_repaint();
                    self.motion.request_fit();
                }
            }
        });
        if state.layout == CompareLayout::Difference {
            ui.horizontal_wrapped(|ui| {
                ui.label("measure");
                for measure in DifferenceMeasure::ALL {
                    if ui
                        .add(egui::Button::selectable(
                            state.measure == measure,
                            measure.name(),
                        ))
                        .on_hover_text(measure.describe())
                        .clicked()
                    {
                        state.measure = measure;
                        ui.ctx().request_repaint();
                    }
                }
            });
        }
        let mut switch = None;
        ui.horizontal_wrapped(|ui| {
            ui.label("listen");
            for side in [Listening::A, Listening::B] {
                // "B −3.8 dB": the gain it plays at to match the other's loudness.
                let name = state.alignment.gain_label(side);
                let response = ui
                    .add_enabled(
                        state.can_listen(side),
                        egui::Button::selectable(state.listening == side, name),
                    )
                    .on_hover_text("key B switches, at the same moment of the music");
                if response.clicked() {
                    switch = Some(side);
                }
            }
            if state.decoding.is_some() {
                ui.spinner();
            }
        });
        self.alignment_controls(ui);
        if let Some(side) = switch {
            self.listen(side);
        }
    }
}
