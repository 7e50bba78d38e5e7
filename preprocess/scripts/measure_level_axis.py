"""Which per-frame level ranks songs like their integrated loudness (docs/DYNAMICS.md, "The
level axis").

    .venv/bin/python preprocess/scripts/measure_level_axis.py data/real-music

For every .ogg, .flac and .wav under the folders: the song's integrated loudness and, for each
timeline y measure, the energy mean and the median of its 1024 drawn frames; then the Spearman
rank correlation of each summary with integrated loudness over the songs.
"""

from __future__ import annotations

import argparse
import glob
import os

import numpy as np
from scipy.stats import spearmanr

from loudscape_extract.timeline import Y_MEASURES, compute_song_frames, sample_song


def _files(folders):
    found = []
    for folder in folders:
        for extension in ("ogg", "flac", "wav"):
            found += glob.glob(os.path.join(folder, "**", f"*.{extension}"), recursive=True)
    return sorted(found)


def measure(folders, *, frames_per_song=1024):
    """One dict per song: ``file``, ``lufs`` and ``(energy mean, median)`` per y measure."""
    rows = []
    for path in _files(folders):
        song = compute_song_frames(path, n_fft=2048, hop_length=1024)
        drawn = sample_song(song, frames_per_song=frames_per_song, z_measure="psr")
        row = {"file": path, "lufs": song.metrics["integrated_lufs"]}
        for name in Y_MEASURES:
            level = drawn.level(name).astype(float)
            level = level[np.isfinite(level)]
            row[name] = (10 * np.log10(np.mean(10 ** (level / 10))), float(np.median(level)))
        rows.append(row)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args()
    rows = measure(args.folders)
    for row in rows:
        cells = "  ".join(f"{m} {row[m][0]:6.1f} {row[m][1]:6.1f}" for m in Y_MEASURES)
        print(f"{row['lufs']:6.1f} LUFS  {cells}  {row['file']}")
    lufs = [row["lufs"] for row in rows]
    for name in Y_MEASURES:
        energy = spearmanr(lufs, [row[name][0] for row in rows])[0]
        median = spearmanr(lufs, [row[name][1] for row in rows])[0]
        print(
            f"{name}: rank correlation with LUFS: energy mean {energy:+.3f}, median {median:+.3f}"
        )


if __name__ == "__main__":
    main()
