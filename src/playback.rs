//! Playback of the song a cloud was extracted from, and the clock the playhead follows.
//!
//! The song is never decoded whole: [`decode`] probes the file and reads its format and length,
//! and a [`TrackSource`] decodes it while it plays, a couple of seconds ahead on its own thread
//! (see [`stream`]), so a song's memory is that buffer whatever its length. A [`Player`] hands
//! the source to an [`AudioBackend`] (rodio on the default output device in the app, mocks in
//! tests); the source counts the frames it gives the device in a shared [`Transport`]. That
//! count is the clock: the playhead reads it through [`AudioClock`], so picture and sound cannot
//! drift apart however long the song, whatever the wall clock does. Seeking and pausing write the
//! transport; the source reads it for every frame, and the decoder thread, asleep while the buffer
//! is full or the song decoded to its end, is woken by what changes it. Between two device
//! callbacks the count stands still, so [`Playhead`] interpolates over at most one callback period
//! with the wall clock.
//!
//! No device (CI machines, a headless server) is not an error of the app: [`Player::new`] keeps
//! the reason in [`PlayerState::NoDevice`] and every other feature works.

pub mod source;
pub mod stream;

/// The bytes of a mono 16-bit PCM WAV file of `samples` at `rate` (the unit tests' audio).
#[cfg(test)]
pub(crate) fn mono_wav_bytes(rate: u32, samples: impl IntoIterator<Item = i16>) -> Vec<u8> {
    let data: Vec<u8> = samples.into_iter().flat_map(i16::to_le_bytes).collect();
    let mut b = Vec::with_capacity(44 + data.len());
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(36 + data.len() as u32).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&1u16.to_le_bytes()); // PCM
    b.extend_from_slice(&1u16.to_le_bytes()); // mono
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(rate * 2).to_le_bytes());
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&16u16.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&(data.len() as u32).to_le_bytes());
    b.extend_from_slice(&data);
    b
}

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::{Thread, ThreadId};
use std::time::{Duration, Instant};

use thiserror::Error;

use crate::data::cloud::PointCloud;
pub use source::{SourceError, checked_source};
use stream::{OpenError, Reader, Ring, Shared};

/// Why the song cannot be played.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PlaybackError {
    #[error("no audio device: {0}")]
    NoDevice(String),
    #[error("{path}: the audio file cannot be found (looked in: {tried})")]
    NotFound { path: String, tried: String },
    #[error("{path}: cannot open the audio file: {reason}")]
    Open { path: PathBuf, reason: String },
    #[error(
        "{path}: playback cannot decode {format} files (it plays wav, flac, ogg vorbis and mp3); \
         convert the song to one of those to hear it"
    )]
    Unsupported { path: PathBuf, format: String },
    #[error("{path}: cannot decode the audio: {reason}")]
    Decode { path: PathBuf, reason: String },
    #[error("{path}: the audio file holds no samples")]
    Empty { path: PathBuf },
}

/// A playable song: its file, format and length. The samples stay in the file; a
/// [`TrackSource`] decodes them as they play. Cheap to clone.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub path: PathBuf,
    pub channels: u16,
    pub sample_rate: u32,
    frames: u64,
}

impl Track {
    /// Frames in the song (samples per channel).
    pub fn frames(&self) -> u64 {
        self.frames
    }

    pub fn duration_s(&self) -> f64 {
        self.frames as f64 / f64::from(self.sample_rate.max(1))
    }
}

/// Formats symphonia (as configured in Cargo.toml) decodes, by file extension.
const PLAYABLE: [&str; 6] = ["wav", "wave", "flac", "ogg", "mp3", "oga"];

/// Opens an audio file for playback: probes its format, decodes its first packet (a file whose
/// audio does not decode fails here, with the message it always gave) and takes its length from
/// the container (FLAC, WAV and Ogg state it; when a file does not, its packets are counted
/// without decoding them, one read of the file). Nothing is kept in memory but that.
pub fn decode(path: &Path) -> Result<Track, PlaybackError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let unsupported = || PlaybackError::Unsupported {
        path: path.to_path_buf(),
        format: if extension.is_empty() {
            "this".into()
        } else {
            format!(".{extension}")
        },
    };
    if ["opus", "m4a", "aac", "mp4", "wma", "aiff", "aif"].contains(&extension.as_str()) {
        return Err(unsupported());
    }
    let open = |path: &Path| {
        Reader::open(path).map_err(|e| match e {
            OpenError::Open(reason) => PlaybackError::Open {
                path: path.to_path_buf(),
                reason,
            },
            OpenError::Unsupported => unsupported(),
            OpenError::Decode(reason) => PlaybackError::Decode {
                path: path.to_path_buf(),
                reason,
            },
        })
    };
    let mut reader = open(path)?;
    let empty = || {
        if PLAYABLE.contains(&extension.as_str()) {
            PlaybackError::Empty {
                path: path.to_path_buf(),
            }
        } else {
            unsupported()
        }
    };
    if !reader.fill() {
        return Err(empty());
    }
    let channels = u16::try_from(reader.channels).unwrap_or(u16::MAX).max(1);
    let sample_rate = reader.sample_rate.unwrap_or(0);
    if sample_rate == 0 {
        return Err(PlaybackError::Decode {
            path: path.to_path_buf(),
            reason: "the file states no sample rate".into(),
        });
    }
    let frames = match reader.stated_frames {
        Some(frames) => frames,
        None => open(path)?.count_frames(),
    };
    if frames == 0 {
        return Err(empty());
    }
    Ok(Track {
        path: path.to_path_buf(),
        channels,
        sample_rate,
        frames,
    })
}

/// Where the song of a cloud is: `source.path` as written (its exact bytes from
/// `source.path_bytes_b64` when recorded; relative to the current directory),
/// then relative to the .ply's folder, then its file name next to the .ply.
pub fn resolve_source(cloud: &PointCloud) -> Result<PathBuf, PlaybackError> {
    // The exact bytes when the file records them (`path_bytes_b64`: a name that is not UTF-8).
    let Some(recorded_path) = cloud.meta.source.as_ref().and_then(|s| s.open_path()) else {
        return Err(PlaybackError::NotFound {
            path: cloud.path.display().to_string(),
            tried: "the file names no source audio (source.path)".into(),
        });
    };
    let recorded = recorded_path.display().to_string();
    let folder = cloud.path.parent().unwrap_or(Path::new(""));
    let mut candidates = vec![recorded_path.clone()];
    if recorded_path.is_relative() {
        candidates.push(folder.join(&recorded_path));
    }
    if let Some(name) = recorded_path.file_name() {
        candidates.push(folder.join(name));
    }
    candidates.dedup();
    for candidate in &candidates {
        if candidate.is_file() {
            return Ok(candidate.clone());
        }
    }
    Err(PlaybackError::NotFound {
        path: recorded,
        tried: candidates
            .iter()
            .map(|c| c.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// A song cloud's length in seconds, as `loudscape video` and the window's export take it: its
/// source's duration as recorded, else the end of the time axis.
pub fn song_duration_s(cloud: &PointCloud) -> f64 {
    cloud
        .meta
        .source
        .as_ref()
        .and_then(|s| s.duration_s)
        .filter(|d| d.is_finite() && *d > 0.0)
        .unwrap_or_else(|| cloud.meta.axes.x.value_at(1.0))
}

/// The playback position and state shared between the UI and the audio thread.
#[derive(Debug)]
pub struct Transport {
    /// Frames handed to the device so far (the position in the track).
    position: AtomicU64,
    playing: AtomicBool,
    /// Loop range in frames, `loop_end == 0` when not looping.
    loop_start: AtomicU64,
    loop_end: AtomicU64,
    /// Set when the song is replaced: its source ends and leaves the mixer.
    retired: AtomicBool,
    /// Counts the jumps of the position (seeks) and the resyncs the source asked for: the
    /// decoder restarts from the position when it changes, and frames decoded before are stale.
    serial: AtomicU64,
    frames: u64,
    /// The linear gain applied to every sample (`f32` bits; 1.0 as the file is): A/B compare's
    /// loudness matching.
    gain: AtomicU32,
    /// The decoder threads filling sources of this transport (one in the app): every change of
    /// what they wait on wakes them. Locked only on the UI's side (seek, play, loop, replace)
    /// and when a decoder starts or ends, never on the audio callback.
    decoders: Mutex<Vec<Thread>>,
}

impl Transport {
    pub fn new(frames: u64) -> Self {
        Self {
            position: AtomicU64::new(0),
            playing: AtomicBool::new(false),
            loop_start: AtomicU64::new(0),
            loop_end: AtomicU64::new(0),
            retired: AtomicBool::new(false),
            serial: AtomicU64::new(0),
            frames,
            gain: AtomicU32::new(1.0f32.to_bits()),
            decoders: Mutex::new(Vec::new()),
        }
    }

    /// Plays every sample `db` decibels louder (negative: quieter) from the next frame on.
    pub fn set_gain_db(&self, db: f32) {
        let linear = if db.is_finite() {
            10f32.powf(db / 20.0)
        } else {
            1.0
        };
        self.gain.store(linear.to_bits(), Ordering::Relaxed);
    }

    /// The linear gain [`Transport::set_gain_db`] set.
    pub fn gain(&self) -> f32 {
        f32::from_bits(self.gain.load(Ordering::Relaxed))
    }

    /// Registers a decoder thread to wake on changes (by the thread itself, as it starts).
    pub(crate) fn add_decoder(&self, thread: Thread) {
        self.decoders
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .push(thread);
    }

    /// Forgets a decoder thread that ended.
    pub(crate) fn remove_decoder(&self, id: ThreadId) {
        self.decoders
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .retain(|t| t.id() != id);
    }

    /// Wakes the decoders: they re-check the serial, the loop and whether the song was replaced.
    fn wake_decoders(&self) {
        for thread in self
            .decoders
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .iter()
        {
            thread.unpark();
        }
    }

    pub fn position(&self) -> u64 {
        self.position.load(Ordering::Acquire)
    }

    /// Frames in the track.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    pub fn is_playing(&self) -> bool {
        self.playing.load(Ordering::Acquire)
    }

    /// How many times the position jumped (or the source asked the decoder to resync); frames
    /// play in order between two changes.
    pub fn serial(&self) -> u64 {
        self.serial.load(Ordering::Acquire)
    }

    fn is_retired(&self) -> bool {
        self.retired.load(Ordering::Acquire)
    }

    /// Tells the decoder to start again from the position. Does not wake it: the caller does
    /// (the UI's side through [`Self::wake_decoders`], the callback through its source's own
    /// handle, without a lock).
    fn resync(&self) {
        self.serial.fetch_add(1, Ordering::AcqRel);
    }

    /// Marks the song replaced: its source ends and its decoder thread with it.
    fn retire(&self) {
        self.retired.store(true, Ordering::Release);
        self.wake_decoders();
    }

    pub fn set_playing(&self, playing: bool) {
        if playing && self.position() >= self.frames {
            self.position.store(self.loop_start(), Ordering::Release);
            self.resync();
            self.wake_decoders();
        }
        self.playing.store(playing, Ordering::Release);
    }

    pub fn seek(&self, frame: u64) {
        self.position
            .store(frame.min(self.frames), Ordering::Release);
        self.resync();
        self.wake_decoders();
    }

    fn loop_start(&self) -> u64 {
        if self.loop_end.load(Ordering::Acquire) > 0 {
            self.loop_start.load(Ordering::Acquire)
        } else {
            0
        }
    }

    /// Loops `[start, end)` frames; None plays to the end and stops. Frames already decoded in
    /// the old order are replaced only where the order differs (the source resyncs there).
    pub fn set_loop(&self, range: Option<(u64, u64)>) {
        match range {
            Some((start, end)) if end > start => {
                self.loop_start
                    .store(start.min(self.frames), Ordering::Release);
                self.loop_end.store(end.min(self.frames), Ordering::Release);
            }
            _ => self.loop_end.store(0, Ordering::Release),
        }
        // The loop decides the order a decoder fills in ([`Self::after`]); a parked one only
        // re-checks (its buffered frames are replaced by a resync where the order differs).
        self.wake_decoders();
    }

    /// The frame that plays after `at`: the next one, or the loop's start at the loop's end
    /// (the order the decoder fills the buffer in).
    fn after(&self, at: u64) -> u64 {
        let loop_end = self.loop_end.load(Ordering::Acquire);
        let next = at + 1;
        if loop_end > 0 && next >= loop_end {
            self.loop_start.load(Ordering::Acquire)
        } else {
            next
        }
    }

    /// Advances by one frame from `at` (unless a seek moved the position meanwhile), wrapping
    /// at the loop end and stopping at the track's end. Returns the next frame to play.
    fn advance(&self, at: u64) -> Option<u64> {
        let next = self.after(at);
        let _ = self
            .position
            .compare_exchange(at, next, Ordering::AcqRel, Ordering::Acquire);
        let now = self.position();
        if now >= self.frames {
            self.playing.store(false, Ordering::Release);
            self.position.store(self.frames, Ordering::Release);
            return None;
        }
        Some(now)
    }
}

/// How many frames the output device has taken: the clock the playhead follows.
pub trait AudioClock {
    fn frames_played(&self) -> u64;
    fn is_running(&self) -> bool;
}

impl AudioClock for Transport {
    fn frames_played(&self) -> u64 {
        self.position()
    }
    fn is_running(&self) -> bool {
        self.is_playing()
    }
}

/// The track as a rodio source: plays from the transport's position while it is playing, and
/// silence while paused (the stream stays open so resuming is instant). Its decoder thread
/// fills a ring of [`stream::BUFFER_SECONDS`] of frames ahead; the source (on the audio
/// callback) only takes frames from it. Right after a seek, until the decoder has the new
/// position's frames, it plays silence and the clock stands (a few milliseconds).
pub struct TrackSource {
    channels: u16,
    sample_rate: u32,
    transport: Arc<Transport>,
    shared: Arc<Shared>,
    /// The frame being handed out, one sample per channel.
    current: Vec<f32>,
    frame: u64,
    channel: u16,
    /// The transport's gain, read once a frame.
    gain: f32,
}

impl TrackSource {
    /// The source of `track`, with its decoder thread started.
    pub fn new(track: Track, transport: Arc<Transport>) -> Self {
        let channels = track.channels.max(1);
        let shared = Arc::new(Shared::new(Ring::new(
            stream::buffer_frames(track.sample_rate),
            usize::from(channels),
        )));
        stream::spawn(
            track.path.clone(),
            usize::from(channels),
            transport.clone(),
            shared.clone(),
        );
        Self {
            channels,
            sample_rate: track.sample_rate,
            transport,
            shared,
            current: vec![0.0; usize::from(channels)],
            frame: 0,
            channel: 0,
            gain: 1.0,
        }
    }

    /// The ring of decoded frames between the decoder thread and the device: its capacity bounds
    /// the source's audio memory.
    pub fn ring(&self) -> &Ring {
        &self.shared.ring
    }

    /// Whether the next frame the transport wants is decoded (then `next` plays it rather than
    /// silence). Drops the frames a seek made stale; asks the decoder to resync when the buffered
    /// frames are not in the order the transport plays (a loop range set since they were
    /// decoded).
    pub fn is_buffered(&mut self) -> bool {
        let ring = &self.shared.ring;
        // Bounded: at most the ring's frames are dropped per call.
        for _ in 0..=ring.capacity() {
            // The serial first: a seek's position is visible once its serial is.
            let serial = stream::serial_bits(self.transport.serial());
            let position = self.transport.position();
            let Some(tag) = ring.front() else {
                return false;
            };
            if stream::tag_serial(tag) != serial {
                ring.skip();
                self.shared.took();
            } else if stream::tag_frame(tag) == position {
                return true;
            } else {
                self.transport.resync();
                self.shared.wake();
            }
        }
        false
    }
}

impl Drop for TrackSource {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Release);
        self.shared.wake();
    }
}

impl Iterator for TrackSource {
    type Item = f32;

    fn next(&mut self) -> Option<f32> {
        let channels = self.channels;
        if self.channel == 0 {
            if self.transport.is_retired() {
                return None;
            }
            if !self.transport.is_playing() {
                // Paused: keep the buffer at the position (a seek while paused refills it).
                self.is_buffered();
                return Some(0.0);
            }
            if self.transport.position() >= self.transport.frames() {
                self.transport.set_playing(false);
                return Some(0.0);
            }
            if !self.is_buffered() {
                return Some(0.0);
            }
            self.frame = self.transport.position();
            self.shared.ring.pop(&mut self.current);
            self.shared.took();
            self.gain = self.transport.gain();
        }
        let sample = self.current[usize::from(self.channel)] * self.gain;
        self.channel += 1;
        if self.channel == channels {
            self.channel = 0;
            if let Some(next) = self.transport.advance(self.frame) {
                self.frame = next;
            }
        }
        Some(sample)
    }
}

impl rodio::Source for TrackSource {
    fn current_span_len(&self) -> Option<usize> {
        // Unknown length: the source lives until its song is replaced.
        None
    }
    fn channels(&self) -> rodio::ChannelCount {
        std::num::NonZero::new(self.channels.max(1)).unwrap_or(std::num::NonZero::<u16>::MIN)
    }
    fn sample_rate(&self) -> rodio::SampleRate {
        std::num::NonZero::new(self.sample_rate.max(1)).unwrap_or(std::num::NonZero::<u32>::MIN)
    }
    fn total_duration(&self) -> Option<Duration> {
        None
    }
}

/// An open audio output that plays sources.
pub trait AudioOutput {
    fn play(&mut self, source: TrackSource);
}

/// Opens audio outputs: the default device in the app, mocks in tests.
pub trait AudioBackend {
    fn open(&self) -> Result<Box<dyn AudioOutput>, PlaybackError>;
}

/// The default output device through rodio (cpal).
pub struct RodioBackend;

struct RodioOutput {
    sink: rodio::MixerDeviceSink,
}

impl AudioOutput for RodioOutput {
    fn play(&mut self, source: TrackSource) {
        self.sink.mixer().add(source);
    }
}

impl AudioBackend for RodioBackend {
    fn open(&self) -> Result<Box<dyn AudioOutput>, PlaybackError> {
        let mut sink = rodio::DeviceSinkBuilder::open_default_sink()
            .map_err(|e| PlaybackError::NoDevice(e.to_string()))?;
        sink.log_on_drop(false);
        Ok(Box::new(RodioOutput { sink }))
    }
}

/// Whether the app can play sound at all.
pub enum PlayerState {
    Ready(Box<dyn AudioOutput>),
    NoDevice(String),
}

/// The song loaded into an output, with its transport.
pub struct Loaded {
    pub track_path: PathBuf,
    pub duration_s: f64,
    pub sample_rate: u32,
    pub transport: Arc<Transport>,
}

/// Plays one song at a time.
pub struct Player {
    pub state: PlayerState,
    pub loaded: Option<Loaded>,
}

impl Player {
    /// Opens the backend's output; a failure becomes [`PlayerState::NoDevice`], never a panic.
    pub fn new(backend: &dyn AudioBackend) -> Self {
        let state = match backend.open() {
            Ok(output) => PlayerState::Ready(output),
            Err(e) => {
                let reason = match e {
                    PlaybackError::NoDevice(reason) => reason,
                    other => other.to_string(),
                };
                log::warn!("no audio device: {reason}");
                PlayerState::NoDevice(reason)
            }
        };
        Self {
            state,
            loaded: None,
        }
    }

    /// Why there is no sound, if there is none.
    pub fn no_device(&self) -> Option<&str> {
        match &self.state {
            PlayerState::NoDevice(reason) => Some(reason),
            PlayerState::Ready(_) => None,
        }
    }

    /// Replaces the current song (stopping it) with `track`, paused at its start.
    pub fn load(&mut self, track: Track) {
        self.unload();
        let transport = Arc::new(Transport::new(track.frames()));
        let loaded = Loaded {
            track_path: track.path.clone(),
            duration_s: track.duration_s(),
            sample_rate: track.sample_rate,
            transport: transport.clone(),
        };
        if let PlayerState::Ready(output) = &mut self.state {
            output.play(TrackSource::new(track, transport));
        }
        self.loaded = Some(loaded);
    }

    /// Stops and forgets the song.
    pub fn unload(&mut self) {
        if let Some(old) = self.loaded.take() {
            // The old source keeps feeding silence; stop it from advancing.
            old.transport.set_playing(false);
            old.transport.retire();
        }
    }

    pub fn is_playing(&self) -> bool {
        self.loaded
            .as_ref()
            .is_some_and(|l| l.transport.is_playing())
    }

    /// Starts or pauses; without a device, nothing plays and the playhead stays.
    pub fn toggle(&mut self) {
        if self.no_device().is_some() {
            return;
        }
        if let Some(loaded) = &self.loaded {
            loaded.transport.set_playing(!loaded.transport.is_playing());
        }
    }

    pub fn seek_s(&self, seconds: f64) {
        if let Some(loaded) = &self.loaded {
            loaded
                .transport
                .seek(seconds_to_frames(seconds, loaded.sample_rate));
        }
    }

    /// Plays the loaded song `db` decibels louder or quieter (A/B compare's loudness matching).
    pub fn set_gain_db(&self, db: f32) {
        if let Some(loaded) = &self.loaded {
            loaded.transport.set_gain_db(db);
        }
    }

    pub fn set_loop_s(&self, range: Option<(f64, f64)>) {
        if let Some(loaded) = &self.loaded {
            let rate = loaded.sample_rate;
            loaded.transport.set_loop(
                range.map(|(a, b)| (seconds_to_frames(a, rate), seconds_to_frames(b, rate))),
            );
        }
    }
}

fn seconds_to_frames(seconds: f64, sample_rate: u32) -> u64 {
    (seconds.max(0.0) * f64::from(sample_rate)).round() as u64
}

/// The playhead's time, from an [`AudioClock`], smoothed between device callbacks: while the
/// clock stands still the time runs on with the wall clock for at most `max_interpolation`, and
/// it snaps back to the clock whenever the clock moves. It never drifts from the device.
#[derive(Clone, Debug)]
pub struct Playhead {
    sample_rate: u32,
    last_frames: u64,
    last_change: Option<Instant>,
    pub max_interpolation: Duration,
}

impl Playhead {
    pub fn new(sample_rate: u32) -> Self {
        Self {
            sample_rate: sample_rate.max(1),
            last_frames: 0,
            last_change: None,
            max_interpolation: Duration::from_millis(50),
        }
    }

    /// The time in seconds at `now`.
    pub fn time_s(&mut self, clock: &dyn AudioClock, now: Instant) -> f64 {
        let frames = clock.frames_played();
        if frames != self.last_frames || self.last_change.is_none() {
            self.last_frames = frames;
            self.last_change = Some(now);
        }
        let base = frames as f64 / f64::from(self.sample_rate);
        if !clock.is_running() {
            return base;
        }
        let since = self
            .last_change
            .map_or(Duration::ZERO, |t| now.saturating_duration_since(t))
            .min(self.max_interpolation);
        base + since.as_secs_f64()
    }
}

/// Where time `seconds` lies on the cloud's x axis, normalized to [-1, 1] (clamped), for Song
/// clouds whose x axis is time.
pub fn time_to_x(axis: &crate::data::axes::Axis, seconds: f64) -> f32 {
    axis.normalized_of(seconds).clamp(-1.0, 1.0) as f32
}

/// The time at a normalized x position.
pub fn x_to_time(axis: &crate::data::axes::Axis, x: f32) -> f64 {
    axis.value_at(f64::from(x.clamp(-1.0, 1.0)))
}

/// "1:05.3" for a playback position.
pub fn format_clock(seconds: f64) -> String {
    let seconds = seconds.max(0.0);
    let minutes = (seconds / 60.0).floor();
    format!("{}:{:04.1}", minutes as u64, seconds - minutes * 60.0)
}
