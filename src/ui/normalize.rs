//! The window's "level as heard" choice: the combo box of Timeline mode and the timeline
//! installed shifted by the chosen preset. The presets and the shift itself are
//! `data::normalize`.

use eframe::egui::{self, RichText};

pub use crate::data::normalize::*;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::heard::Heard;

/// The choice a window starts with, applied once a timeline is shown.
pub(super) fn heard_starting(choice: Normalization) -> Heard {
    Heard {
        pending: (choice != Normalization::AsMastered).then_some(choice),
        ..Heard::default()
    }
}

/// The combo box's words for `choice`.
fn choice_name(choice: Normalization) -> &'static str {
    match choice {
        Normalization::AsMastered => "as mastered (none)",
        Normalization::Preset(preset) => preset.service.name,
    }
}

impl LoudscapeApp {
    /// The "level as heard" combo box of Timeline mode.
    pub(super) fn heard_choice(&mut self, ui: &mut egui::Ui) {
        let Some(loaded) = self.timeline.as_ref() else {
            return;
        };
        if loaded.id != self.heard.shown {
            // a newly loaded timeline is shown as mastered (unless a choice is on its way)
            self.heard.preset = Normalization::AsMastered;
            self.heard.original = None;
        }
        let mut choice = self.heard.preset;
        ui.add_space(6.0);
        egui::ComboBox::from_label("level as heard")
            .selected_text(choice_name(choice))
            .show_ui(ui, |ui| {
                for option in Normalization::ALL {
                    let item = ui.selectable_value(&mut choice, option, choice_name(option));
                    if let Some(preset) = option.preset() {
                        item.on_hover_text(format!(
                            "{:+.0} LUFS, {}",
                            preset.service.target_lufs,
                            turn_up_words(preset.service.turn_up)
                        ));
                    }
                }
            })
            .response
            .on_hover_text(
                "Shift each song's y by the gain this service or standard applies to it at \
                 playback (from the song's integrated loudness and true peak)",
            );
        if let Some(preset) = self.heard.preset.preset() {
            let service = &preset.service;
            ui.label(
                RichText::new(format!(
                    "y as heard: {:+.0} LUFS, {}",
                    service.target_lufs,
                    turn_up_words(service.turn_up)
                ))
                .small()
                .weak(),
            );
        }
        if choice != self.heard.preset {
            self.heard.pending = Some(choice);
        }
    }

    /// Installs the timeline shifted by the chosen preset (or as loaded), keeping the camera
    /// and the selected song.
    pub(super) fn apply_heard(&mut self, frame: &eframe::Frame) {
        let (Some(render_state), Some(loaded)) = (frame.wgpu_render_state(), &self.timeline) else {
            return;
        };
        let Some(choice) = self.heard.pending.take() else {
            return;
        };
        let original = self
            .heard
            .original
            .clone()
            .filter(|_| loaded.id == self.heard.shown)
            .unwrap_or_else(|| loaded.cloud.clone());
        let cloud = match choice.preset() {
            None => (*original).clone(),
            Some(preset) => match normalized(&original, &preset) {
                Ok(cloud) => cloud,
                Err(message) => {
                    self.messages.error(message);
                    return;
                }
            },
        };
        let selected = self.selected_song;
        self.motion.keep_camera_for_next_load();
        // the same file shifted, not a re-extraction: drop the shown copy first
        if let Some(old) = self.timeline.take() {
            crate::ui::bridge::ViewResources::write(render_state, |r| r.remove(old.id));
        }
        self.replace(render_state, cloud);
        self.selected_song = selected;
        self.heard = Heard {
            preset: choice,
            pending: None,
            original: Some(original),
            shown: self.timeline.as_ref().map_or(0, |l| l.id),
        };
    }
}
