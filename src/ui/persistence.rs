//! What the window remembers between runs ([`Remembered`], kept by eframe's storage): the
//! files, view, camera, surface and volume choices, colours, and audio picked by hand for a
//! cloud.

use std::path::PathBuf;

use crate::render::scene::ViewKind;
use crate::ui::state::LoudscapeApp;
use crate::view::camera::Camera;

/// What the app remembers between runs.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Remembered {
    pub files: Vec<PathBuf>,
    pub view: Option<ViewKind>,
    pub camera: Option<Camera>,
    pub iso_value: Option<f32>,
    pub show_box: Option<bool>,
    /// Transfer function preset name (Classic, Ember, Glacial) and the volume's hp tint.
    #[serde(default)]
    pub transfer: Option<String>,
    #[serde(default)]
    pub hp_tint: Option<bool>,
    /// Surface method short name (mt, dc).
    #[serde(default)]
    pub surface_method: Option<String>,
    /// Audio picked by hand for a cloud whose recorded source moved: cloud path -> audio path.
    pub audio_for: Vec<(PathBuf, PathBuf)>,
    /// Colour maps and background (`render::colormap::Colours`).
    #[serde(default)]
    pub colours: Option<crate::render::colormap::Colours>,
}

impl LoudscapeApp {
    pub(super) fn remembered(&self) -> Remembered {
        let files = [self.song.as_ref(), self.timeline.as_ref()]
            .into_iter()
            .flatten()
            .map(|l| std::path::absolute(&l.cloud.path).unwrap_or_else(|_| l.cloud.path.clone()))
            .collect();
        Remembered {
            files,
            view: Some(self.settings.view),
            camera: Some(self.motion.camera()),
            iso_value: Some(self.settings.surface.iso_value),
            show_box: Some(self.settings.show_box),
            transfer: Some(self.settings.volume.preset.name().to_string()),
            hp_tint: Some(self.settings.volume.hp_tint),
            surface_method: Some(self.settings.surface.method.short_name().to_string()),
            audio_for: self.audio_for.clone(),
            colours: Some(self.settings.colours),
        }
    }

    /// Applies what was remembered to a new window; returns the files to open (the command
    /// line's, or the remembered ones whose camera then comes back as it was left).
    pub(super) fn apply_remembered(
        &mut self,
        mut files: Vec<PathBuf>,
        remembered: Option<Remembered>,
    ) -> Vec<PathBuf> {
        if let Some(r) = remembered {
            if let Some(view) = r.view {
                self.settings.view = view;
            }
            if let Some(iso) = r.iso_value {
                self.settings.surface.iso_value = iso.clamp(0.0, 1.0);
            }
            if let Some(show) = r.show_box {
                self.settings.show_box = show;
            }
            if let Some(preset) = r
                .transfer
                .as_deref()
                .and_then(crate::render::transfer::TransferPreset::parse)
            {
                self.settings.volume.preset = preset;
            }
            if let Some(tint) = r.hp_tint {
                self.settings.volume.hp_tint = tint;
            }
            if let Some(method) = r
                .surface_method
                .as_deref()
                .and_then(crate::render::surface::SurfaceMethod::parse)
            {
                self.settings.surface.method = method;
            }
            if let Some(colours) = r.colours {
                self.settings.colours = colours;
            }
            self.audio_for = r.audio_for;
            // The camera and the files go together: the view comes back as it was left.
            if files.is_empty() {
                files = r.files.into_iter().filter(|f| f.is_file()).collect();
                if let Some(camera) = r.camera
                    && !files.is_empty()
                {
                    self.motion.restore(camera, files.len());
                }
            }
        }
        files
    }

    /// Keeps the audio picked by hand for the song cloud, forgetting it when it is the
    /// recorded source again.
    pub(super) fn remember_audio_choice(&mut self) {
        if let Some(track) = self.audio.track_path()
            && let Some(song) = &self.song
        {
            let cloud = std::path::absolute(&song.cloud.path).unwrap_or_default();
            let track = std::path::absolute(&track).unwrap_or(track);
            let recorded = crate::playback::resolve_source(&song.cloud)
                .ok()
                .and_then(|p| std::path::absolute(p).ok());
            let entry = self.audio_for.iter().position(|(c, _)| c == &cloud);
            match (entry, recorded.as_ref() == Some(&track)) {
                (Some(i), true) => {
                    self.audio_for.remove(i);
                }
                (Some(i), false) => self.audio_for[i].1 = track,
                (None, false) => self.audio_for.push((cloud, track)),
                (None, true) => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Remembered;
    use crate::render::colormap::{Background, Colours, DensityColourMap, HpColourMap};

    #[test]
    fn colours_are_remembered_and_older_records_read_without_them() {
        let colours = Colours {
            hp: HpColourMap::PuOr,
            density: DensityColourMap::Magma,
            background: Background::Light,
        };
        let remembered = Remembered {
            colours: Some(colours),
            ..Default::default()
        };
        let text = serde_json::to_string(&remembered).expect("serialize");
        let back: Remembered = serde_json::from_str(&text).expect("deserialize");
        assert_eq!(back.colours, Some(colours));
        let old: Remembered =
            serde_json::from_str(r#"{"files": [], "show_box": true}"#).expect("old");
        assert_eq!(old.colours, None);
    }
}
