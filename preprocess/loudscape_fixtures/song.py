"""Regenerate the small Song-mode fixture the Rust reader's tests use.

    python -m loudscape_fixtures.song [--out-dir data]

writes ``fixture_song.ply`` (the real extractor run on a short synthesized signal) and
``fixture_song.expected.json`` (point count, first and last three records, per-column sums in
float64, and the full metadata object). The signal: 0.5 s stereo at 8 kHz, 100 ms of digital
silence (dropped frames), then a decaying 500 Hz tone with a second harmonic and two clicks.
Extraction: n_fft 64, hop 64, floor 40 dB, linear frequency. ``source.path`` is recorded as
``data/fixture_song.wav`` (the path given on the command line, relative to the repo root);
the wav itself is not kept.

The file is written in format version 2, which the app reads (``--format-version 1`` for the
older layout); ``loudscape_fixtures.formats`` writes the fixtures of both versions in
tests/fixtures/format/.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile

import numpy as np
import soundfile

from loudscape_extract.ply import read_ply, write_ply
from loudscape_extract.song import extract_song

FIXTURE_STEM = "fixture_song"
SAMPLE_RATE = 8000
N_FFT = 64
HOP = 64
FLOOR_DB = 40.0
FORMAT_VERSION = 2


def fixture_signal() -> np.ndarray:
    """The fixture's audio.

    Returns
    -------
    samples : np.ndarray [shape=(4000, 2), dtype=float32]
    """
    n = SAMPLE_RATE // 2
    t = np.arange(n) / SAMPLE_RATE
    tone = 0.5 * np.sin(2 * np.pi * 500 * t) + 0.15 * np.sin(2 * np.pi * 1000 * t)
    tone *= np.exp(-3.0 * t)
    for click in (0.2, 0.35):
        tone[int(click * SAMPLE_RATE)] += 0.8
    tone[: SAMPLE_RATE // 10] = 0.0
    left = tone
    right = 0.7 * tone
    return np.stack([left, right], axis=1).astype(np.float32)


@contextlib.contextmanager
def _working_directory(path: str):
    previous = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(previous)


def expected_values(points: np.ndarray, metadata: dict) -> dict:
    """What the Rust reader's tests check: count, first/last 3 records, column sums."""
    return {
        "point_count": int(points.shape[0]),
        "first_records": [[float(v) for v in row] for row in points[:3]],
        "last_records": [[float(v) for v in row] for row in points[-3:]],
        "column_sums": [float(v) for v in points.astype(np.float64).sum(axis=0)],
        "metadata": metadata,
    }


def write_fixture(out_dir: str, *, format_version: int = FORMAT_VERSION) -> tuple[str, str]:
    """Write ``fixture_song.ply`` and ``fixture_song.expected.json`` into ``out_dir``.

    Returns
    -------
    paths : tuple of str
        The PLY and JSON paths.
    """
    out_dir = os.path.abspath(out_dir)
    ply_path = os.path.join(out_dir, FIXTURE_STEM + ".ply")
    json_path = os.path.join(out_dir, FIXTURE_STEM + ".expected.json")
    with tempfile.TemporaryDirectory() as scratch:
        os.makedirs(os.path.join(scratch, "data"))
        relative = os.path.join("data", FIXTURE_STEM + ".wav")
        soundfile.write(os.path.join(scratch, relative), fixture_signal(), SAMPLE_RATE, "FLOAT")
        with _working_directory(scratch):
            extract_song(relative, ply_path, n_fft=N_FFT, hop_length=HOP, floor_db=FLOOR_DB)
    points, metadata = read_ply(ply_path)
    write_ply(ply_path, points=points, metadata=metadata, format_version=format_version)
    points, metadata = read_ply(ply_path)
    with open(json_path, "w", encoding="ascii") as handle:
        json.dump(expected_values(points, metadata), handle, indent=1)
        handle.write("\n")
    return ply_path, json_path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default="data", help="where to write (default: data)")
    parser.add_argument(
        "--format-version", type=int, choices=(1, 2), default=FORMAT_VERSION, help="(2)"
    )
    args = parser.parse_args(argv)
    for path in write_fixture(args.out_dir, format_version=args.format_version):
        print(path, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
