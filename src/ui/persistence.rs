//! What the window remembers between runs ([`Remembered`], kept by eframe's storage): the
//! files, the slot shown, view, camera, surface and volume choices, colours, "level as heard",
//! B of an A/B compare, and audio picked by hand for a cloud.
//!
//! eframe saves on a clean close and every [`AUTO_SAVE`]; a window destroyed from outside
//! (`xdotool windowclose`, a killed X client) gets no close, so a change asks for a frame once
//! the interval has passed ([`LoudscapeApp::ask_to_save`]) and at most that much is lost.

use std::path::PathBuf;
use std::time::Duration;

use crate::data::normalize::Normalization;
use crate::ui::state::{LoudscapeApp, Slot};

/// How often eframe saves what is remembered (when it changed; its default is 30 s).
pub(super) const AUTO_SAVE: Duration = Duration::from_secs(1);

pub use crate::ui::state::remembered::Remembered;

/// The name a slot is remembered by.
fn slot_name(slot: Slot) -> &'static str {
    match slot {
        Slot::Song => "song",
        Slot::Timeline => "timeline",
    }
}

fn slot_named(name: &str) -> Option<Slot> {
    [Slot::Song, Slot::Timeline]
        .into_iter()
        .find(|&slot| slot_name(slot) == name)
}

impl LoudscapeApp {
    pub(super) fn remembered(&self) -> Remembered {
        let files = [self.song.as_ref(), self.timeline.as_ref()]
            .into_iter()
            .flatten()
            .map(|l| std::path::absolute(&l.cloud.path).unwrap_or_else(|_| l.cloud.path.clone()))
            .collect();
        // The versions compared (loaded or loading), absolute: B first.
        let compared: Vec<PathBuf> = self.compare.as_ref().map_or_else(Vec::new, |c| {
            c.versions
                .iter()
                .filter(|v| v.loaded.is_some() || v.receiver.is_some())
                .map(|v| std::path::absolute(&v.path).unwrap_or_else(|_| v.path.clone()))
                .collect()
        });
        Remembered {
            files,
            view: Some(self.settings.view),
            camera: Some(self.motion.camera()),
            view_heights: self.motion.heights(),
            iso_value: Some(self.settings.surface.iso_value),
            show_box: Some(self.settings.show_box),
            transfer: Some(self.settings.volume.preset.name().to_string()),
            hp_tint: Some(self.settings.volume.hp_tint),
            surface_method: Some(self.settings.surface.method.short_name().to_string()),
            audio_for: self.audio.chosen().to_vec(),
            colours: Some(self.settings.colours),
            active: self
                .active()
                .is_some()
                .then(|| slot_name(self.active).to_string()),
            compare: compared.first().cloned(),
            compare_more: compared.iter().skip(1).cloned().collect(),
            heard: self
                .heard
                .pending
                .unwrap_or(self.heard.preset)
                .preset()
                .map(|preset| preset.key.to_string()),
        }
    }

    /// Asks for a frame once [`AUTO_SAVE`] has passed when what is remembered changed since
    /// eframe last saved it (eframe saves only in a frame), so a window destroyed from outside
    /// loses at most that much.
    pub(super) fn ask_to_save(&mut self, ctx: &eframe::egui::Context, frame: &eframe::Frame) {
        // Without storage eframe never saves: nothing to come back for.
        if self.persist
            && frame.storage().is_some()
            && self.saved.as_ref() != Some(&self.remembered())
        {
            ctx.request_repaint_after(AUTO_SAVE + Duration::from_millis(100));
        }
    }

    /// The load of `path` failed. Of files opened together, the one it hid may now be shown
    /// (fitted: a remembered camera was the failed one's slot's).
    pub(super) fn first_shown_failed(&mut self, path: &std::path::Path) {
        let Some(slot) = self.first_shown.failed(path) else {
            return;
        };
        if self.slot(slot).is_some() && (self.active != slot || self.active().is_none()) {
            self.motion.abandon_restore();
            self.motion.cloud_installed(self.active, slot);
            self.active = slot;
        }
    }

    /// Applies what was remembered to a new window; returns the files to open (the command
    /// line's, or the remembered ones whose camera then comes back as it was left).
    pub(super) fn apply_remembered(
        &mut self,
        mut files: Vec<PathBuf>,
        remembered: Option<Remembered>,
    ) -> Vec<PathBuf> {
        let mut prefer = None;
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
            self.audio.restore_chosen(r.audio_for);
            if self.heard.pending.is_none()
                && let Some(choice) = r.heard.as_deref().and_then(Normalization::parse)
            {
                self.heard = crate::ui::normalize::heard_starting(choice);
            }
            // The camera and the files go together: the view comes back as it was left, the
            // slot it showed first, and B of a compare with A.
            if files.is_empty() {
                files = r.files.into_iter().filter(|f| f.is_file()).collect();
                let active = r.active.as_deref().and_then(slot_named);
                match (r.camera, active) {
                    (Some(camera), Some(slot)) if files.len() > 1 => {
                        // Its cloud takes the camera; the other slot's waits unseen.
                        self.active = slot;
                        self.motion.restore(camera, 1);
                        prefer = Some(slot);
                    }
                    (Some(camera), _) if !files.is_empty() => {
                        self.motion.restore(camera, files.len());
                    }
                    _ => {}
                }
                if !files.is_empty()
                    && r.camera.is_some()
                    && let Some(heights) = r.view_heights
                {
                    self.motion.restore_heights(heights);
                }
                if !files.is_empty() {
                    for version in r.compare.into_iter().chain(r.compare_more) {
                        if version.is_file() {
                            self.compare_with(version);
                        }
                    }
                    // The compare comes back where it was left, not fitted again.
                    if r.camera.is_some()
                        && let Some(state) = self.compare.as_mut()
                    {
                        state.camera_restored();
                    }
                }
            }
        }
        // Several files: the slot shown first is decided by them, not by the last load in.
        self.first_shown = crate::ui::state::first_shown::FirstShown::new(&files, prefer);
        files
    }

    /// Keeps the audio picked by hand for the song cloud (`AudioPanel::remember_choice`).
    pub(super) fn remember_audio_choice(&mut self) {
        if let Some(song) = &self.song {
            self.audio.remember_choice(&song.cloud);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Normalization, Remembered};
    use crate::ui::app::WindowOptions;
    use crate::ui::state::{LoudscapeApp, Slot};

    /// No audio device, no recent list: a scripted run's options (`run` passes it nothing
    /// remembered; here it is given what a reopened window reads).
    fn options(files: Vec<std::path::PathBuf>) -> WindowOptions {
        WindowOptions {
            files,
            screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
            ..Default::default()
        }
    }

    /// A window reopened with `remembered` (no files on the command line).
    fn reopened(remembered: Remembered) -> LoudscapeApp {
        LoudscapeApp::new(options(Vec::new()), Some(remembered))
    }

    #[test]
    fn the_compare_level_as_heard_and_the_slot_shown_come_back() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let song = repo.join("data/demo_song.ply");
        let timeline = repo.join("data/demo_timeline.ply");
        let b = repo.join("data/fixture_song.ply");
        let key = crate::ui::normalize::PRESETS[1].key.to_string();
        let mut camera = crate::view::camera::Camera::default();
        camera.azimuth += 0.5;
        let mut app = reopened(Remembered {
            files: vec![song.clone(), timeline.clone()],
            camera: Some(camera),
            active: Some("timeline".into()),
            compare: Some(b.clone()),
            compare_more: vec![repo.join("data/no-such-c.ply"), song.clone()],
            heard: Some(key.clone()),
            ..Default::default()
        });
        let compared = |app: &LoudscapeApp| -> Vec<std::path::PathBuf> {
            app.compare.as_ref().map_or_else(Vec::new, |c| {
                c.versions.iter().map(|v| v.path.clone()).collect()
            })
        };
        assert_eq!(
            compared(&app),
            [b.clone(), song.clone()],
            "B and the further versions that are there"
        );
        assert_eq!(
            app.heard.pending,
            Some(Normalization::Preset(crate::ui::normalize::PRESETS[1])),
            "level as heard"
        );
        assert_eq!(app.active, Slot::Timeline, "the slot it closed on");
        assert_eq!(app.motion.camera(), camera);
        let mut state = app.compare.take().expect("a compare");
        assert!(
            !state.fit_scene(true, false, 1),
            "the compare's scene of A's points so far keeps the camera"
        );
        assert!(
            !state.fit_scene(true, true, 2),
            "the scene of the whole of A keeps the camera too"
        );
        assert!(
            !state.fit_scene(true, true, 2),
            "and so does that scene built again (the alignment came after it)"
        );
        assert!(
            state.fit_scene(true, true, 3),
            "another song in A is fitted"
        );
        assert!(
            !state.fit_scene(false, true, 3),
            "another version beside A is not"
        );
        app.compare = Some(state);
        let again = app.remembered();
        assert_eq!(
            again.compare,
            Some(b.clone()),
            "remembered again while B loads"
        );
        assert_eq!(again.compare_more, std::slice::from_ref(&song));
        assert_eq!(again.heard, Some(key));
        assert_eq!(again.active, None, "nothing shown yet");

        // A B that is gone is not asked for; a command line's files start afresh.
        let app = reopened(Remembered {
            files: vec![song.clone()],
            compare: Some(repo.join("data/no-such-b.ply")),
            ..Default::default()
        });
        assert!(app.compare.is_none());
        let app = LoudscapeApp::new(
            options(vec![song]),
            Some(Remembered {
                compare: Some(b),
                ..Default::default()
            }),
        );
        assert!(app.compare.is_none(), "B goes with the remembered A only");
        let mut app = LoudscapeApp::new(options(Vec::new()), None);
        app.compare_with(repo.join("data/fixture_song.ply"));
        let state = app.compare.as_mut().expect("a compare");
        assert!(state.fit_scene(true, true, 1), "a new compare is fitted");
    }

    /// The cloud of `path` came in `slot` (what `poll_loading` does once it is on the GPU).
    fn came(app: &mut LoudscapeApp, path: &std::path::Path, slot: Slot) {
        let how = app.arrival(path, slot);
        app.show_installed(slot, how);
    }

    #[test]
    fn the_slot_shown_first_does_not_depend_on_which_load_ends_last() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let song = repo.join("data/demo_song.ply");
        let timeline = repo.join("data/demo_timeline.ply");
        let mut camera = crate::view::camera::Camera::default();
        camera.azimuth += 0.5;
        let orders = [
            [(&song, Slot::Song), (&timeline, Slot::Timeline)],
            [(&timeline, Slot::Timeline), (&song, Slot::Song)],
        ];
        for order in &orders {
            // Reopened on the timeline: it comes back, with its camera.
            let mut app = reopened(Remembered {
                files: vec![song.clone(), timeline.clone()],
                camera: Some(camera),
                active: Some("timeline".into()),
                ..Default::default()
            });
            for (path, slot) in order {
                came(&mut app, path, *slot);
            }
            assert_eq!(app.active, Slot::Timeline, "reopened, loads in {order:?}");
            assert_eq!(
                app.motion.camera(),
                camera,
                "its camera, loads in {order:?}"
            );
            // `loudscape song.ply timeline.ply`: the first named.
            let mut app = LoudscapeApp::new(options(vec![song.clone(), timeline.clone()]), None);
            for (path, slot) in order {
                came(&mut app, path, *slot);
            }
            assert_eq!(
                app.active,
                Slot::Song,
                "song named first, loads in {order:?}"
            );
            let mut app = LoudscapeApp::new(options(vec![timeline.clone(), song.clone()]), None);
            for (path, slot) in order {
                came(&mut app, path, *slot);
            }
            assert_eq!(
                app.active,
                Slot::Timeline,
                "timeline first, loads in {order:?}"
            );
            // A cloud opened later by hand is shown.
            came(&mut app, &repo.join("data/fixture_song.ply"), Slot::Song);
            assert_eq!(app.active, Slot::Song, "opened by hand");
        }
        // Reopened on the timeline, whose load fails before the song's ends: the song is
        // shown fitted, not with the timeline's camera.
        let mut app = reopened(Remembered {
            files: vec![song.clone(), timeline.clone()],
            camera: Some(camera),
            active: Some("timeline".into()),
            ..Default::default()
        });
        app.first_shown_failed(&timeline);
        came(&mut app, &song, Slot::Song);
        assert_eq!(app.active, Slot::Song);
        assert!(app.motion.fit_pending(), "fitted");
    }

    #[test]
    fn a_reopened_camera_keeps_its_framing_when_the_strip_comes_after_the_first_frames() {
        let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut camera = crate::view::camera::Camera::default();
        camera.azimuth += 0.5;
        // Closed with the loudness strip under a 590-point view in an 800-point window.
        let mut app = reopened(Remembered {
            files: vec![repo.join("data/demo_song.ply")],
            camera: Some(camera),
            view_heights: Some((590.0, 800.0)),
            ..Default::default()
        });
        // Reopened: the first frames have no strip yet (700 points), then it comes.
        for view in [700.0, 700.0, 590.0] {
            app.motion
                .size_view_within(1200.0 / view, None, Some((view, 800.0)));
        }
        let back = app.motion.camera();
        assert!(
            (back.distance - camera.distance).abs() < 1e-4 * camera.distance,
            "closer or farther than at close: {} against {}",
            back.distance,
            camera.distance
        );
        assert_eq!(app.remembered().view_heights, Some((590.0, 800.0)));
    }

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
