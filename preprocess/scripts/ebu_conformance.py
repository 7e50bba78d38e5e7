"""The EBU Tech 3341 / 3342 conformance table of docs/DYNAMICS.md, from the same cases and the
same meter the test suite checks (loudscape_extract.conformance).

    .venv/bin/python preprocess/scripts/ebu_conformance.py

Prints a Markdown table (case, signal, expected with tolerance, our reading: the one value,
or the lowest and highest of a case's several readings, and whether every reading is within
the tolerance), then what the 100 ms grid alone reads for cases 10 and 13.
"""

from __future__ import annotations

import sys

import numpy as np

from loudscape_extract.conformance import CASES, RATE, run_case, tone_sequence
from loudscape_extract.loudness import block_loudness, short_term_loudness


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
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
