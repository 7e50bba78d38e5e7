"""The EBU Tech 3341 / 3342 conformance table of docs/DYNAMICS.md, from the same cases and the
same meter the test suite checks (loudscape_extract.conformance).

    .venv/bin/python preprocess/scripts/ebu_conformance.py

Prints a Markdown table (case, signal, expected with tolerance, our reading: the one value,
or the lowest and highest of a case's several readings, and whether every reading is within
the tolerance), then what the 100 ms grid alone reads for cases 10 and 13, and what the
any-position maxima cost the streamed extraction of a 3-minute stereo 44.1 kHz track.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from loudscape_extract.conformance import CASES, RATE, run_case, tone_sequence
from loudscape_extract.loudness import (
    WindowMaxima,
    block_loudness,
    short_term_loudness,
    weighted_power,
)


def _reading(values: list[float]) -> str:
    low, high = min(values), max(values)
    if round(low, 2) == round(high, 2):
        return f"{low:+.2f}"
    return f"{low:+.2f} .. {high:+.2f} ({len(values)} readings)"


def _grid_line(label: str, window, parts_of) -> str:
    """The lowest maximum over the 20 files when only the 100 ms grid's windows count."""
    maxima = [
        float(np.max(window(tone_sequence(parts_of(i)), sample_rate=RATE))) for i in range(20)
    ]
    out = sum(abs(m + 23.0) > 0.1 for m in maxima)
    return (
        f"- {label} on the 100 ms grid alone: {min(maxima):+.2f} .. {max(maxima):+.2f} LUFS, "
        f"{out} of 20 files out of tolerance"
    )


def main() -> int:
    print("| case | signal | expected | our reading | within |")
    print("|---|---|---|---|---|")
    all_ok = True
    for case in CASES:
        results = run_case(case)
        ok = all(passed for _, passed in results)
        all_ok &= ok
        values = [reading.value for reading, _ in results]
        print(
            f"| {case.name} | {case.signal} | {case.expected} | {_reading(values)} | "
            f"{'yes' if ok else 'NO'} |"
        )
    print()
    print(
        _grid_line(
            "3341-10 (max S)",
            short_term_loudness,
            lambda i: [(None, i * 0.15), (-23.0, 3.0), (None, 1.0)],
        )
    )
    print(
        _grid_line(
            "3341-13 (max M)",
            block_loudness,
            lambda i: [(None, i * 0.02), (-23.0, 0.4), (None, 1.0)],
        )
    )
    print(_cost_line())
    return 0 if all_ok else 1


def _cost_line() -> str:
    """Time of the maxima's share of the signal pass: weighted power and running sums over
    3 minutes of K-weighted stereo at 44.1 kHz, fed in the pass's 2^20-sample blocks."""
    rate, n, block = 44100, 44100 * 180, 1 << 20
    filtered = (np.random.default_rng(0).standard_normal((2, n)) * 0.1).astype(np.float32)
    times = []
    for _ in range(3):
        start = time.perf_counter()
        maxima = WindowMaxima(sample_rate=rate)
        for first in range(0, n, block):
            maxima.feed(weighted_power(filtered[:, first : first + block], np.ones(2)))
        times.append(time.perf_counter() - start)
    return (
        f"- cost of the any-position maxima, 3 min stereo 44.1 kHz: {min(times):.2f} s (best of 3)"
    )


if __name__ == "__main__":
    sys.exit(main())
