"""Every dynamics measure of the given recordings, and how each ranks them (docs/DYNAMICS.md).

    python preprocess/scripts/measure_dynamics.py FILE_OR_FOLDER ... [--markdown]

Prints one row per file and the Spearman rank correlation of each measure with the TT DR
value and with LRA (scipy's spearmanr).
"""

from __future__ import annotations

import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
KEYS = [
    ("integrated_lufs", "LUFS"),
    ("lra_lu", "LRA"),
    ("plr_db", "PLR"),
    ("dr_db", "DR"),
    ("psr_median_db", "PSR"),
    ("psr_spread_db", "PSR p90-p10"),
    ("crest_3s_median_db", "crest 3 s"),
    ("crest_median_db", "crest frame"),
    ("dc_offset", "DC"),
]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="+")
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args(argv)
    sys.path.insert(0, os.path.join(REPO, "preprocess"))
    from scipy.stats import spearmanr

    from loudscape_extract import decode_audio, track_features
    from loudscape_extract.timeline import discover_audio

    rows = []
    for path in discover_audio(args.inputs):
        metrics = track_features(decode_audio(path)).metrics
        rows.append((os.path.relpath(path), metrics))
    header = ["file"] + [label for _, label in KEYS]
    print("| " + " | ".join(header) + " |" if args.markdown else "  ".join(header))
    if args.markdown:
        print("|---" * len(header) + "|")
    for path, m in rows:
        cells = [path] + [
            "-" if m[k] is None else (f"{m[k]:.3f}" if k == "dc_offset" else f"{m[k]:.1f}")
            for k, _ in KEYS
        ]
        print("| " + " | ".join(cells) + " |" if args.markdown else "  ".join(cells))
    print()
    for reference in ("dr_db", "lra_lu"):
        for key, label in KEYS[:-1]:
            if key == reference:
                continue
            pairs = [(m[key], m[reference]) for _, m in rows if None not in (m[key], m[reference])]
            rho = spearmanr(*zip(*pairs, strict=True)).statistic
            print(f"rank correlation of {label} with {reference}: {rho:+.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
