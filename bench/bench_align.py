"""Alignment time on a pair of 4-minute songs (issue 34: under 2 s on the 2-core machine).

    .venv/bin/python bench/bench_align.py [--runs 5]

A 4-minute stereo track at 44.1 kHz is made from the real-music tracks (data/real-music, fetched
by scripts/fetch-real-music.sh), one after another; B is the same audio 0.731 s later, 4 dB
louder and clipped softly (a tanh limiter), with 2 s cut out at 2:00. Each run times
``align(A, B)`` alone (the decoded samples are in memory, as in ``compare``); the median, the
minimum and the maximum are printed with the load average, and the found offset and parts.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "preprocess"))

from loudscape_extract.align import align  # noqa: E402
from loudscape_extract.audio import decode_audio  # noqa: E402

TRACKS = [
    "torus-trooper-data/tt1.ogg",
    "rrootage-data/stg_a.ogg",
    "hex-a-hop-data/music-ending.ogg",
    "torus-trooper-data/tt3.ogg",
    "rrootage-data/stg_b.ogg",
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--music", default=os.path.join(REPO, "data", "real-music"))
    args = parser.parse_args()
    rate = 44100
    parts = []
    for name in TRACKS:
        audio = decode_audio(os.path.join(args.music, name))
        if audio.sample_rate != rate:
            continue
        x = audio.samples if audio.n_channels == 2 else np.repeat(audio.samples, 2, axis=1)
        parts.append(x)
    a = np.concatenate(parts)[: 240 * rate]
    if len(a) < 240 * rate:
        print(f"bench_align: only {len(a) / rate:.0f} s of music found", file=sys.stderr)
        return 1
    louder = np.tanh(a * 10 ** (4 / 20) * 1.2) / 1.2
    delayed = np.concatenate([np.zeros((int(0.731 * rate), 2), np.float32), louder])
    cut = 120 * rate
    b = np.concatenate([delayed[:cut], delayed[cut + 2 * rate :]]).astype(np.float32)
    times = []
    for _ in range(args.runs):
        start = time.perf_counter()
        result = align(a, b, rate)
        times.append(time.perf_counter() - start)
    print(
        f"align, two 4-minute songs: median {statistics.median(times):.2f} s, "
        f"min {min(times):.2f}, max {max(times):.2f} ({args.runs} runs, "
        f"load {os.getloadavg()[0]:.1f}); offset {result.offset_s:.4f} s, "
        f"{len(result.segments)} parts, confidence {result.confidence:.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
