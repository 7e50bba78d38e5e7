"""How hard each frequency band of a Song cloud stops at the noise floor (docs/FORMAT.md).

    python preprocess/scripts/floor_edge.py [FILE ...] [--floor-db 80] [--markdown]

For each file (and a synthesized quiet track: a -30 dBFS tone over hiss whose 4-22 kHz bins
sit at the floor) prints, per band, the floor edge ratio: the band's point density in the
1 dB just above the floor over its densest 1 dB within 40 dB of the floor (1 = a wall at its
densest level, as a hard floor made on quiet tracks; near 0 = it fades out).
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
BANDS = [(22.0, 86.0), (86.0, 350.0), (350.0, 1400.0), (1400.0, 4000.0), (4000.0, 22050.0)]


def quiet_track(*, seconds: float = 6.0, rate: int = 44100) -> np.ndarray:
    """A quiet synthesized track: a -30 dBFS 440 Hz tone and hiss 76 dB under its bin level."""
    rng = np.random.default_rng(12)
    t = np.arange(int(seconds * rate)) / rate
    tone = 0.0316 * np.sin(2 * np.pi * 440.0 * t) * (0.6 + 0.4 * np.sin(2 * np.pi * 0.5 * t))
    hiss = 8e-5 * rng.standard_normal(t.shape)
    return np.stack([tone + hiss, tone + hiss], axis=1).astype(np.float32)


def band_edges(cloud, frequencies_hz: np.ndarray) -> list[float]:
    """:func:`floor_edge_ratio` of each band in :data:`BANDS` for a linear-frequency cloud."""
    from loudscape_extract.floor import floor_edge_ratio

    y_axis = cloud.axes["y"]
    y_min, y_max = y_axis["min"], y_axis["max"]
    levels = y_min + (cloud.points[:, 1].astype(np.float64) + 1.0) * 0.5 * (y_max - y_min)
    freq = (cloud.points[:, 2].astype(np.float64) + 1.0) * 0.5 * frequencies_hz[-1]
    return [floor_edge_ratio(levels[(freq >= lo) & (freq < hi)], y_min=y_min) for lo, hi in BANDS]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="*")
    parser.add_argument("--floor-db", type=float, default=80.0)
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(REPO, "preprocess"))
    from loudscape_extract import decode_audio, track_features
    from loudscape_extract.audio import Audio
    from loudscape_extract.points import song_points

    rows = []
    sources = [("synthesized quiet track", None)] + [(path, path) for path in args.inputs]
    for name, path in sources:
        if path is None:
            samples = quiet_track()
            audio = Audio(path="quiet", samples=samples, sample_rate=44100)
        else:
            audio = decode_audio(path)
        features = track_features(audio)
        cloud = song_points(features, floor_db=args.floor_db)
        rows.append((name, cloud.peak_level_db, band_edges(cloud, features.frequencies_hz)))
    header = ["file", "peak bin dB"] + [f"{lo:g}-{hi:g} Hz" for lo, hi in BANDS]
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
    for name, peak, edges in rows:
        cells = [name, f"{peak:.1f}"] + [f"{edge:.2f}" for edge in edges]
        print(("| " + " | ".join(cells) + " |") if args.markdown else "  ".join(cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
