//! Playback without a sound card: the playhead follows a mocked audio clock, seeking moves it,
//! time maps onto the cloud's x axis as the metadata says, and a missing device is a state, not
//! a panic.

use std::cell::Cell;
use std::sync::Arc;
use std::time::{Duration, Instant};

use loudscape::data::axes::Axis;
use loudscape::playback::{
    AudioBackend, AudioClock, AudioOutput, PlaybackError, Player, Playhead, Track, TrackSource,
    Transport, time_to_x, x_to_time,
};

struct MockClock {
    frames: Cell<u64>,
    running: bool,
}

impl AudioClock for MockClock {
    fn frames_played(&self) -> u64 {
        self.frames.get()
    }
    fn is_running(&self) -> bool {
        self.running
    }
}

#[test]
fn playhead_follows_the_audio_clock_not_the_wall_clock() {
    let clock = MockClock {
        frames: Cell::new(0),
        running: true,
    };
    let mut playhead = Playhead::new(48_000);
    let start = Instant::now();
    assert_eq!(playhead.time_s(&clock, start), 0.0);
    // Ten minutes of device callbacks of 480 frames, while the wall clock runs 1% fast: the
    // playhead stays with the device.
    let mut worst = 0.0f64;
    for callback in 1..=60_000u64 {
        clock.frames.set(callback * 480);
        let wall = start + Duration::from_micros(callback * 10_100);
        let t = playhead.time_s(&clock, wall);
        worst = worst.max((t - callback as f64 * 0.01).abs());
    }
    assert!(worst < 1e-9, "playhead drifted by {worst} s");
    // Between callbacks it interpolates, at most max_interpolation.
    let last = start + Duration::from_micros(60_000 * 10_100);
    let t = playhead.time_s(&clock, last + Duration::from_millis(5));
    assert!((t - (600.0 + 0.005)).abs() < 1e-6, "{t}");
    let t = playhead.time_s(&clock, last + Duration::from_secs(3));
    assert!((t - (600.0 + 0.05)).abs() < 1e-6, "{t}");
    // Paused: exactly the clock.
    let paused = MockClock {
        frames: Cell::new(24_000),
        running: false,
    };
    assert_eq!(playhead.time_s(&paused, last + Duration::from_secs(9)), 0.5);
}

fn ramp_track(frames: usize, channels: u16, sample_rate: u32) -> Track {
    let samples: Vec<f32> = (0..frames * usize::from(channels))
        .map(|i| (i / usize::from(channels)) as f32)
        .collect();
    Track {
        path: "ramp.wav".into(),
        samples: samples.into(),
        channels,
        sample_rate,
    }
}

#[test]
fn the_source_counts_frames_and_seeking_moves_it() {
    let track = ramp_track(1000, 2, 100);
    let transport = Arc::new(Transport::new(1000));
    let mut source = TrackSource::new(track, transport.clone());
    // Paused: silence, the clock stands.
    assert_eq!(source.next(), Some(0.0));
    assert_eq!(transport.frames_played(), 0);
    transport.set_playing(true);
    let played: Vec<f32> = (0..20).map(|_| source.next().unwrap_or(-1.0)).collect();
    assert_eq!(&played[..4], &[0.0, 0.0, 1.0, 1.0]);
    assert_eq!(transport.frames_played(), 10);
    transport.seek(500);
    assert_eq!(source.next(), Some(500.0));
    assert_eq!(source.next(), Some(500.0));
    assert_eq!(transport.frames_played(), 501);
    // Loop [600, 610): after the end it wraps.
    transport.seek(605);
    transport.set_loop(Some((600, 610)));
    let frames: Vec<f32> = (0..20)
        .map(|_| source.next().unwrap_or(-1.0))
        .step_by(2)
        .collect();
    assert_eq!(
        frames,
        vec![
            605.0, 606.0, 607.0, 608.0, 609.0, 600.0, 601.0, 602.0, 603.0, 604.0
        ]
    );
    // At the end it stops.
    transport.set_loop(None);
    transport.seek(998);
    for _ in 0..4 {
        source.next();
    }
    assert!(!transport.is_playing());
    assert_eq!(transport.frames_played(), 1000);
    assert_eq!(source.next(), Some(0.0));
}

struct NoDevice;
impl AudioBackend for NoDevice {
    fn open(&self) -> Result<Box<dyn AudioOutput>, PlaybackError> {
        Err(PlaybackError::NoDevice("no default output device".into()))
    }
}

struct Silent;
struct SilentOutput;
impl AudioOutput for SilentOutput {
    fn play(&mut self, _source: TrackSource) {}
}
impl AudioBackend for Silent {
    fn open(&self) -> Result<Box<dyn AudioOutput>, PlaybackError> {
        Ok(Box::new(SilentOutput))
    }
}

#[test]
fn without_a_device_the_player_says_so_and_keeps_working() {
    let mut player = Player::new(&NoDevice);
    assert_eq!(player.no_device(), Some("no default output device"));
    player.load(ramp_track(100, 1, 100));
    player.toggle();
    assert!(!player.is_playing());
    player.seek_s(0.5);
    let loaded = player.loaded.as_ref().expect("track kept");
    assert_eq!(loaded.transport.frames_played(), 50);
}

#[test]
fn seeking_in_seconds_lands_on_the_right_frame() {
    let mut player = Player::new(&Silent);
    assert!(player.no_device().is_none());
    player.load(ramp_track(44_100 * 3, 2, 44_100));
    player.seek_s(1.5);
    let transport = player.loaded.as_ref().expect("loaded").transport.clone();
    assert_eq!(transport.frames_played(), 66_150);
    player.seek_s(99.0);
    assert_eq!(transport.frames_played(), 44_100 * 3);
    player.toggle();
    assert!(player.is_playing());
    assert_eq!(
        transport.frames_played(),
        0,
        "playing from the end restarts"
    );
}

#[test]
fn time_maps_onto_the_x_axis_of_the_metadata() {
    let cloud = loudscape::data::cloud::load(
        &std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.ply"),
    )
    .expect("demo cloud");
    let x = &cloud.meta.axes.x;
    assert_eq!(x.unit, "s");
    assert!((time_to_x(x, x.min) + 1.0).abs() < 1e-6);
    assert!((time_to_x(x, x.max) - 1.0).abs() < 1e-6);
    let mid = (x.min + x.max) / 2.0;
    assert!(time_to_x(x, mid).abs() < 1e-6);
    assert!((x_to_time(x, 0.5) - (x.min + 0.75 * (x.max - x.min))).abs() < 1e-6);
    // Before the first frame and after the last: clamped to the box.
    assert_eq!(time_to_x(x, x.min - 10.0), -1.0);
    assert_eq!(time_to_x(x, x.max + 10.0), 1.0);
    let axis = Axis::linear("time", "s", 0.0, 30.0);
    assert!((time_to_x(&axis, 7.5) + 0.5).abs() < 1e-6);
}

#[test]
fn the_demo_song_resolves_and_unplayable_formats_say_why() {
    let repo = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("loudscape-playback-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let opus = dir.join("song.opus");
    std::fs::write(&opus, b"OggS not really").expect("write");
    let err = loudscape::playback::decode(&opus).expect_err("opus is not playable");
    let text = err.to_string();
    assert!(text.contains(".opus") && text.contains("wav"), "{text}");
    // A moved song: the message says it cannot be found and where it looked.
    let mut cloud = loudscape::data::cloud::load(&repo.join("data/demo_song.ply")).expect("demo");
    if let Some(source) = cloud.meta.source.as_mut() {
        source.path = Some("gone/away.wav".into());
    }
    let err = loudscape::playback::resolve_source(&cloud).expect_err("moved");
    assert!(err.to_string().contains("cannot be found"), "{err}");
    // A real wav decodes.
    let wav = dir.join("tone.wav");
    write_wav(&wav, 8000, &[0, 16384, -16384, 0]);
    let track = loudscape::playback::decode(&wav).expect("wav decodes");
    assert_eq!(track.sample_rate, 8000);
    assert_eq!(track.frames(), 4);
    assert!((track.samples[1] - 0.5).abs() < 1e-3);
    let _ = std::fs::remove_dir_all(&dir);
}

fn write_wav(path: &std::path::Path, rate: u32, samples: &[i16]) {
    let data_len = (samples.len() * 2) as u32;
    let mut b = Vec::new();
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(36 + data_len).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&1u16.to_le_bytes());
    b.extend_from_slice(&1u16.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(rate * 2).to_le_bytes());
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&16u16.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&data_len.to_le_bytes());
    for s in samples {
        b.extend_from_slice(&s.to_le_bytes());
    }
    std::fs::write(path, b).expect("write wav");
}
