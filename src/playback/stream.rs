//! Streamed decoding: the song is decoded while it plays, a couple of seconds ahead, never whole.
//!
//! A [`Reader`] decodes the file packet by packet with symphonia and seeks to an exact frame
//! (the container's packet timestamps say where a decoded packet starts, so the frames before
//! the target are dropped). A decoder thread ([`spawn`]) runs the reader and fills a bounded
//! [`Ring`] in the order the [`Transport`] will play (loop wraps included); the audio callback
//! only takes frames out of the ring, so file reads and seeks never run on it. Every frame in
//! the ring carries its frame number and the transport's seek serial when it was decoded: the
//! callback plays a frame only when both match where the transport stands, drops the ones a
//! seek made stale, and asks for a resync when the order is not the one it needs (a loop range
//! changed while frames were buffered).
//!
//! The decoder thread sleeps (parks, no timeout) whenever it has nothing to do: the ring is full
//! (always so while paused) or the song is decoded to its end. It is woken when there is work:
//! by the callback once it has taken a quarter of the ring ([`refill_at`]: 1.5 s still buffered,
//! so a refill never starts late), by the [`Transport`] on a seek, a loop change or when the song
//! is replaced, and by the source when it asks for a resync or is dropped. Every wake re-checks
//! all it waits on, and an unpark that comes before the park makes the park return at once, so
//! no wake is lost.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering, fence};
use std::sync::{Arc, OnceLock};
use std::thread::Thread;

use symphonia::core::audio::SampleBuffer;
use symphonia::core::codecs::{CODEC_TYPE_NULL, Decoder, DecoderOptions};
use symphonia::core::errors::Error;
use symphonia::core::formats::{FormatOptions, FormatReader, SeekMode, SeekTo};
use symphonia::core::io::MediaSourceStream;
use symphonia::core::meta::MetadataOptions;
use symphonia::core::probe::Hint;

use super::Transport;

/// How much decoded audio the ring holds ahead of the device, in seconds of the track.
pub const BUFFER_SECONDS: f64 = 2.0;

/// The ring's capacity in frames for a sample rate: [`BUFFER_SECONDS`] of audio, whatever the
/// song's length.
pub fn buffer_frames(sample_rate: u32) -> usize {
    (f64::from(sample_rate.max(1)) * BUFFER_SECONDS).ceil() as usize
}

/// Free frames in a ring of `capacity` at which the callback wakes the decoder waiting for room:
/// a quarter of it (0.5 s of the 2 s), so the decoder refills in bursts a couple of times a second
/// while three quarters (1.5 s) are still buffered, never once per callback and never late.
pub fn refill_at(capacity: usize) -> usize {
    (capacity / 4).max(1)
}

/// Why a file cannot be opened for decoding.
#[derive(Debug)]
pub(crate) enum OpenError {
    Open(String),
    /// No format reader or codec for it (or no audio track in it).
    Unsupported,
    Decode(String),
}

/// Decodes one file packet by packet, from any frame.
pub(crate) struct Reader {
    path: PathBuf,
    format: Box<dyn FormatReader>,
    decoder: Box<dyn Decoder>,
    track_id: u32,
    pub(crate) channels: usize,
    pub(crate) sample_rate: Option<u32>,
    /// Frames in the track as the container states them (None or 0 when it does not).
    pub(crate) stated_frames: Option<u64>,
    buffer: Option<SampleBuffer<f32>>,
    /// Interleaved samples of the last decoded packet not handed out yet start here.
    offset: usize,
    /// After a seek: the frame the next samples must start at (earlier ones are dropped).
    target: Option<u64>,
    /// How far before the target the last retry seeked, when the container's seek overshot.
    backoff: u64,
    ended: bool,
}

impl Reader {
    /// Opens `path` the way rodio's decoder does (same probe, gapless trimming on), so the
    /// frames are the ones a whole decode gives.
    pub(crate) fn open(path: &Path) -> Result<Self, OpenError> {
        let file = std::fs::File::open(path).map_err(|e| OpenError::Open(e.to_string()))?;
        let stream = MediaSourceStream::new(Box::new(file), Default::default());
        let mut hint = Hint::new();
        if let Some(extension) = path.extension().and_then(|e| e.to_str()) {
            hint.with_extension(extension);
        }
        let options = FormatOptions {
            enable_gapless: true,
            ..Default::default()
        };
        let probed = symphonia::default::get_probe()
            .format(&hint, stream, &options, &MetadataOptions::default())
            .map_err(|e| match e {
                Error::Unsupported(_) => OpenError::Unsupported,
                other => OpenError::Decode(other.to_string()),
            })?;
        let format = probed.format;
        let track = format
            .tracks()
            .iter()
            .find(|t| t.codec_params.codec != CODEC_TYPE_NULL)
            .ok_or(OpenError::Unsupported)?;
        let decoder = symphonia::default::get_codecs()
            .make(&track.codec_params, &DecoderOptions::default())
            .map_err(|e| match e {
                Error::Unsupported(_) => OpenError::Unsupported,
                other => OpenError::Decode(other.to_string()),
            })?;
        let params = &track.codec_params;
        Ok(Self {
            path: path.to_path_buf(),
            track_id: track.id,
            channels: params.channels.map_or(0, |c| c.count()),
            sample_rate: params.sample_rate,
            stated_frames: params.n_frames.filter(|&n| n > 0),
            format,
            decoder,
            buffer: None,
            offset: 0,
            target: None,
            backoff: 0,
            ended: false,
        })
    }

    /// The decoded samples not handed out yet (interleaved, whole frames); empty at the end.
    pub(crate) fn remaining(&self) -> &[f32] {
        match &self.buffer {
            Some(buffer) => &buffer.samples()[self.offset.min(buffer.len())..],
            None => &[],
        }
    }

    /// Hands out `frames` frames of [`Self::remaining`].
    pub(crate) fn consume(&mut self, frames: usize) {
        self.offset += frames * self.channels.max(1);
    }

    /// Decodes packets until one gives samples (after a seek: samples at or after the target);
    /// false at the end of the stream or on an error that ends it.
    pub(crate) fn fill(&mut self) -> bool {
        while self.remaining().is_empty() {
            if self.ended || !self.decode_packet() {
                self.ended = true;
                return false;
            }
        }
        true
    }

    /// Decodes the next packet of the track into the buffer; false when the stream ends.
    fn decode_packet(&mut self) -> bool {
        loop {
            let packet = match self.format.next_packet() {
                Ok(packet) => packet,
                Err(_) => return false,
            };
            if packet.track_id() != self.track_id {
                continue;
            }
            let ts = packet.ts();
            let decoded = match self.decoder.decode(&packet) {
                Ok(decoded) => decoded,
                // Like rodio: a packet that does not decode is skipped.
                Err(Error::DecodeError(_)) => continue,
                Err(_) => return false,
            };
            let frames = decoded.frames();
            if frames == 0 {
                continue;
            }
            let spec = *decoded.spec();
            let channels = spec.channels.count();
            if self.channels == 0 {
                self.channels = channels;
                self.sample_rate = Some(spec.rate);
            }
            if channels != self.channels {
                // A change of layout mid-stream: not this track's frames.
                continue;
            }
            let mut skip = 0;
            if let Some(target) = self.target {
                if ts > target {
                    // The seek landed past the target: seek again, further before it.
                    self.backoff = (self.backoff * 2).max(frames as u64 * 2);
                    let earlier = target.saturating_sub(self.backoff);
                    if ts == 0 || !self.seek_raw(earlier) {
                        // Nothing earlier to go to: play from here.
                        self.target = None;
                    }
                    continue;
                }
                if ts + frames as u64 <= target {
                    continue;
                }
                skip = (target - ts) as usize;
                self.target = None;
            }
            let needed = decoded.capacity() * channels;
            let buffer = match &mut self.buffer {
                Some(buffer) if buffer.capacity() >= needed => buffer,
                slot => slot.insert(SampleBuffer::new(decoded.capacity() as u64, spec)),
            };
            buffer.copy_interleaved_ref(decoded);
            self.offset = skip * channels;
            return true;
        }
    }

    /// Positions the reader so that the next samples are those of `frame`.
    pub(crate) fn seek(&mut self, frame: u64) {
        self.buffer = None;
        self.offset = 0;
        self.ended = false;
        self.backoff = 0;
        self.target = Some(frame);
        if !self.seek_raw(frame) {
            self.rewind();
        }
    }

    /// Asks the container for the packet holding `ts`; false when it cannot seek.
    fn seek_raw(&mut self, ts: u64) -> bool {
        let to = SeekTo::TimeStamp {
            ts,
            track_id: self.track_id,
        };
        match self.format.seek(SeekMode::Accurate, to) {
            Ok(_) => {
                self.decoder.reset();
                true
            }
            Err(e) => {
                log::debug!("{}: seek to frame {ts} failed: {e}", self.path.display());
                false
            }
        }
    }

    /// Reopens the file at its start (a container that cannot seek): decoding then drops the
    /// frames before the target.
    fn rewind(&mut self) {
        let target = self.target;
        match Reader::open(&self.path) {
            Ok(fresh) => {
                *self = fresh;
                self.target = target;
            }
            Err(_) => self.ended = true,
        }
    }

    /// Frames in the stream by reading its packets without decoding them: for containers that
    /// do not state their length (some mp3 and ogg files).
    pub(crate) fn count_frames(mut self) -> u64 {
        let mut frames = 0u64;
        while let Ok(packet) = self.format.next_packet() {
            if packet.track_id() == self.track_id {
                let trim = u64::from(packet.trim_start()) + u64::from(packet.trim_end());
                frames += packet.dur().saturating_sub(trim);
            }
        }
        frames
    }
}

/// A single-producer single-consumer ring of decoded frames with a fixed capacity: the decoder
/// thread pushes, the audio callback takes. Lock-free (atomics only), never allocates after
/// [`Ring::new`].
pub struct Ring {
    channels: usize,
    capacity: usize,
    samples: Box<[AtomicU32]>,
    /// Per slot: the frame number (low 40 bits) and the seek serial it was decoded for.
    tags: Box<[AtomicU64]>,
    /// Frames taken so far (written by the consumer only).
    head: AtomicUsize,
    /// Frames pushed so far (written by the producer only).
    tail: AtomicUsize,
}

const FRAME_BITS: u32 = 40;
const FRAME_MASK: u64 = (1 << FRAME_BITS) - 1;

/// A frame's tag: its number and the serial (its low 24 bits) of the seek it was decoded after.
pub(crate) fn tag(serial: u64, frame: u64) -> u64 {
    (serial << FRAME_BITS) | (frame & FRAME_MASK)
}

pub(crate) fn tag_frame(tag: u64) -> u64 {
    tag & FRAME_MASK
}

pub(crate) fn tag_serial(tag: u64) -> u64 {
    tag >> FRAME_BITS
}

pub(crate) fn serial_bits(serial: u64) -> u64 {
    serial & ((1 << (64 - FRAME_BITS)) - 1)
}

impl Ring {
    pub fn new(capacity: usize, channels: usize) -> Self {
        let capacity = capacity.max(1);
        let channels = channels.max(1);
        Self {
            channels,
            capacity,
            samples: (0..capacity * channels)
                .map(|_| AtomicU32::new(0))
                .collect(),
            tags: (0..capacity).map(|_| AtomicU64::new(u64::MAX)).collect(),
            head: AtomicUsize::new(0),
            tail: AtomicUsize::new(0),
        }
    }

    /// The most frames it can hold.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Frames buffered now (never more than [`Ring::capacity`]).
    pub fn len(&self) -> usize {
        self.tail
            .load(Ordering::Acquire)
            .wrapping_sub(self.head.load(Ordering::Acquire))
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Room for this many frames (exact on the producer side; on the consumer side at least
    /// this many, as the producer may have pushed since).
    fn free(&self) -> usize {
        self.capacity - self.len()
    }

    /// Producer: appends one frame (the caller checked [`Ring::free`]).
    fn push(&self, tag: u64, frame: &[f32]) {
        let tail = self.tail.load(Ordering::Relaxed);
        let slot = tail % self.capacity;
        let base = slot * self.channels;
        for c in 0..self.channels {
            let value = frame.get(c).copied().unwrap_or(0.0);
            self.samples[base + c].store(value.to_bits(), Ordering::Relaxed);
        }
        self.tags[slot].store(tag, Ordering::Relaxed);
        self.tail.store(tail.wrapping_add(1), Ordering::Release);
    }

    /// Consumer: the tag of the oldest frame, if any.
    pub(crate) fn front(&self) -> Option<u64> {
        let head = self.head.load(Ordering::Relaxed);
        if self.tail.load(Ordering::Acquire) == head {
            return None;
        }
        Some(self.tags[head % self.capacity].load(Ordering::Relaxed))
    }

    /// Consumer: takes the oldest frame into `out` (one sample per channel).
    pub(crate) fn pop(&self, out: &mut [f32]) {
        let head = self.head.load(Ordering::Relaxed);
        let base = (head % self.capacity) * self.channels;
        for (c, sample) in out.iter_mut().enumerate().take(self.channels) {
            *sample = f32::from_bits(self.samples[base + c].load(Ordering::Relaxed));
        }
        self.head.store(head.wrapping_add(1), Ordering::Release);
    }

    /// Consumer: drops the oldest frame.
    pub(crate) fn skip(&self) {
        let head = self.head.load(Ordering::Relaxed);
        self.head.store(head.wrapping_add(1), Ordering::Release);
    }
}

/// What the decoder thread and the source share.
pub(crate) struct Shared {
    pub(crate) ring: Ring,
    /// Set when the source is dropped: the thread ends.
    pub(crate) closed: AtomicBool,
    /// The decoder thread, set once by the thread itself before it first looks at what it waits
    /// on (so a change before it is set is seen by that first look).
    decoder: OnceLock<Thread>,
    /// Set by the decoder before it parks because the ring is full; the consumer clears it and
    /// wakes the decoder once [`refill_at`] frames are free.
    wants_room: AtomicBool,
    /// How many times the decoder woke from a park (a measure of its idle cost).
    wakeups: AtomicU64,
}

impl Shared {
    pub(crate) fn new(ring: Ring) -> Self {
        Self {
            ring,
            closed: AtomicBool::new(false),
            decoder: OnceLock::new(),
            wants_room: AtomicBool::new(false),
            wakeups: AtomicU64::new(0),
        }
    }

    /// Wakes the decoder thread (if it runs yet): it re-checks everything it waits on.
    pub(crate) fn wake(&self) {
        if let Some(thread) = self.decoder.get() {
            thread.unpark();
        }
    }

    /// Consumer, after each frame it took or dropped: wakes the decoder waiting for room once
    /// there is room for [`refill_at`] frames. Lock-free and, until then, two atomic loads.
    pub(crate) fn took(&self) {
        if self.ring.free() < refill_at(self.ring.capacity) {
            return;
        }
        // Pairs with the fence in `park`: either the decoder sees this frame taken
        // before it parks, or this sees `wants_room` set and wakes it.
        fence(Ordering::SeqCst);
        if self.wants_room.load(Ordering::Relaxed) && self.wants_room.swap(false, Ordering::AcqRel)
        {
            self.wake();
        }
    }

    /// How many times the decoder thread woke from a park so far.
    #[cfg(test)]
    pub(crate) fn wakeups(&self) -> u64 {
        self.wakeups.load(Ordering::Relaxed)
    }
}

/// Starts the decoder thread of a track: it fills `shared.ring` from the transport's position,
/// resyncs when the transport's seek serial changes, and ends when the source is dropped or the
/// song is replaced. A file that fails to open (gone since it was probed) plays as silence.
pub(crate) fn spawn(
    path: PathBuf,
    channels: usize,
    transport: Arc<Transport>,
    shared: Arc<Shared>,
) {
    let spawned = std::thread::Builder::new()
        .name("loudscape-audio-decoder".into())
        .spawn(move || {
            let me = std::thread::current();
            let id = me.id();
            // Registered before `run` first looks at the transport: no change is missed.
            let _ = shared.decoder.set(me.clone());
            transport.add_decoder(me);
            run(&path, channels, &transport, &shared);
            transport.remove_decoder(id);
        });
    if let Err(e) = spawned {
        log::warn!("cannot start the audio decoder: {e}");
    }
}

/// Parks the decoder until something it waits on may have changed. `for_room`: it waits for the
/// consumer to free room in the full ring (otherwise only for the transport or the source: the
/// song is decoded to its end).
fn park(shared: &Shared, for_room: bool) {
    if for_room {
        shared.wants_room.store(true, Ordering::Relaxed);
        // Pairs with the fence in `Shared::took`.
        fence(Ordering::SeqCst);
        if shared.ring.free() >= refill_at(shared.ring.capacity) {
            // The consumer took frames meanwhile and may have missed the flag: go on filling.
            shared.wants_room.store(false, Ordering::Relaxed);
            return;
        }
    }
    std::thread::park();
    shared.wakeups.fetch_add(1, Ordering::Relaxed);
    shared.wants_room.store(false, Ordering::Relaxed);
}

fn run(path: &Path, channels: usize, transport: &Transport, shared: &Shared) {
    let mut reader = match Reader::open(path) {
        Ok(reader) => Some(reader),
        Err(e) => {
            log::warn!("{}: cannot reopen for playback: {e:?}", path.display());
            None
        }
    };
    let silence = vec![0.0f32; channels.max(1)];
    let ring = &shared.ring;
    let mut serial = None;
    let mut next = 0u64;
    loop {
        if shared.closed.load(Ordering::Acquire) || transport.is_retired() {
            return;
        }
        let now = transport.serial();
        if serial != Some(now) {
            serial = Some(now);
            next = transport.position();
            if let Some(reader) = reader.as_mut() {
                reader.seek(next);
            }
        }
        let total = transport.frames();
        if next >= total || ring.free() == 0 {
            park(shared, next < total);
            continue;
        }
        let frame_tag = serial_bits(now);
        let mut budget = ring.free();
        while budget > 0 && next < total {
            if let Some(reader) = reader.as_mut()
                && reader.fill()
            {
                let frame = reader.remaining();
                ring.push(tag(frame_tag, next), &frame[..channels.min(frame.len())]);
                reader.consume(1);
            } else {
                // The stream ended before the length the container stated: silence to it.
                ring.push(tag(frame_tag, next), &silence);
            }
            budget -= 1;
            let following = transport.after(next);
            if following != next + 1
                && let Some(reader) = reader.as_mut()
            {
                reader.seek(following);
            }
            next = following;
            if budget.is_multiple_of(1024) && transport.serial() != now {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    //! The decoder's idle cost, measured in wake-ups: none while paused or at the song's end, a
    //! few a second while playing, and the buffer never runs low.

    use std::path::{Path, PathBuf};
    use std::sync::Arc;
    use std::time::{Duration, Instant};

    use super::refill_at;
    use crate::playback::{TrackSource, Transport, decode};

    const RATE: u32 = 8_000;

    /// A mono 16-bit WAV of `frames` frames whose sample at frame `i` is `i % 32768`.
    fn ramp_wav(name: &str, frames: usize) -> (PathBuf, PathBuf) {
        let dir = std::env::temp_dir().join(format!(
            "loudscape-decoder-idle-{}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let b = crate::playback::mono_wav_bytes(RATE, (0..frames).map(|i| (i % 32_768) as i16));
        let path = dir.join("ramp.wav");
        std::fs::write(&path, b).expect("write wav");
        (dir, path)
    }

    fn open(path: &Path) -> (Arc<Transport>, TrackSource) {
        let track = decode(path).expect("ramp decodes");
        let transport = Arc::new(Transport::new(track.frames()));
        let source = TrackSource::new(track, transport.clone());
        (transport, source)
    }

    fn until(what: &str, mut done: impl FnMut() -> bool) {
        let deadline = Instant::now() + Duration::from_secs(20);
        while !done() {
            assert!(Instant::now() < deadline, "timed out waiting until {what}");
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Wake-ups of the decoder over one second in which the source is called as a device
    /// would call it (a callback of 10 ms every 10 ms), paused or stopped.
    fn wakeups_over_a_second(source: &mut TrackSource) -> u64 {
        let before = source.shared.wakeups();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(1) {
            for _ in 0..RATE / 100 {
                assert_eq!(source.next(), Some(0.0), "paused: silence");
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        source.shared.wakeups() - before
    }

    fn decoders(transport: &Transport) -> usize {
        transport
            .decoders
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .len()
    }

    #[test]
    fn the_decoder_sleeps_while_paused_and_at_the_end_and_wakes_for_a_seek() {
        let frames = RATE as usize * 10;
        let (dir, path) = ramp_wav("paused", frames);
        let (transport, mut source) = open(&path);
        let capacity = source.ring().capacity();
        // Paused with a full ring: the decoder has nothing to do (a 2 ms poll woke ~500 times).
        until("the ring is full", || source.ring().len() == capacity);
        let paused = wakeups_over_a_second(&mut source);
        assert!(paused <= 3, "{paused} wake-ups in a second while paused");
        // Played to the end: decoded to the end, it sleeps again.
        transport.seek(frames as u64 - 100);
        transport.set_playing(true);
        until("the song ends", || {
            source.next();
            !transport.is_playing()
        });
        assert_eq!(transport.position(), frames as u64);
        let ended = wakeups_over_a_second(&mut source);
        assert!(ended <= 3, "{ended} wake-ups in a second at the end");
        // A seek wakes it (nothing else would: the ring is empty, the consumer takes nothing),
        // and it decodes the frames from there.
        transport.seek(12_345);
        until("the seek's frame is decoded", || source.is_buffered());
        transport.set_playing(true);
        let mut got = Vec::new();
        for _ in 0..3 {
            got.push(source.next().expect("the source lives"));
        }
        let expected: Vec<f32> = (12_345..12_348)
            .map(|i| f32::from((i % 32_768) as i16) / 32_768.0)
            .collect();
        assert_eq!(got, expected);
        drop(source);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn real_time_playback_refills_in_bursts_and_never_runs_low() {
        let frames = RATE as usize * 10;
        let (dir, path) = ramp_wav("playing", frames);
        let (transport, mut source) = open(&path);
        let capacity = source.ring().capacity();
        until("the ring is full", || source.ring().len() == capacity);
        transport.set_playing(true);
        // 1.5 s of playback in real time, in 10 ms callbacks.
        let before = source.shared.wakeups();
        let start = Instant::now();
        let (mut taken, mut lowest, mut silent) = (0usize, capacity, 0usize);
        while start.elapsed() < Duration::from_millis(1_500) {
            let due = (start.elapsed().as_secs_f64() * f64::from(RATE)) as usize;
            while taken < due {
                if !source.is_buffered() {
                    silent += 1;
                }
                let sample = source.next().expect("the source lives");
                let expected = f32::from((taken % 32_768) as i16) / 32_768.0;
                assert_eq!(sample, expected, "frame {taken}");
                taken += 1;
                lowest = lowest.min(source.ring().len());
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let wakeups = source.shared.wakeups() - before;
        assert_eq!(silent, 0, "the buffer ran dry");
        assert_eq!(transport.position(), taken as u64);
        // Woken once a quarter of the ring is free: 1.5 s still buffered at each refill.
        let floor = capacity - refill_at(capacity);
        assert!(
            lowest + RATE as usize / 2 >= floor && lowest >= RATE as usize / 2,
            "the buffer fell to {lowest} frames of {capacity} (refill at {floor})"
        );
        // 1.5 s of frames taken, a refill each 0.5 s: about three (a 2 ms poll woke ~750 times).
        assert!(
            (1..=10).contains(&wakeups),
            "{wakeups} wake-ups in 1.5 s of playback"
        );
        drop(source);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_sleeping_decoder_ends_when_its_song_is_replaced_or_its_source_dropped() {
        let (dir, path) = ramp_wav("ends", RATE as usize * 10);
        // Replaced (the source stays in the mixer until its next callback).
        let (transport, source) = open(&path);
        until("the ring is full", || {
            source.ring().len() == source.ring().capacity()
        });
        assert_eq!(decoders(&transport), 1);
        transport.retire();
        until("the decoder ends", || decoders(&transport) == 0);
        drop(source);
        // Dropped.
        let (transport, source) = open(&path);
        until("the ring is full", || {
            source.ring().len() == source.ring().capacity()
        });
        drop(source);
        until("the decoder ends", || decoders(&transport) == 0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
