//! The transport bar: plays the Song cloud's source audio, shows where the playhead is, seeks,
//! loops a range, and says plainly when there is no device or the file cannot be found (with a
//! path field to point at it instead). [`AudioPanel`] owns the window's playback: the song in
//! the player, a seek asked for before it is loaded (`--seek`), and the audio picked by hand
//! for a cloud whose recorded source is elsewhere (remembered between runs).

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32, RichText};

use crate::data::cloud::PointCloud;
use crate::playback::{self, PlaybackError, Player, Playhead, RodioBackend, Track};

/// What the bar knows about the song of the current Song cloud.
enum Source {
    None,
    Decoding(PathBuf, Receiver<Result<Track, PlaybackError>>),
    Ready,
    Failed(String),
}

pub struct AudioPanel {
    player: Player,
    source: Source,
    playhead: Option<Playhead>,
    /// Path typed by the user when the recorded source cannot be found or played.
    pub path_field: String,
    pub loop_enabled: bool,
    pub loop_range: (f64, f64),
    /// The playback time of the current frame, seconds.
    time_s: f64,
    no_device_said: bool,
    /// The song now in the player (its file and length: it streams), for an A/B swap to hand back.
    track: Option<Track>,
    /// The gain (f64 bits) last told to the player's loaded song (a new load plays at 0 dB).
    gain_set: Option<u64>,
    /// Where to put the playhead once a song is loaded (`--seek`).
    pending_seek: Option<f64>,
    /// The audio picked by hand for a cloud (absolute paths: cloud, audio), used instead of
    /// the recorded source when the cloud is loaded again.
    chosen: Vec<(PathBuf, PathBuf)>,
}

impl AudioPanel {
    pub fn new(open_device: bool) -> Self {
        let player = if open_device {
            // Without ALSA's own lines on stderr (eight on a machine without a sound card).
            crate::ui::alsa_quiet::quietly(|| Player::new(&RodioBackend))
        } else {
            Player::new(&NoBackend)
        };
        Self {
            player,
            source: Source::None,
            playhead: None,
            path_field: String::new(),
            loop_enabled: false,
            loop_range: (0.0, 0.0),
            time_s: 0.0,
            no_device_said: false,
            track: None,
            gain_set: None,
            pending_seek: None,
            chosen: Vec::new(),
        }
    }

    /// Puts the playhead at `seconds` once a song is loaded (at once when one is).
    pub fn seek_when_loaded(&mut self, seconds: f64) {
        if self.player.loaded.is_some() {
            self.seek(seconds);
        } else {
            self.pending_seek = Some(seconds);
        }
    }

    /// The audio picked by hand for each cloud (absolute paths: cloud, audio), as remembered.
    pub fn chosen(&self) -> &[(PathBuf, PathBuf)] {
        &self.chosen
    }

    /// The audio picked by hand in an earlier run.
    pub fn restore_chosen(&mut self, chosen: Vec<(PathBuf, PathBuf)>) {
        self.chosen = chosen;
    }

    /// The audio picked by hand for the cloud at `cloud`.
    fn chosen_for(&self, cloud: &Path) -> Option<PathBuf> {
        let cloud = std::path::absolute(cloud).ok()?;
        self.chosen
            .iter()
            .find(|(c, _)| c == &cloud)
            .map(|(_, audio)| audio.clone())
    }

    /// Keeps the audio playing as the one picked for `cloud`, forgetting the choice when it
    /// is the recorded source again.
    pub fn remember_choice(&mut self, cloud: &PointCloud) {
        let Some(track) = self.track_path() else {
            return;
        };
        let cloud_path = std::path::absolute(&cloud.path).unwrap_or_default();
        let track = std::path::absolute(&track).unwrap_or(track);
        let recorded = playback::resolve_source(cloud)
            .ok()
            .and_then(|p| std::path::absolute(p).ok());
        let entry = self.chosen.iter().position(|(c, _)| c == &cloud_path);
        match (entry, recorded.as_ref() == Some(&track)) {
            (Some(i), true) => {
                self.chosen.remove(i);
            }
            (Some(i), false) => self.chosen[i].1 = track,
            (None, false) => self.chosen.push((cloud_path, track)),
            (None, true) => {}
        }
    }

    /// Finds and decodes the song of a freshly loaded Song cloud (on a worker thread): the
    /// audio picked for it by hand when that file is there, else its recorded source.
    pub fn load_for(&mut self, cloud: &PointCloud) {
        let remembered = self.chosen_for(&cloud.path);
        self.player.unload();
        self.gain_set = None;
        self.track = None;
        self.playhead = None;
        self.time_s = 0.0;
        let found = match remembered.filter(|p| p.is_file()) {
            Some(path) => Ok(path),
            None => playback::resolve_source(cloud),
        };
        match found {
            Ok(path) => self.decode(path),
            Err(e) => {
                self.path_field = cloud
                    .meta
                    .source
                    .as_ref()
                    .and_then(|s| s.path.clone())
                    .unwrap_or_default();
                self.source = Source::Failed(e.to_string());
            }
        }
    }

    fn decode(&mut self, path: PathBuf) {
        let (sender, receiver) = channel();
        let thread_path = path.clone();
        std::thread::spawn(move || {
            let _ = sender.send(playback::decode(&thread_path));
        });
        self.path_field = path.display().to_string();
        self.source = Source::Decoding(path, receiver);
    }

    /// The path of the song being played, when it decoded.
    pub fn track_path(&self) -> Option<PathBuf> {
        self.player.loaded.as_ref().map(|l| l.track_path.clone())
    }

    /// Takes a finished decode; keeps repainting while one runs or while playing.
    pub fn poll(&mut self, ctx: &egui::Context) {
        if let Source::Decoding(_, receiver) = &self.source {
            match receiver.try_recv() {
                Ok(Ok(track)) => {
                    self.playhead = Some(Playhead::new(track.sample_rate));
                    self.loop_range = (0.0, track.duration_s());
                    self.track = Some(track.clone());
                    self.player.load(track);
                    self.gain_set = None;
                    self.source = Source::Ready;
                }
                Ok(Err(e)) => self.source = Source::Failed(e.to_string()),
                Err(std::sync::mpsc::TryRecvError::Empty) => {
                    ctx.request_repaint_after(Duration::from_millis(50));
                }
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    self.source = Source::Failed("the audio decoder stopped".into());
                }
            }
        }
        if self.player.loaded.is_some()
            && let Some(seconds) = self.pending_seek.take()
        {
            self.seek(seconds);
        }
        if let (Some(loaded), Some(playhead)) = (self.player.loaded.as_ref(), &mut self.playhead) {
            self.time_s = playhead.time_s(loaded.transport.as_ref(), Instant::now());
        }
        if self.player.is_playing() {
            ctx.request_repaint();
        }
    }

    /// The playhead time, while a song is loaded.
    pub fn time_s(&self) -> Option<f64> {
        self.player.loaded.as_ref().map(|_| self.time_s)
    }

    /// Where the loaded song's transport stands, in seconds (what the output plays next).
    pub fn position_s(&self) -> Option<f64> {
        self.player
            .loaded
            .as_ref()
            .map(|l| l.transport.position() as f64 / f64::from(l.sample_rate.max(1)))
    }

    pub fn loop_shown(&self) -> Option<(f64, f64)> {
        (self.loop_enabled && self.player.loaded.is_some()).then_some(self.loop_range)
    }

    pub fn toggle(&mut self) {
        self.player.toggle();
    }

    pub fn seek(&mut self, seconds: f64) {
        self.player.seek_s(seconds);
        if let Some(p) = self.playhead.as_mut() {
            *p = Playhead::new(self.player.loaded.as_ref().map_or(1, |l| l.sample_rate));
        }
    }

    /// A/B compare: plays `other` from the position (and in the state, playing or paused) the
    /// current song is at, and hands the current song back so it can be swapped in again. The
    /// loop range stays. Returns `None` when no song was loaded yet (then `other` just loads).
    pub fn swap_track(&mut self, other: Track) -> Option<Track> {
        self.swap_track_at(other, |t| t)
    }

    /// As [`Self::swap_track`], `other` starting at `target(t)`, `t` being the current song's
    /// position: the same moment of the music in an aligned release (A/B compare).
    pub fn swap_track_at(
        &mut self,
        other: Track,
        target: impl FnOnce(f64) -> f64,
    ) -> Option<Track> {
        let (time, playing) = (self.time_s, self.player.is_playing());
        let time = target(time);
        let previous = self.track.take();
        self.playhead = Some(Playhead::new(other.sample_rate));
        if previous.is_none() {
            self.loop_range = (0.0, other.duration_s());
        }
        self.path_field = other.path.display().to_string();
        self.track = Some(other.clone());
        self.player.load(other);
        self.gain_set = None;
        self.source = Source::Ready;
        if previous.is_some() {
            self.seek(time);
            self.time_s = time;
            self.player
                .set_loop_s(self.loop_shown().filter(|(a, b)| b > a));
            if playing {
                self.player.toggle();
            }
        }
        previous
    }

    /// Plays the loaded song `db` decibels louder or quieter (A/B loudness matching); told to
    /// the player only when it changes, and again after every load or swap.
    pub fn set_gain_db(&mut self, db: f64) {
        if self.gain_set != Some(db.to_bits()) && self.player.loaded.is_some() {
            self.player.set_gain_db(db as f32);
            self.gain_set = Some(db.to_bits());
        }
    }

    /// The bar under the 3D view.
    pub fn bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            let loaded = self.player.loaded.as_ref().map(|l| l.duration_s);
            let playing = self.player.is_playing();
            let can_play = loaded.is_some() && self.player.no_device().is_none();
            let label = if playing { "Pause" } else { "Play" };
            if ui
                .add_enabled(can_play, egui::Button::new(label))
                .on_hover_text("Space")
                .clicked()
            {
                self.toggle();
            }
            let duration = loaded.unwrap_or(0.0);
            ui.label(
                RichText::new(format!(
                    "{} / {}",
                    playback::format_clock(self.time_s),
                    playback::format_clock(duration)
                ))
                .monospace(),
            );
            if loaded.is_some() {
                let mut t = self.time_s;
                let width = (ui.available_width() - 330.0).max(80.0);
                ui.spacing_mut().slider_width = width;
                let response =
                    ui.add(egui::Slider::new(&mut t, 0.0..=duration.max(0.001)).show_value(false));
                if response.changed() {
                    self.seek(t);
                }
                let before = (self.loop_enabled, self.loop_range);
                ui.checkbox(&mut self.loop_enabled, "loop");
                if self.loop_enabled {
                    let (a, b) = &mut self.loop_range;
                    ui.add(
                        egui::DragValue::new(a)
                            .range(0.0..=duration)
                            .speed(0.1)
                            .suffix(" s"),
                    );
                    ui.label("–");
                    ui.add(
                        egui::DragValue::new(b)
                            .range(0.0..=duration)
                            .speed(0.1)
                            .suffix(" s"),
                    );
                    if ui.small_button("from here").clicked() {
                        *a = self.time_s;
                        if *b <= *a {
                            *b = duration;
                        }
                    }
                }
                if before != (self.loop_enabled, self.loop_range) {
                    self.player
                        .set_loop_s(self.loop_shown().filter(|(a, b)| b > a));
                }
            }
        });
        if let Some(reason) = self.player.no_device() {
            if !self.no_device_said {
                log::warn!("no audio device: {reason}");
                self.no_device_said = true;
            }
            ui.label(
                RichText::new(format!(
                    "No audio device ({reason}): playback is off; everything else works."
                ))
                .small()
                .color(Color32::from_rgb(230, 180, 90)),
            );
        }
        match &self.source {
            Source::Decoding(path, _) => {
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("decoding {}", path.display()));
                });
            }
            Source::Failed(message) => {
                let message = message.clone();
                ui.colored_label(Color32::from_rgb(240, 120, 100), message);
                ui.horizontal(|ui| {
                    ui.label("audio file:");
                    ui.add(egui::TextEdit::singleline(&mut self.path_field).desired_width(360.0));
                    if ui.button("Use this file").clicked() {
                        let path = PathBuf::from(self.path_field.trim());
                        self.decode(path);
                    }
                });
            }
            Source::None | Source::Ready => {}
        }
    }
}

/// The backend used when the app must not touch the sound card (screenshot runs in tests).
struct NoBackend;

impl playback::AudioBackend for NoBackend {
    fn open(&self) -> Result<Box<dyn playback::AudioOutput>, PlaybackError> {
        Err(PlaybackError::NoDevice("audio is off for this run".into()))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::{Duration, Instant};

    use super::*;

    const RATE: u32 = 8_000;

    /// A silent mono 16-bit WAV of `seconds` at 8 kHz.
    fn silent_wav(path: &Path, seconds: u32) {
        let samples = std::iter::repeat_n(0i16, (RATE * seconds) as usize);
        let bytes = crate::playback::mono_wav_bytes(RATE, samples);
        std::fs::write(path, bytes).expect("write wav");
    }

    /// Polls the panel until its song is loaded (the decode runs on a thread).
    fn until_loaded(panel: &mut AudioPanel) {
        let ctx = egui::Context::default();
        let deadline = Instant::now() + Duration::from_secs(20);
        while panel.time_s().is_none() {
            assert!(Instant::now() < deadline, "the song never loaded");
            panel.poll(&ctx);
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("loudscape-audio-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    /// `--seek` is asked for before the song is decoded: the playhead goes there on the poll
    /// that loads it; asked with a song loaded, at once.
    #[test]
    fn a_seek_asked_before_the_song_is_loaded_waits_for_it() {
        let dir = temp_dir("seek");
        let song = dir.join("song.wav");
        silent_wav(&song, 4);
        let mut panel = AudioPanel::new(false);
        panel.seek_when_loaded(1.5);
        assert_eq!(panel.position_s(), None);
        panel.decode(song);
        until_loaded(&mut panel);
        assert_eq!(panel.position_s(), Some(1.5));
        panel.seek_when_loaded(3.0);
        assert_eq!(panel.position_s(), Some(3.0), "loaded: at once");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Audio picked by hand is what the cloud loads next time, until the recorded source is
    /// picked again.
    #[test]
    fn the_audio_picked_for_a_cloud_is_remembered_until_it_is_the_recorded_one() {
        let dir = temp_dir("chosen");
        let (recorded, picked) = (dir.join("recorded.wav"), dir.join("picked.wav"));
        silent_wav(&recorded, 1);
        silent_wav(&picked, 1);
        let mut cloud = PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(100, 3),
            crate::data::cloud::DataMode::Song,
        );
        cloud.path = dir.join("song.ply");
        cloud.meta.source = Some(crate::data::cloud::Source {
            path: Some(recorded.display().to_string()),
            ..Default::default()
        });
        let mut panel = AudioPanel::new(false);
        panel.load_for(&cloud);
        until_loaded(&mut panel);
        panel.remember_choice(&cloud);
        assert!(
            panel.chosen().is_empty(),
            "the recorded source is no choice"
        );

        panel.decode(picked.clone());
        panel.player.unload();
        until_loaded(&mut panel);
        panel.remember_choice(&cloud);
        assert_eq!(panel.chosen().len(), 1);
        let mut again = AudioPanel::new(false);
        again.restore_chosen(panel.chosen().to_vec());
        again.load_for(&cloud);
        assert_eq!(again.path_field, picked.display().to_string());

        panel.decode(recorded.clone());
        panel.player.unload();
        until_loaded(&mut panel);
        panel.remember_choice(&cloud);
        assert!(
            panel.chosen().is_empty(),
            "forgotten when the recorded one is back"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
