"""Time to the first Song-mode points and to the finished file, as a program reading
``--progress json`` sees them (issue 27: points while extracting).

    .venv/bin/python bench/bench_points_stream.py TRACK [TRACK ...] [--runs 5] [--code DIR]

Each run starts ``python -m loudscape_extract.cli song TRACK -o OUT --progress json`` as a child
process and stamps, from its start, the first stdout line carrying ``points`` and the ``done``
line. An extractor without the points lines (``--code DIR``: the ``preprocess`` folder of an
older checkout) has its first points only in the finished file: "first points" is its done
time then. With ``--code`` the two extractors run in turn (A B A B ...); medians are printed.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def one_run(track: str, code: str, out: str) -> tuple[float, float]:
    """(seconds to the first points line or the done line, seconds to done) of one child."""
    env = dict(os.environ, PYTHONPATH=code)
    command = [sys.executable, "-m", "loudscape_extract.cli", "song", track, "-o", out, "-q"]
    start = time.perf_counter()
    child = subprocess.Popen(
        [*command, "--progress", "json"], stdout=subprocess.PIPE, text=True, env=env
    )
    first = done = None
    for line in child.stdout:
        record = json.loads(line)
        now = time.perf_counter() - start
        if "points" in record and first is None:
            first = now
        if "done" in record:
            done = now
    if child.wait() != 0 or done is None:
        raise SystemExit(f"{track}: the extractor failed")
    return (done if first is None else first), done


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("tracks", nargs="+")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--code", help="another extractor's preprocess folder, run in turn")
    args = parser.parse_args()
    codes = {"this": os.path.join(REPO, "preprocess")}
    if args.code:
        codes["other"] = os.path.abspath(args.code)
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "out.ply")
        for track in args.tracks:
            times = {name: [] for name in codes}
            for _ in range(args.runs):
                for name, code in codes.items():
                    times[name].append(one_run(track, code, out))
            for name, runs in times.items():
                first = statistics.median(t[0] for t in runs)
                done = statistics.median(t[1] for t in runs)
                print(
                    f"{os.path.basename(track)} {name}: first points {first:.2f} s, "
                    f"done {done:.2f} s (median of {len(runs)}; first "
                    f"{', '.join(f'{t[0]:.2f}' for t in runs)})"
                )


if __name__ == "__main__":
    main()
