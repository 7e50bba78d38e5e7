"""HPSS's running median: the compiled kernel (crates/median) against scipy's, on a real song.

    .venv/bin/python bench/bench_median.py [--runs 5]

The magnitude spectrogram (n_fft 2048, hop 1024: 1025 x 9044 float32) of the 3:30 track of
bench/peers_extract.py (made once under ``out/peers/`` from data/real-music, ``make
real-music``), median-filtered with a 31-long window along time (axis 1, HPSS's harmonic
estimate) and along frequency (axis 0, the percussive one) by
``loudscape_extract.median_filter_axis``: with the compiled kernel, then with it turned off
(scipy.ndimage's 1-D running median on the bits, the fallback). The two answers are checked to
be the same bits. Medians of ``--runs`` calls, wall and CPU; nanoseconds per median. Not a test.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peers_extract import MUSIC, OUT, SONG_PARTS, make_song  # noqa: E402

from loudscape_extract import median_filter_axis, native, stft_magnitude  # noqa: E402
from loudscape_extract.audio import decode_audio  # noqa: E402


def timed(data: np.ndarray, axis: int, runs: int) -> tuple[np.ndarray, list[float], list[float]]:
    walls, cpus = [], []
    for _ in range(runs):
        wall, cpu = time.perf_counter(), time.process_time()
        result = median_filter_axis(data, size=31, axis=axis)
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return result, walls, cpus


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    if not native.available():
        print("bench_median: the compiled running median is not built (make native)")
        return 1
    if any(not os.path.isfile(os.path.join(MUSIC, part)) for part in SONG_PARTS):
        print(f"bench_median: {MUSIC} is incomplete (make real-music)")
        return 1
    os.makedirs(OUT, exist_ok=True)
    song = os.path.join(OUT, "track-3m30.ogg")
    if not os.path.isfile(song):
        make_song(song)
    audio = decode_audio(song)
    mono = audio.samples.mean(axis=1, dtype=np.float32)
    magnitude = stft_magnitude(mono, n_fft=2048, hop_length=1024)
    print(f"{os.path.basename(song)}: magnitude {magnitude.shape} {magnitude.dtype}, size 31")
    print(f"kernel: {native.library_path()}")
    for axis, name in ((1, "along time (axis 1)"), (0, "along frequency (axis 0)")):
        ours, walls, cpus = timed(magnitude, axis, args.runs)
        native._library, native._loaded = None, True  # the fallback
        try:
            theirs, scipy_walls, scipy_cpus = timed(magnitude, axis, args.runs)
        finally:
            native._loaded = False
            native._load()
        assert np.array_equal(ours.view(np.uint32), theirs.view(np.uint32)), axis
        per = 1e9 / magnitude.size
        kernel, scipy = statistics.median(cpus), statistics.median(scipy_cpus)
        print(
            f"{name}: kernel {statistics.median(walls):.3f} s wall, {kernel:.3f} CPU-s "
            f"({kernel * per:.1f} ns a median); scipy {statistics.median(scipy_walls):.3f} s "
            f"wall, {scipy:.3f} CPU-s ({scipy * per:.1f} ns); {scipy / kernel:.1f}x"
        )
    print(f"same bits; 1-minute load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
