//! The compare section of the side panel: the field and the "Compare with…" dialog (each adds
//! a version: B, then C...), loading and error lines, the layout (A only, side by side,
//! difference), the difference measure, and the listening switch with each version's gain and
//! the one heard named. What it decides from the state (the typed path, the dialog's
//! answer, which side can be heard) is `state/compare_window.rs`.

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
        let mut start = Vec::new();
        ui.horizontal_wrapped(|ui| {
            let field = &mut self.open.compare_path;
            let edit = ui.add(
                egui::TextEdit::singleline(field)
                    .id(egui::Id::unique(COMPARE_FIELD))
                    .hint_text("B: song or cloud")
                    .desired_width(130.0),
            );
            let entered = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            start.extend(typed_path(field, entered));
            let open = self.compare.as_ref().is_none_or(|c| c.dialog.is_none());
            if ui
                .add_enabled(
                    open && self.song.is_some(),
                    egui::Button::new("Compare with…"),
                )
                .on_hover_text(
                    "adds a version (B, C...) to compare with the song (A); or drop a file \
                     with Shift held",
                )
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
                    .get_or_insert_with(CompareState::empty)
                    .await_dialog(crate::ui::open::open_dialog(false));
            }
        });
        if let Some(state) = self.compare.as_mut() {
            match state.poll_dialog() {
                Poll::Ready(picked) => start.extend(picked),
                Poll::Pending => ui.ctx().request_repaint_after(Duration::from_millis(100)),
            }
        }
        if !start.is_empty() && self.song.is_none() {
            self.messages
                .warn("open a song (A) first, then compare it with B".to_string());
        } else if !start.is_empty() {
            for path in start {
                self.compare_with(path);
            }
            // The version added last is seen beside A (unless another is heard).
            if let Some(state) = self.compare.as_mut() {
                state.show(Listening(state.versions.len()));
            }
        }
        let Some(state) = self.compare.as_mut() else {
            return;
        };
        for (i, version) in state.versions.iter().enumerate() {
            if version.receiver.is_some() {
                ui.horizontal_wrapped(|ui| {
                    ui.spinner();
                    ui.label(format!(
                        "loading {}: {}",
                        Listening(i + 1).letter(),
                        version.path.display()
                    ));
                });
            }
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
                    state.set_layout(layout);
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
                            !state.matched && state.measure == measure,
                            measure.name(),
                        ))
                        .on_hover_text(measure.describe())
                        .clicked()
                    {
                        state.pick_measure(Some(measure));
                        ui.ctx().request_repaint();
                    }
                }
                // Level-weighted with the version's levels moved by its matching gain.
                let gain = state.alignment.match_words(state.beside);
                let hover = match &gain {
                    Some(words) => format!(
                        "level-weighted, {words}: what remains is dynamics and tonal balance"
                    ),
                    None => "needs the versions' matching gains (their alignment)".to_string(),
                };
                if ui
                    .add_enabled(
                        gain.is_some(),
                        egui::Button::selectable(state.matched, "matched"),
                    )
                    .on_hover_text(hover)
                    .on_disabled_hover_text("needs the versions' matching gains (their alignment)")
                    .clicked()
                {
                    state.pick_measure(None);
                    ui.ctx().request_repaint();
                }
            });
        }
        let mut switch = None;
        ui.horizontal_wrapped(|ui| {
            ui.label("listen");
            for side in (0..state.count()).map(Listening) {
                // "B −3.8 dB": the gain it plays at to match the other's loudness.
                let name = state.alignment.gain_label(side);
                let response = ui
                    .add_enabled(
                        state.can_listen(side),
                        egui::Button::selectable(state.listening == side, name),
                    )
                    .on_hover_text(
                        "key B steps through the versions, at the same moment of the music",
                    );
                if response.clicked() {
                    switch = Some(side);
                }
            }
            if state.versions.iter().any(|v| v.decoding.is_some()) {
                ui.spinner();
            }
        });
        // The version heard: its name and the gain it plays at.
        let heard = state.listening;
        let name = match state.version(heard) {
            Some(version) => version.name(),
            None => self
                .song
                .as_ref()
                .and_then(|s| s.cloud.path.file_name())
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        };
        ui.label(format!(
            "hearing {}: {name} at {:+.1} dB",
            heard.letter(),
            state.alignment.gain_db(heard)
        ));
        self.alignment_controls(ui);
        if let Some(side) = switch {
            self.listen(side);
        }
    }
}
