"""Synthesize the 30-second demo song and extract it to data/demo_song.ply.

    python preprocess/scripts/make_demo_song.py

Deterministic (numpy, fixed seed): 110 bpm, kick/snare/hat pattern, a bass line and an
Am-F-C-G chord progression with harmonics and envelopes, a lead line in the second half, an
intro, a breakdown and a fade-out so the loudness moves. Writes data/demo_song.flac (16-bit,
stereo, 22.05 kHz; not committed, this script regenerates it) and data/demo_song.ply.

Demo extraction parameters (to keep the PLY under 5 MB): the song is synthesized at
22.05 kHz, n_fft 2048, hop 1024 (the defaults), noise floor 60 dB instead of the default 80,
linear frequency. The metadata's source.path is ``data/demo_song.flac``: the script runs the
extractor from the repository root with that relative path.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import soundfile

SAMPLE_RATE = 22050
DURATION_S = 30.0
BPM = 110.0
SEED = 20240611
FLOOR_DB = 60.0
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
WAV = os.path.join("data", "demo_song.flac")  # lossless and small enough to ship
PLY = os.path.join("data", "demo_song.ply")

BEAT = 60.0 / BPM
BAR = 4 * BEAT
# Am, F, C, G: MIDI notes of each chord (root position, middle register) and bass roots.
CHORDS = [(57, 60, 64, 69), (53, 57, 60, 65), (55, 60, 64, 67), (55, 59, 62, 67)]
BASS_ROOTS = [33, 29, 36, 31]
LEAD = [69, 72, 74, 76, 74, 72, 69, 67, 69, 72, 76, 79, 76, 74, 72, 69]


def midi_hz(note: float) -> float:
    return 440.0 * 2.0 ** ((note - 69) / 12)


def envelope(n: int, *, sr: int, attack_s: float, release_s: float, decay_s: float | None = None):
    t = np.arange(n) / sr
    env = np.minimum(1.0, t / max(attack_s, 1e-4))
    if decay_s:
        env *= np.exp(-t / decay_s)
    tail = np.clip((n / sr - t) / max(release_s, 1e-4), 0.0, 1.0)
    return env * tail


def tone(frequency: float, duration_s: float, *, sr: int, harmonics, detune: float = 0.0):
    n = int(duration_s * sr)
    t = np.arange(n) / sr
    out = np.zeros(n)
    for k, amplitude in enumerate(harmonics, start=1):
        f = frequency * k * (1 + detune)
        if f < sr / 2:
            out += amplitude * np.sin(2 * np.pi * f * t + 0.3 * k)
    return out


def kick(rng, sr):
    n = int(0.35 * sr)
    t = np.arange(n) / sr
    frequency = 45 + 85 * np.exp(-t / 0.03)
    body = np.sin(2 * np.pi * np.cumsum(frequency) / sr) * np.exp(-t / 0.18)
    click = np.convolve(rng.standard_normal(n), np.hanning(9) / 4, mode="same")
    click *= np.exp(-t / 0.002) * 0.3
    return 0.9 * body + click


def snare(rng, sr):
    n = int(0.25 * sr)
    t = np.arange(n) / sr
    noise = np.diff(rng.standard_normal(n + 1)) * 0.5 * np.exp(-t / 0.07)
    body = 0.5 * np.sin(2 * np.pi * 185 * t) * np.exp(-t / 0.05)
    return 0.6 * (noise + body)


def hat(rng, sr, *, open_hat: bool = False):
    n = int((0.25 if open_hat else 0.06) * sr)
    t = np.arange(n) / sr
    noise = np.diff(rng.standard_normal(n + 1)) * 0.3
    return 0.35 * noise * np.exp(-t / (0.08 if open_hat else 0.015))


def add(track: np.ndarray, sound: np.ndarray, start_s: float, gain: float = 1.0, *, sr: int):
    i = int(round(start_s * sr))
    if i >= track.shape[0]:
        return
    n = min(sound.shape[0], track.shape[0] - i)
    track[i : i + n] += gain * sound[:n]


def synthesize(*, sample_rate: int = SAMPLE_RATE, duration_s: float = DURATION_S) -> np.ndarray:
    """The demo song (the benchmark uses it at 44.1 kHz, 3 minutes).

    Returns
    -------
    samples : np.ndarray [shape=(n_samples, 2), dtype=float32]
    """
    sr = sample_rate
    rng = np.random.default_rng(SEED)
    n = int(duration_s * sr)
    drums, bass, pads_left, pads_right, lead = (np.zeros(n) for _ in range(5))
    n_bars = int(np.ceil(duration_s / BAR))
    for bar in range(n_bars):
        start = bar * BAR
        chord = CHORDS[bar % 4]
        intro, breakdown = bar < 2, bar in (6, 7)
        # Chords: a pad per note, harmonics falling as 1/k^2, slow attack, slight stereo detune.
        for i, note in enumerate(chord):
            harmonics = [1 / k**2 for k in range(1, 7)]
            voice = tone(midi_hz(note), BAR, sr=sr, harmonics=harmonics, detune=0.0015 * (i - 1.5))
            voice *= envelope(voice.shape[0], sr=sr, attack_s=0.12, release_s=0.3)
            add(pads_left, voice, start, 0.10 * (1.2 if i % 2 else 0.8), sr=sr)
            add(pads_right, voice, start, 0.10 * (0.8 if i % 2 else 1.2), sr=sr)
        if intro:
            continue
        # Drums: kick on 1 and 3 (and the "and" of 3), snare on 2 and 4, eighth-note hats.
        for beat in range(4):
            t = start + beat * BEAT
            if not breakdown and beat in (0, 2):
                add(drums, kick(rng, sr), t, sr=sr)
            if not breakdown and beat == 2:
                add(drums, kick(rng, sr), t + BEAT / 2, 0.6, sr=sr)
            if not breakdown and beat in (1, 3):
                add(drums, snare(rng, sr), t, sr=sr)
            add(drums, hat(rng, sr, open_hat=beat == 3), t, 0.8, sr=sr)
            add(drums, hat(rng, sr), t + BEAT / 2, 0.5, sr=sr)
        if breakdown:
            continue
        # Bass: eighth notes on the root, octave jump on the last two, saw-like harmonics.
        for eighth in range(8):
            note = BASS_ROOTS[bar % 4] + (12 if eighth >= 6 else 0)
            sound = tone(midi_hz(note), BEAT / 2, sr=sr, harmonics=[1 / k for k in range(1, 9)])
            sound *= envelope(sound.shape[0], sr=sr, attack_s=0.005, release_s=0.03, decay_s=0.25)
            add(bass, sound, start + eighth * BEAT / 2, 0.22, sr=sr)
        # Lead in the second half: a quarter-note line with vibrato.
        if bar >= 8:
            for quarter in range(4):
                note = LEAD[(bar * 4 + quarter) % len(LEAD)]
                duration = BEAT * 0.95
                t = np.arange(int(duration * sr)) / sr
                vibrato = 1 + 0.004 * np.sin(2 * np.pi * 5.5 * t)
                phase = 2 * np.pi * np.cumsum(midi_hz(note) * vibrato) / sr
                sound = sum(np.sin(k * phase) / k for k in (1, 2, 3, 4))
                sound *= envelope(sound.shape[0], sr=sr, attack_s=0.02, release_s=0.08, decay_s=0.8)
                add(lead, sound, start + quarter * BEAT, 0.12, sr=sr)
    left = drums + bass + pads_left + 0.8 * lead
    right = drums + bass + pads_right + 1.0 * lead
    mix = np.stack([left, right], axis=1)
    fade = np.clip((duration_s - np.arange(n) / sr) / 2.0, 0.0, 1.0)  # 2 s fade-out
    mix *= fade[:, None]
    mix = np.tanh(1.5 * mix) / 1.5  # gentle saturation, like a bus compressor would
    # Low-pass at 0.8 of Nyquist (as a recording chain would), so the noise in the drums does
    # not pile up at Nyquist and make large inter-sample peaks.
    taps = np.sinc(0.8 * np.arange(-32, 33)) * np.kaiser(65, 8.0)
    taps /= taps.sum()
    mix = np.stack([np.convolve(mix[:, c], taps, mode="same") for c in range(2)], axis=1)
    mix *= 10 ** (-1.0 / 20) / np.max(np.abs(mix))  # peak at -1 dBFS
    return mix.astype(np.float32)


def main() -> int:
    sys.path.insert(0, os.path.join(REPO, "preprocess"))
    from loudscape_extract.song import extract_song

    os.chdir(REPO)  # so the metadata records the repo-relative path data/demo_song.flac
    os.makedirs("data", exist_ok=True)
    soundfile.write(WAV, synthesize(), SAMPLE_RATE, subtype="PCM_16")
    metadata = extract_song(WAV, PLY, floor_db=FLOOR_DB)
    size_mb = os.path.getsize(PLY) / 1e6
    print(f"{WAV}: {DURATION_S:.0f} s at {SAMPLE_RATE} Hz", file=sys.stderr)
    print(f"{PLY}: {metadata['point_count']} points, {size_mb:.2f} MB", file=sys.stderr)
    print(f"metrics: {metadata['metrics']}", file=sys.stderr)
    return 0 if size_mb <= 5.0 else 1


if __name__ == "__main__":
    sys.exit(main())
