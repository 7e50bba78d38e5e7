//! Playback without a sound card: the playhead follows a mocked audio clock, seeking moves it,
//! time maps onto the cloud's x axis as the metadata says, and a missing device is a state, not
//! a panic. The song streams from its file: long synthesized WAV and FLAC files play the samples
//! a whole decode gives, from any frame, around loops, through a buffer of fixed capacity.

use std::cell::Cell;
use std::path::{Path, PathBuf};
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

/// A scratch folder of this test process.
fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("loudscape-playback-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A float WAV whose every sample is its frame number (exact in f32 below 2^24), opened for
/// playback.
fn ramp_track(dir: &Path, frames: usize, channels: u16, sample_rate: u32) -> Track {
    let samples: Vec<f32> = (0..frames * usize::from(channels))
        .map(|i| (i / usize::from(channels)) as f32)
        .collect();
    let path = dir.join(format!("ramp-{frames}-{channels}-{sample_rate}.wav"));
    write_wav_f32(&path, channels, sample_rate, &samples);
    loudscape::playback::decode(&path).expect("ramp decodes")
}

/// The next `frames` frames the source plays while playing, interleaved, skipping the silence
/// it gives while its decoder catches up after a seek (that silence does not move the clock).
fn play(source: &mut TrackSource, channels: usize, frames: usize) -> Vec<f32> {
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut out = Vec::with_capacity(frames * channels);
    while out.len() < frames * channels {
        if !source.is_buffered() {
            assert!(Instant::now() < deadline, "the decoder never caught up");
            std::thread::sleep(Duration::from_micros(200));
            continue;
        }
        for _ in 0..channels {
            out.push(source.next().expect("the source lives"));
        }
    }
    out
}

/// Waits until the frame at the transport's position is decoded.
fn wait_buffered(source: &mut TrackSource) {
    let deadline = Instant::now() + Duration::from_secs(30);
    while !source.is_buffered() {
        assert!(Instant::now() < deadline, "the decoder never caught up");
        std::thread::sleep(Duration::from_micros(200));
    }
}

#[test]
fn a_gain_scales_every_sample_from_the_next_frame_on() {
    let dir = scratch("gain");
    let track = ramp_track(&dir, 1000, 2, 100);
    let transport = Arc::new(Transport::new(1000));
    let mut source = TrackSource::new(track, transport.clone());
    transport.set_playing(true);
    transport.seek(100);
    assert_eq!(play(&mut source, 2, 1), vec![100.0, 100.0]);
    // A/B compare's matching: -6.0206 dB is half the amplitude, exactly enough here.
    transport.set_gain_db(-20.0 * 2f32.log10());
    let played = play(&mut source, 2, 2);
    for (got, want) in played.iter().zip([50.5, 50.5, 51.0, 51.0]) {
        assert!((got - want).abs() < 1e-3, "{played:?}");
    }
    transport.set_gain_db(0.0);
    assert_eq!(play(&mut source, 2, 1), vec![103.0, 103.0]);
    // A gain that is not a number plays the file as it is.
    transport.set_gain_db(f32::NAN);
    assert_eq!(play(&mut source, 2, 1), vec![104.0, 104.0]);
    drop(source);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_source_counts_frames_and_seeking_moves_it() {
    let dir = scratch("counts");
    let track = ramp_track(&dir, 1000, 2, 100);
    assert_eq!(track.frames(), 1000);
    let transport = Arc::new(Transport::new(1000));
    let mut source = TrackSource::new(track, transport.clone());
    // Paused: silence, the clock stands (however long the decoder has had).
    wait_buffered(&mut source);
    assert_eq!(source.next(), Some(0.0));
    assert_eq!(transport.frames_played(), 0);
    transport.set_playing(true);
    let played = play(&mut source, 2, 10);
    assert_eq!(&played[..4], &[0.0, 0.0, 1.0, 1.0]);
    assert_eq!(transport.frames_played(), 10);
    transport.seek(500);
    assert_eq!(play(&mut source, 2, 1), vec![500.0, 500.0]);
    assert_eq!(transport.frames_played(), 501);
    // Loop [600, 610): after the end it wraps (the loop set after the seek: the frames decoded
    // past 609 are replaced where the order differs).
    transport.seek(605);
    transport.set_loop(Some((600, 610)));
    let frames: Vec<f32> = play(&mut source, 2, 10).into_iter().step_by(2).collect();
    assert_eq!(
        frames,
        vec![
            605.0, 606.0, 607.0, 608.0, 609.0, 600.0, 601.0, 602.0, 603.0, 604.0
        ]
    );
    // At the end it stops.
    transport.set_loop(None);
    transport.seek(998);
    play(&mut source, 2, 2);
    assert_eq!(source.next(), Some(0.0));
    assert!(!transport.is_playing());
    assert_eq!(transport.frames_played(), 1000);
    assert_eq!(source.next(), Some(0.0));
    // Playing again from the end restarts at the start.
    transport.set_playing(true);
    assert_eq!(play(&mut source, 2, 1), vec![0.0, 0.0]);
    drop(source);
    let _ = std::fs::remove_dir_all(&dir);
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
    let dir = scratch("no-device");
    player.load(ramp_track(&dir, 100, 1, 100));
    let _ = std::fs::remove_dir_all(&dir);
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
    let dir = scratch("seconds");
    player.load(ramp_track(&dir, 44_100 * 3, 2, 44_100));
    let _ = std::fs::remove_dir_all(&dir);
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
    let dir = scratch("formats");
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
    let transport = Arc::new(Transport::new(track.frames()));
    let mut source = TrackSource::new(track, transport.clone());
    transport.set_playing(true);
    let played = play(&mut source, 1, 4);
    assert_eq!(played, vec![0.0, 0.5, -0.5, 0.0]);
    drop(source);
    // A file that cannot be opened, one that is not audio, one without samples: one clear
    // message each.
    let err = loudscape::playback::decode(&dir.join("missing.wav")).expect_err("missing");
    assert!(
        matches!(err, PlaybackError::Open { .. }) && err.to_string().contains("cannot open"),
        "{err}"
    );
    let garbage = dir.join("garbage.wav");
    std::fs::write(&garbage, vec![7u8; 4096]).expect("write");
    let err = loudscape::playback::decode(&garbage).expect_err("not audio");
    assert!(matches!(err, PlaybackError::Unsupported { .. }), "{err}");
    let empty = dir.join("empty.wav");
    write_wav(&empty, 8000, &[]);
    let err = loudscape::playback::decode(&empty).expect_err("no samples");
    assert!(matches!(err, PlaybackError::Empty { .. }), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A canonical WAV file: `format` 1 (16-bit PCM) or 3 (32-bit float), `data` the interleaved
/// little-endian samples.
fn write_wav_bytes(path: &Path, format: u16, bits: u16, channels: u16, rate: u32, data: &[u8]) {
    let data_len = data.len() as u32;
    let block = channels * bits / 8;
    let mut b = Vec::with_capacity(44 + data.len());
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(36 + data_len).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&format.to_le_bytes());
    b.extend_from_slice(&channels.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(rate * u32::from(block)).to_le_bytes());
    b.extend_from_slice(&block.to_le_bytes());
    b.extend_from_slice(&bits.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&data_len.to_le_bytes());
    b.extend_from_slice(data);
    std::fs::write(path, b).expect("write wav");
}

/// A mono 16-bit WAV.
fn write_wav(path: &Path, rate: u32, samples: &[i16]) {
    write_wav_16(path, 1, rate, samples);
}

fn write_wav_f32(path: &Path, channels: u16, rate: u32, samples: &[f32]) {
    let data: Vec<u8> = samples.iter().flat_map(|s| s.to_le_bytes()).collect();
    write_wav_bytes(path, 3, 32, channels, rate, &data);
}

fn write_wav_16(path: &Path, channels: u16, rate: u32, samples: &[i16]) {
    let data: Vec<u8> = samples.iter().flat_map(|s| s.to_le_bytes()).collect();
    write_wav_bytes(path, 1, 16, channels, rate, &data);
}

fn crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &byte in bytes {
        crc ^= byte;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

fn crc16(bytes: &[u8]) -> u16 {
    let mut crc = 0u16;
    for &byte in bytes {
        crc ^= u16::from(byte) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x8005
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// A 16-bit FLAC of `samples` (interleaved) in blocks of `block` frames, each subframe stored
/// verbatim (no seek table: symphonia seeks by searching the frames).
fn write_flac(path: &Path, channels: u16, rate: u32, block: usize, samples: &[i16]) {
    let ch = usize::from(channels);
    let total = (samples.len() / ch) as u64;
    let mut b = Vec::new();
    b.extend_from_slice(b"fLaC");
    b.extend_from_slice(&[0x80, 0, 0, 34]); // last block, STREAMINFO, 34 bytes
    b.extend_from_slice(&(block as u16).to_be_bytes());
    b.extend_from_slice(&(block as u16).to_be_bytes());
    b.extend_from_slice(&[0; 6]); // frame sizes unknown
    let packed: u64 = (u64::from(rate) << 44)
        | (u64::from(channels - 1) << 41)
        | (15u64 << 36)
        | (total & ((1 << 36) - 1));
    b.extend_from_slice(&packed.to_be_bytes());
    b.extend_from_slice(&[0; 16]); // no MD5
    for (number, frames) in samples.chunks(block * ch).enumerate() {
        let start = b.len();
        let n = frames.len() / ch;
        b.extend_from_slice(&[0xFF, 0xF8]); // sync, fixed block size
        b.push(0x70); // block size: 16 bits follow; sample rate from STREAMINFO
        b.push(((channels as u8 - 1) << 4) | 0x08); // independent channels, 16 bits
        // The frame number, UTF-8 coded.
        let number = number as u32;
        if number < 0x80 {
            b.push(number as u8);
        } else if number < 0x800 {
            b.push(0xC0 | (number >> 6) as u8);
            b.push(0x80 | (number & 0x3F) as u8);
        } else {
            assert!(number < 0x10000);
            b.push(0xE0 | (number >> 12) as u8);
            b.push(0x80 | ((number >> 6) & 0x3F) as u8);
            b.push(0x80 | (number & 0x3F) as u8);
        }
        b.extend_from_slice(&((n - 1) as u16).to_be_bytes());
        let header_crc = crc8(&b[start..]);
        b.push(header_crc);
        for c in 0..ch {
            b.push(0x02); // VERBATIM, no wasted bits
            for f in 0..n {
                b.extend_from_slice(&frames[f * ch + c].to_be_bytes());
            }
        }
        let frame_crc = crc16(&b[start..]);
        b.extend_from_slice(&frame_crc.to_be_bytes());
    }
    std::fs::write(path, b).expect("write flac");
}

/// Noise (so a frame off anywhere shows) with a slow sweep, interleaved.
fn noise(frames: usize, channels: u16) -> Vec<i16> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    (0..frames * usize::from(channels))
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 48) as i16
        })
        .collect()
}

/// What decoding the whole file with rodio gives (the way the window decoded songs before they
/// streamed).
fn whole(path: &Path) -> Vec<f32> {
    let file = std::fs::File::open(path).expect("open");
    rodio::Decoder::try_from(file)
        .expect("rodio decodes")
        .collect()
}

/// Streams `path` whole, seeks to frames around packet edges and checks each against `reference`
/// and the samples written; a loop over a packet edge wraps in order without a resync.
fn check_streaming(path: &Path, channels: u16, rate: u32, written: &[i16], packet: u64) {
    let ch = usize::from(channels);
    let reference = whole(path);
    assert_eq!(reference.len(), written.len(), "rodio decodes every sample");
    for (r, w) in reference.iter().zip(written) {
        assert_eq!(r.to_bits(), (f32::from(*w) / 32_768.0).to_bits());
    }
    let track = loudscape::playback::decode(path).expect("decodes");
    let frames = (written.len() / ch) as u64;
    assert_eq!(track.frames(), frames, "the length from the container");
    assert_eq!((track.channels, track.sample_rate), (channels, rate));
    let transport = Arc::new(Transport::new(track.frames()));
    let mut source = TrackSource::new(track, transport.clone());
    // Memory: the buffer holds two seconds of frames, a small share of the song.
    let capacity = source.ring().capacity();
    assert_eq!(capacity, loudscape::playback::stream::buffer_frames(rate));
    assert!(capacity as f64 <= 2.0 * f64::from(rate) + 1.0);
    assert!(
        frames > 10 * capacity as u64,
        "the song is longer than the buffer"
    );
    // The whole song, bit for bit.
    transport.set_playing(true);
    let mut streamed = Vec::with_capacity(reference.len());
    let chunk = 4_000;
    while (streamed.len() / ch) < frames as usize {
        let left = frames as usize - streamed.len() / ch;
        streamed.extend(play(&mut source, ch, left.min(chunk)));
        assert!(source.ring().len() <= capacity);
    }
    assert_eq!(transport.frames_played(), frames);
    assert!(!transport.is_playing(), "it stops at the end");
    let same = streamed
        .iter()
        .zip(&reference)
        .all(|(a, b)| a.to_bits() == b.to_bits());
    assert!(same, "the stream differs from the whole decode");
    // Seeking to a frame gives the samples from that frame.
    transport.set_playing(true);
    for frame in [
        0,
        1,
        packet - 1,
        packet,
        packet + 1,
        frames / 3 + 7,
        frames / 2,
        frames - packet - 3,
        frames - 5,
        5 * packet + 11,
    ] {
        transport.seek(frame);
        let n = 64.min((frames - frame) as usize);
        let got = play(&mut source, ch, n);
        let at = frame as usize * ch;
        assert_eq!(
            got,
            reference[at..at + n * ch],
            "after a seek to frame {frame}"
        );
        assert_eq!(transport.frames_played(), frame + n as u64);
        transport.set_playing(true);
    }
    // A loop across a packet edge, set before the seek into it: it wraps three times in order,
    // and the decoder never had to resync (it decoded in the loop's order).
    let (a, b) = (3 * packet - 100, 4 * packet + 257);
    transport.set_loop(Some((a, b)));
    transport.seek(b - 10);
    wait_buffered(&mut source);
    let serial = transport.serial();
    let len = (b - a) as usize;
    let got = play(&mut source, ch, 10 + 3 * len);
    let mut expected = reference[(b as usize - 10) * ch..b as usize * ch].to_vec();
    for _ in 0..3 {
        expected.extend_from_slice(&reference[a as usize * ch..b as usize * ch]);
    }
    assert_eq!(got, expected, "the loop plays in order");
    assert_eq!(transport.serial(), serial, "the loop was decoded in order");
    assert_eq!(transport.frames_played(), a, "back at the loop's start");
}

#[test]
fn a_long_wav_streams_the_samples_of_a_whole_decode() {
    let dir = scratch("long-wav");
    // Two minutes of mono noise at 22.05 kHz: 60 times the buffer.
    let (rate, channels) = (22_050, 1);
    let written = noise(rate as usize * 120, channels);
    let path = dir.join("long.wav");
    write_wav_16(&path, channels, rate, &written);
    // symphonia's WAV packets: 1152 frames for this format.
    check_streaming(&path, channels, rate, &written, 1152);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_long_flac_streams_the_samples_of_a_whole_decode() {
    let dir = scratch("long-flac");
    // A minute of stereo noise at 44.1 kHz in 4096-frame FLAC blocks.
    let (rate, channels) = (44_100, 2);
    let written = noise(rate as usize * 60, channels);
    let path = dir.join("long.flac");
    write_flac(&path, channels, rate, 4096, &written);
    check_streaming(&path, channels, rate, &written, 4096);
    let _ = std::fs::remove_dir_all(&dir);
}
