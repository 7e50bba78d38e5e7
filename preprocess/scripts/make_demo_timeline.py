"""Synthesize twenty demo songs, 1970s to 2010s, and build data/demo_timeline.ply from them.

    python preprocess/scripts/make_demo_timeline.py [--report docs/images/report_demo.png]

Deterministic (numpy, fixed seeds). Four songs per decade, two in each of two years (1973,
1977, 1983, ... 2017), 20 s at 22.05 kHz, built from the demo song's instruments
(make_demo_song.py). One parameter, ``modern = (year - 1970) / 50``, moves each mix along
the loudness war:

- arrangement: sparse (pads, kick, snare, eighth hats) -> dense (doubled pads, sixteenth hats,
  a distorted saw layer, busier bass);
- dynamics: quiet verses and loud choruses (-12 dB apart) -> every section at the same level;
- mastering: gentle saturation peaking at -3 dBFS -> heavy saturation, then a hard limiter,
  peaking at -0.1 dBFS.

The songs are written as tagged FLAC files (year, title, artist) in a temporary folder and go
through the real ``timeline`` pipeline (tags read with mutagen, no manifest), with 400 frames
per song (of about 430) and ``--x-by year``. Song paths in the metadata are recorded as
``songs/<file>.flac``.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

import numpy as np
import soundfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
PLY = os.path.join("data", "demo_timeline.ply")
SAMPLE_RATE = 22050
DURATION_S = 20.0
FRAMES_PER_SONG = 400
YEARS = tuple(decade + offset for decade in range(1970, 2020, 10) for offset in (3, 3, 7, 7))
ARTISTS = ("Demo Band A", "Demo Band B")

sys.path.insert(0, HERE)
import make_demo_song as demo  # noqa: E402


def synthesize_year(year: int, variant: int, *, sr: int = SAMPLE_RATE, duration_s=DURATION_S):
    """One demo song whose mix and master follow the year (see the module docstring).

    Returns
    -------
    samples : np.ndarray [shape=(n_samples, 2), dtype=float32]
    """
    modern = float(np.clip((year - 1970) / 50.0, 0.0, 1.0))
    rng = np.random.default_rng(year * 10 + variant)
    n = int(duration_s * sr)
    beat = 60.0 / (100.0 + 8 * variant + 12 * modern)
    bar = 4 * beat
    drums, bass, pads_l, pads_r, layer = (np.zeros(n) for _ in range(5))
    n_bars = int(np.ceil(duration_s / bar))
    section_gain = np.ones(n)
    shift = [0, 2, -3][variant % 3]
    for b in range(n_bars):
        start = b * bar
        chord = [note + shift for note in demo.CHORDS[(b + variant) % 4]]
        chorus = (b // 2) % 2 == 1
        # Section dynamics: verses quieter than choruses, less so as the years go on.
        verse_db = -12.0 * (1 - modern) - 1.0
        i0, i1 = int(start * sr), min(n, int((start + bar) * sr))
        section_gain[i0:i1] = 1.0 if chorus else 10 ** (verse_db / 20)
        voices = chord + ([note + 12 for note in chord] if modern > 0.35 else [])
        for i, note in enumerate(voices):
            harmonics = [1 / k ** (2.0 - modern) for k in range(1, 7)]
            voice = demo.tone(demo.midi_hz(note), bar, sr=sr, harmonics=harmonics, detune=0.002 * i)
            voice *= demo.envelope(voice.shape[0], sr=sr, attack_s=0.1, release_s=0.3)
            demo.add(pads_l, voice, start, 0.08 * (1.2 if i % 2 else 0.8), sr=sr)
            demo.add(pads_r, voice, start, 0.08 * (0.8 if i % 2 else 1.2), sr=sr)
        hats_per_beat = 4 if modern > 0.5 else 2
        for q in range(4):
            t = start + q * beat
            if q in (0, 2) or (modern > 0.6 and q == 3):
                demo.add(drums, demo.kick(rng, sr), t, 1.0, sr=sr)
            if q in (1, 3):
                demo.add(drums, demo.snare(rng, sr), t, 0.9, sr=sr)
            for h in range(hats_per_beat):
                gain = (0.6 if h == 0 else 0.35) * (0.5 + 0.5 * modern)
                demo.add(drums, demo.hat(rng, sr), t + h * beat / hats_per_beat, gain, sr=sr)
        notes = 8 if modern < 0.5 else 16
        for k in range(notes):
            root = demo.BASS_ROOTS[(b + variant) % 4] + shift + (12 if k % 4 == 3 else 0)
            length = bar / notes
            sound = demo.tone(
                demo.midi_hz(root), length, sr=sr, harmonics=[1 / j for j in range(1, 9)]
            )
            sound *= demo.envelope(sound.shape[0], sr=sr, attack_s=0.005, release_s=0.02)
            demo.add(bass, sound, start + k * length, 0.2, sr=sr)
        if modern > 0.4 and chorus:
            # A distorted saw layer (a wall of guitars/synths) in the choruses.
            for note in chord[:3]:
                saw = demo.tone(
                    demo.midi_hz(note - 12), bar, sr=sr, harmonics=[1 / j for j in range(1, 16)]
                )
                demo.add(layer, np.tanh(3 * saw) * 0.06 * modern, start, sr=sr)
    left = drums * (1.4 - 0.5 * modern) + bass + pads_l + layer
    right = drums * (1.4 - 0.5 * modern) + bass + pads_r + layer
    mix = np.stack([left, right], axis=1) * section_gain[:, None]
    fade = np.clip((duration_s - np.arange(n) / sr) / 1.5, 0.0, 1.0)
    mix *= fade[:, None]
    mix /= np.max(np.abs(mix))
    # Mastering: saturation, then a hard limiter whose ceiling drops with the years.
    drive = 1.0 + 9.0 * modern**1.5
    mix = np.tanh(drive * mix) / np.tanh(drive)
    ceiling = 1.0 - 0.6 * modern
    mix = np.clip(mix, -ceiling, ceiling) / ceiling
    taps = np.sinc(0.8 * np.arange(-32, 33)) * np.kaiser(65, 8.0)
    taps /= taps.sum()
    mix = np.stack([np.convolve(mix[:, c], taps, mode="same") for c in range(2)], axis=1)
    peak_db = -3.0 + 2.9 * modern
    mix *= 10 ** (peak_db / 20) / np.max(np.abs(mix))
    return mix.astype(np.float32)


def write_songs(folder: str) -> list[str]:
    """Write the twenty tagged FLAC songs into ``folder``; returns their paths."""
    import mutagen.flac

    os.makedirs(folder, exist_ok=True)
    paths = []
    for i, year in enumerate(YEARS):
        variant = i % 2
        path = os.path.join(folder, f"{year}_{variant}.flac")
        soundfile.write(path, synthesize_year(year, variant), SAMPLE_RATE, subtype="PCM_16")
        tags = mutagen.flac.FLAC(path)
        tags["date"] = str(year)
        tags["title"] = f"Demo {year}"
        tags["artist"] = ARTISTS[variant]
        tags.save()
        paths.append(path)
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--report", help="also render the report PNG here (repo-relative)")
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(REPO, "preprocess"))
    from loudscape_extract.timeline import build_timeline

    output = os.path.join(REPO, PLY)
    os.makedirs(os.path.dirname(output), exist_ok=True)
    previous = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="loudscape-demo-") as scratch:
        os.chdir(scratch)  # so the metadata records songs/<file>.flac
        try:
            write_songs("songs")
            result = build_timeline(
                ["songs"],
                output,
                frames_per_song=FRAMES_PER_SONG,
                x_by="year",
                cache_dir=None,
                jobs=os.cpu_count() or 1,
            )
        finally:
            os.chdir(previous)
    size_mb = os.path.getsize(output) / 1e6
    print(f"{PLY}: {result.metadata['point_count']} points, {size_mb:.2f} MB", file=sys.stderr)
    for song in result.metadata["songs"]:
        m = song["metrics"]
        print(
            f"  {song['year']} {song['artist']:<18} {m['integrated_lufs']:6.1f} LUFS  "
            f"crest {m['crest_median_db']:5.1f} dB  LRA {m['lra_lu']:4.1f} LU  "
            f"PLR {m['plr_db']:5.1f} dB  DR {m['dr_db']:4.1f} dB  "
            f"PSR {m['psr_median_db']:4.1f} dB  hp {m['hp_mean']:.2f}",
            file=sys.stderr,
        )
    if args.report:
        from loudscape_extract.report import write_report

        write_report(output, os.path.join(REPO, args.report))
        print(f"{args.report}: written", file=sys.stderr)
    return 0 if size_mb <= 3.0 and not result.failed else 1


if __name__ == "__main__":
    sys.exit(main())
