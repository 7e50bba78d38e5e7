"""Benchmark timelines of many short synthesized songs (``make bench-timeline``).

    .venv/bin/python bench/bench_timeline.py [--cold-songs 1000] [--warm-songs 10000] [--runs 3]

1. Writes ``--warm-songs`` short songs (4 s, 8 kHz mono 16-bit WAV: a chord with a random
   root, a bass line and clicks, a random gain) and a manifest (path, year 1960-2020) under
   ``out/bench-timeline/`` (kept between runs; regenerated when missing). Only ``--distinct``
   (1,000) are distinct recordings; the others are byte-for-byte copies under their own names
   and years, so filling the cache computes 1,000 songs while a rebuild still hashes, reads,
   samples and lays out every one of the 10,000.
2. Cold: the first ``--cold-songs`` of them, empty cache, ``--jobs 2`` with the process pool
   and with ``--dask`` (a two-worker LocalCluster); ``--runs`` runs each.
3. Warm: all ``--warm-songs`` songs rebuilt from a filled cache (filled once, not timed),
   ``--runs`` runs. The last warm run's file is kept: ``out/bench-timeline/timeline_10000.ply``.

Each run is ``loudscape-extract timeline --manifest ... --quiet`` as a child process, timed end
to end (interpreter start, imports, reading the manifest, hashing, cache reads or extraction,
layout, write); medians are printed with the commands. Not a test.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import sys
import time

import numpy as np
import soundfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_song import run_child  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
OUT = os.path.join(REPO, "out", "bench-timeline")
RATE = 8000
DURATION_S = 4.0


def synth_song(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = int(DURATION_S * RATE)
    t = np.arange(n) / RATE
    root = 110.0 * 2 ** (rng.integers(0, 12) / 12)
    y = np.zeros(n)
    for ratio in (1.0, 1.26, 1.5, 2.0):
        y += 0.12 * np.sin(2 * np.pi * root * ratio * t)
    y += 0.2 * np.sin(2 * np.pi * root / 2 * t) * (1 + np.sin(2 * np.pi * 0.5 * t)) / 2
    for start in np.arange(0, DURATION_S, 60.0 / rng.integers(80, 160)):
        i = int(start * RATE)
        length = min(300, n - i)
        y[i : i + length] += 0.6 * rng.standard_normal(length) * np.exp(-np.arange(length) / 50)
    return (y * rng.uniform(0.2, 0.9) / max(1.0, np.abs(y).max())).astype(np.float32)


def make_library(count: int, distinct: int) -> str:
    """``count`` songs and a manifest; returns the manifest path. Song ``i`` is the recording
    ``i % distinct`` (byte for byte, so one cache entry serves its copies)."""
    songs = os.path.join(OUT, "songs")
    os.makedirs(songs, exist_ok=True)
    manifest = os.path.join(OUT, f"manifest_{count}.csv")
    years = np.random.default_rng(0).integers(1960, 2021, count)
    lines = ["path,year,title,artist"]
    for i in range(count):
        name = f"song{i:05d}.wav"
        path = os.path.join(songs, name)
        if i < distinct:
            if not os.path.exists(path):
                soundfile.write(path, synth_song(i), RATE, subtype="PCM_16")
        else:
            shutil.copyfile(os.path.join(songs, f"song{i % distinct:05d}.wav"), path)
        lines.append(f"songs/{name},{years[i]},Song {i},Artist {i % 97}")
    with open(manifest, "w") as handle:
        handle.write("\n".join(lines) + "\n")
    return manifest


def timeline(manifest: str, output: str, cache: str, *extra: str) -> tuple[float, float]:
    executable = os.path.join(os.path.dirname(sys.executable), "loudscape-extract")
    command = [executable, "timeline", "--manifest", manifest, "-o", output, "--quiet"]
    wall, rss, _, _ = run_child([*command, "--cache-dir", cache, "--jobs", "2", *extra])
    return wall, rss


def report(label: str, command: str, runs: list[tuple[float, float]]) -> None:
    walls = [w for w, _ in runs]
    print(f"{label}\n  command: {command}")
    print(
        f"  runs {', '.join(f'{w:.1f}' for w in walls)} s; median {statistics.median(walls):.1f}"
        f" s; peak RSS median {statistics.median(r for _, r in runs):.0f} MiB",
        flush=True,
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cold-songs", type=int, default=1000)
    parser.add_argument("--warm-songs", type=int, default=10000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument(
        "--distinct",
        type=int,
        default=1000,
        help="distinct recordings; the others are copies under other names and years (the "
        "warm rebuild does the same work per song; filling the cache computes only these)",
    )
    parser.add_argument("--skip-pool", action="store_true", help="cold runs with Dask only")
    parser.add_argument("--skip-cold", action="store_true")
    args = parser.parse_args()
    start = time.perf_counter()
    distinct = max(args.distinct, args.cold_songs)
    warm_manifest = make_library(max(args.warm_songs, args.cold_songs), distinct)
    cold_manifest = make_library(args.cold_songs, distinct)
    print(
        f"{args.warm_songs} songs ({distinct} distinct recordings) of {DURATION_S:g} s "
        f"({RATE} Hz mono WAV) ready in "
        f"{time.perf_counter() - start:.0f} s; {os.cpu_count()} CPUs; python "
        f"{platform.python_version()}; load average {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    scratch = os.path.join(OUT, "scratch")
    os.makedirs(scratch, exist_ok=True)
    output = os.path.join(scratch, "cold.ply")
    if not args.skip_cold:
        engines = [("process pool", ()), ("Dask LocalCluster, 2 workers", ("--dask",))]
        for label, extra in engines[1:] if args.skip_pool else engines:
            runs = []
            for _ in range(args.runs):
                cache = os.path.join(scratch, "cold-cache")
                shutil.rmtree(cache, ignore_errors=True)
                runs.append(timeline(cold_manifest, output, cache, *extra))
            report(
                f"cold, {args.cold_songs} songs, {label}",
                f"loudscape-extract timeline --manifest manifest_{args.cold_songs}.csv -o t.ply "
                f"--cache-dir EMPTY --jobs 2 {' '.join(extra)}".strip(),
                runs,
            )
    cache = os.path.join(OUT, "cache")
    kept = os.path.join(OUT, f"timeline_{args.warm_songs}.ply")
    fill = time.perf_counter()
    timeline(warm_manifest, kept, cache)
    print(f"cache filled (or checked) in {time.perf_counter() - fill:.0f} s", flush=True)
    runs = [timeline(warm_manifest, kept, cache) for _ in range(args.runs)]
    report(
        f"warm rebuild, {args.warm_songs} songs from the cache",
        f"loudscape-extract timeline --manifest manifest_{args.warm_songs}.csv -o t.ply "
        "--cache-dir FILLED --jobs 2",
        runs,
    )
    print(
        f"kept: {os.path.relpath(kept, REPO)} ({os.path.getsize(kept) / 1e6:.0f} MB); "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
