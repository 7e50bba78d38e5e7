//! The extraction settings that change the picture of a song opened from audio: the floor (how
//! far below the loudest bin the quietest kept point lies), the frequency scale and the FFT
//! size (the hop stays half of it). They are the extractor's own flags (`loudscape-extract song
//! --floor-db --freq-scale --n-fft --hop`) and part of the cloud cache's key. "Re-extract" opens
//! the same song again with the new settings on the loading thread: the old cloud stays on
//! screen, with the progress bar below, until the new one is ready (or from the cache at once).
//! The choices themselves (`ExtractChoices`, kept in the Open row) are
//! `state/extract_settings.rs`.

use std::path::{Path, PathBuf};

use eframe::egui::{self, RichText};

use crate::extract::Settings;
use crate::ui::state::LoudscapeApp;

/// The extractor's default floor (`loudscape_extract.points.DEFAULT_FLOOR_DB`).
pub(super) const DEFAULT_FLOOR_DB: f32 = 80.0;
/// FFT sizes offered (the hop is half).
const FFT_SIZES: [u32; 5] = [512, 1024, 2048, 4096, 8192];

/// Whether `path` names audio by its extension (the song slot's cloud is named by its audio
/// when it came from it). No file is read: this runs every frame.
pub(super) fn named_like_audio(path: &Path) -> bool {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .is_some_and(|e| crate::ui::open::AUDIO_EXTENSIONS.contains(&e.as_str()))
}

impl LoudscapeApp {
    /// The "Extraction" section, for a song on screen that came from audio.
    pub(super) fn extraction_controls(&mut self, ui: &mut egui::Ui) {
        let Some(audio) = self
            .song
            .as_ref()
            .map(|l| l.cloud.path.clone())
            .filter(|p| named_like_audio(p))
        else {
            return;
        };
        if self.active != crate::ui::state::Slot::Song {
            return;
        }
        let shown = match &self.open.extract.shown {
            Some((path, settings)) if path == &audio => settings.clone(),
            _ => Settings::default(),
        };
        ui.add_space(4.0);
        ui.label(RichText::new("Extraction").strong())
            .on_hover_text("loudscape-extract's settings for this song; the cache keeps each");
        let next = &mut self.open.extract.next;
        let mut floor = next.floor_db.unwrap_or(DEFAULT_FLOOR_DB);
        if ui
            .add(
                egui::Slider::new(&mut floor, 10.0..=120.0)
                    .step_by(5.0)
                    .text("floor (dB)"),
            )
            .on_hover_text("keep bins down to this many dB below the song's loudest")
            .changed()
        {
            next.floor_db = (floor != DEFAULT_FLOOR_DB).then_some(floor);
        }
        ui.horizontal(|ui| {
            ui.label("frequency");
            for scale in ["linear", "log"] {
                if ui
                    .selectable_label(next.freq_scale == scale, scale)
                    .clicked()
                {
                    next.freq_scale = scale.to_string();
                }
            }
        });
        ui.horizontal(|ui| {
            ui.label("FFT");
            egui::ComboBox::from_id_salt("n_fft")
                .selected_text(next.n_fft.to_string())
                .show_ui(ui, |ui| {
                    for size in FFT_SIZES {
                        if ui
                            .selectable_label(next.n_fft == size, size.to_string())
                            .clicked()
                        {
                            next.n_fft = size;
                            next.hop = size / 2;
                        }
                    }
                });
            ui.label(RichText::new(format!("hop {}", next.hop)).small().weak());
        });
        let busy = self.loading.iter().any(|l| l.path == audio);
        let changed = *next != shown;
        ui.horizontal(|ui| {
            let button = ui
                .add_enabled(changed && !busy, egui::Button::new("Re-extract"))
                .on_hover_text("extract the song again with these settings; the view stays");
            if button.clicked() {
                self.reextract(audio.clone());
            }
            if changed
                && !busy
                && ui
                    .small_button("undo")
                    .on_hover_text("back to the song's settings")
                    .clicked()
            {
                self.open.extract.next = shown.clone();
            }
        });
    }

    /// The song on screen, when it came from audio.
    fn shown_audio(&self) -> Option<PathBuf> {
        self.song
            .as_ref()
            .map(|l| l.cloud.path.clone())
            .filter(|p| named_like_audio(p))
    }

    /// Whether the song on screen is being extracted again.
    pub(super) fn reextracting(&self) -> bool {
        self.shown_audio()
            .is_some_and(|audio| self.loading.iter().any(|l| l.path == audio))
    }

    /// Ctrl+E: the song on screen again with the panel's settings (when they changed).
    pub(super) fn reextract_shown_song(&mut self) {
        let Some(audio) = self.shown_audio() else {
            return;
        };
        let shown = match &self.open.extract.shown {
            Some((path, settings)) if path == &audio => settings.clone(),
            _ => Settings::default(),
        };
        if !self.reextracting() && self.open.extract.next != shown {
            self.reextract(audio);
        }
    }

    /// A scripted setting of the Extraction panel (`--press floor=40`, tests), as its slider
    /// would set it; false when `name` is no such setting.
    pub(super) fn scripted_setting(&mut self, name: &str) -> bool {
        match name
            .strip_prefix("floor=")
            .and_then(|v| v.parse::<f32>().ok())
        {
            Some(floor) => {
                self.open.extract.next.floor_db = Some(floor);
                true
            }
            None => false,
        }
    }

    /// Opens `audio` again with the chosen settings (the old cloud stays until it is ready).
    pub(super) fn reextract(&mut self, audio: PathBuf) {
        eprintln!(
            "loudscape: {}: extracting again ({}); the cloud shown stays until the new one is ready",
            audio.display(),
            self.open.extract.next.arguments().join(" ")
        );
        // The new cloud keeps the camera: the same song, seen the same way.
        self.motion.keep_camera_for_next_load();
        self.start_loading(audio);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn audio_by_name_only() {
        assert!(named_like_audio(Path::new("a/b/song.FLAC")));
        assert!(named_like_audio(Path::new("song.ogg")));
        assert!(!named_like_audio(Path::new("song.ply")));
        assert!(!named_like_audio(Path::new("song")));
    }
}
