"""NumPy reference timings for loudscape's GPU voxelization.

Runs ``loudscape bench --export-points DIR`` (the GPU timings), then voxelizes the very same
points with NumPy (``np.bincount``; ``np.add.at`` is shown once for scale) the way the GPU does
without smoothing: per-voxel loudness sum, hp sum and count, mean hp, and the density normalized
by the 99th percentile of the positive sums. Prints both.

Usage::

    python bench/bench_voxelize.py [--loudscape PATH] [--runs N]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def grid_box(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The grid box of src/render/grid/voxelize.rs ``grid_box``: bounding box grown by 1 %."""
    if len(xyz) == 0:
        return np.full(3, -1.0, np.float32), np.full(3, 1.0, np.float32)
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    centre = (lo + hi) * np.float32(0.5)
    extent = hi - lo
    thinnest = max(float(extent.max()) * 0.05, 0.02)
    extent = np.maximum(extent, np.float32(thinnest)) * np.float32(1.02)
    return centre - extent * np.float32(0.5), centre + extent * np.float32(0.5)


def voxelize(points: np.ndarray, resolution: int, *, use_add_at: bool = False):
    """Density and mean hp, each of shape (resolution,) * 3 indexed [z, y, x].

    Parameters
    ----------
    points : np.ndarray, shape (n, 5), float32
        x, y, z, scalar, hp per point.
    resolution : int
        Voxels per side.
    """
    xyz = points[:, :3]
    lo, hi = grid_box(xyz)
    per_unit = np.float32(resolution) / (hi - lo)
    ijk = np.clip(np.floor((xyz - lo) * per_unit), 0, resolution - 1).astype(np.int64)
    index = ijk[:, 0] + resolution * (ijk[:, 1] + resolution * ijk[:, 2])
    n = resolution**3
    scalar = np.clip(points[:, 3], 0.0, 1.0)
    hp = np.clip(points[:, 4], 0.0, 1.0)
    if use_add_at:
        sums = np.zeros(n)
        np.add.at(sums, index, scalar)
        hp_sums = np.zeros(n)
        np.add.at(hp_sums, index, hp)
        counts = np.zeros(n, np.int64)
        np.add.at(counts, index, 1)
    else:
        sums = np.bincount(index, weights=scalar, minlength=n)
        hp_sums = np.bincount(index, weights=hp, minlength=n)
        counts = np.bincount(index, minlength=n)
    hp_mean = np.where(counts > 0, hp_sums / np.maximum(counts, 1), 0.5)
    positive = sums[sums > 0]
    reference = np.percentile(positive, 99.0) if len(positive) else 1.0
    density = np.minimum(sums / reference, 1.0)
    shape = (resolution,) * 3
    return density.reshape(shape).astype(np.float32), hp_mean.reshape(shape).astype(np.float32)


def median_ms(fn, runs: int) -> float:
    fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return float(np.median(times))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    target = os.environ.get("CARGO_TARGET_DIR", "target")
    parser.add_argument("--loudscape", default=str(Path(target) / "debug" / "loudscape"))
    parser.add_argument("--runs", type=int, default=11)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        command = [
            args.loudscape,
            "bench",
            "--only",
            "volume",
            "--runs",
            str(args.runs),
            "--export-points",
            tmp,
        ]
        print("$", " ".join(command[:-1]), "DIR", flush=True)
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            print(result.stderr.strip(), file=sys.stderr)
            return 1
        print("GPU (loudscape bench):")
        for line in result.stdout.splitlines():
            print("  " + line)
        print(f"NumPy {np.__version__} (same points, no smoothing, median of {args.runs}):")
        for name, resolution in [("song", 128), ("large", 224)]:
            points = np.fromfile(Path(tmp) / f"{name}.f32", dtype=np.float32).reshape(-1, 5)
            ms = median_ms(lambda p=points, r=resolution: voxelize(p, r), args.runs)
            print(
                f"  voxelize {name}: {len(points)} points -> {resolution}^3"
                f" (np.bincount): {ms:.2f} ms"
            )
            if name == "song":
                ms = median_ms(lambda p=points, r=resolution: voxelize(p, r, use_add_at=True), 3)
                print(
                    f"  voxelize {name}: {len(points)} points -> {resolution}^3"
                    f" (np.add.at): {ms:.2f} ms"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
