"""The compression ladder of docs/DYNAMICS.md: dynamic material through a real compressor and
limiter (pedalboard) at increasing amounts, measured by every dynamics measure.

    python preprocess/scripts/compression_ladder.py [REAL.wav|ogg ...] [--markdown]

Material: the demo timeline's most dynamic synthesized song (1973: quiet verses, loud
choruses) and each file given (the docs use the real-music tracks of
scripts/fetch-real-music.sh). Rung 0 is the material peak-normalized to -1 dBFS; rung k
goes through a compressor (threshold -20 dB, ratio 1 + k/2, attack 10 ms, release 150 ms),
4k dB of gain into a limiter (threshold -1 dB, release 100 ms), and is peak-normalized to
-1 dBFS again, as a master would be. Nothing is tuned per measure.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
RUNGS = 6


def rung(samples: np.ndarray, rate: int, k: int) -> np.ndarray:
    from pedalboard import Compressor, Gain, Limiter, Pedalboard

    x = samples * (10 ** (-1 / 20) / np.max(np.abs(samples)))
    if k == 0:
        return x.astype(np.float32)
    board = Pedalboard(
        [
            Compressor(threshold_db=-20.0, ratio=1.0 + 0.5 * k, attack_ms=10.0, release_ms=150.0),
            Gain(gain_db=4.0 * k),
            Limiter(threshold_db=-1.0, release_ms=100.0),
        ]
    )
    y = board(x.T.astype(np.float32), rate).T
    return (y * (10 ** (-1 / 20) / np.max(np.abs(y)))).astype(np.float32)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="*", help="real recordings to add to the ladder")
    parser.add_argument("--markdown", action="store_true", help="print Markdown tables")
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(REPO, "preprocess"))
    sys.path.insert(0, HERE)
    from make_demo_timeline import SAMPLE_RATE, synthesize_year

    from loudscape_extract import Audio, decode_audio, track_features
    from loudscape_extract.timeline import SongEntry, frames_of, timeline_points

    materials = [("synthesized (demo 1973)", synthesize_year(1973, 0), SAMPLE_RATE)]
    for path in args.files:
        audio = decode_audio(path)
        materials.append((os.path.basename(path), audio.samples, audio.sample_rate))
    keys = [
        ("integrated_lufs", "LUFS"),
        ("psr_median_db", "PSR"),
        ("dr_db", "DR"),
        ("plr_db", "PLR"),
        ("lra_lu", "LRA"),
        ("crest_3s_median_db", "crest 3 s"),
        ("crest_median_db", "crest frame"),
    ]
    all_ok = True
    for name, samples, rate in materials:
        songs, rows = {}, []
        for k in range(RUNGS):
            audio = Audio(samples=rung(samples, rate, k), sample_rate=rate, path=f"rung{k}")
            songs[f"rung{k}"] = frames_of(track_features(audio))
        for measure in ("psr", "crest-3s", "crest-frame"):
            entries = [SongEntry(f"rung{k}", 2000 + k) for k in range(RUNGS)]
            points, layout = timeline_points(
                entries, songs, frames_per_song=512, x_by="order", z_measure=measure
            )
            for k, song in enumerate(layout["songs"]):
                block = points[song["point_offset"] : song["point_offset"] + song["point_count"]]
                if measure == "psr":
                    rows.append(
                        {"rung": k, **{key: songs[f"rung{k}"].metrics[key] for key, _ in keys}}
                    )
                rows[k][f"z {measure}"] = float(np.median(block[:, 2]))
        columns = [label for _, label in keys] + ["z psr", "z crest-3s", "z crest-frame"]
        print(f"\n{name}\n")
        if args.markdown:
            print("| rung | " + " | ".join(columns) + " |")
            print("|---" * (len(columns) + 1) + "|")
        for row in rows:
            values = [row[key] for key, _ in keys] + [row[c] for c in columns[len(keys) :]]
            cells = [
                f"{v:.2f}" if c.startswith("z ") else f"{v:.1f}"
                for v, c in zip(values, columns, strict=True)
            ]
            line = " | ".join([str(row["rung"])] + cells)
            print(f"| {line} |" if args.markdown else line)
        loud = [r["integrated_lufs"] for r in rows]
        verdicts = []
        for key, label in keys[1:] + [(c, c) for c in columns[len(keys) :]]:
            values = [r[key] for r in rows]
            falls = all(b < a for a, b in zip(values, values[1:], strict=False))
            verdicts.append(f"{label}: {'falls' if falls else 'NOT monotonic'}")
        rises = all(b > a for a, b in zip(loud, loud[1:], strict=False))
        all_ok &= rises
        print(
            f"\nloudness {'rises' if rises else 'does NOT rise'} monotonically; "
            + "; ".join(verdicts)
        )
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
