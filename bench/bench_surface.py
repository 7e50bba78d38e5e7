"""Isosurface extraction: loudscape's two engines against scikit-image and VTK, same fields.

Runs ``loudscape bench --fields-dir DIR``, which times marching tetrahedra and dual contouring
on both engines (the GPU passes, and the CPU extraction the app uses where the device is the
CPU) on a song-like field at 128^3 and 224^3 and writes each field as a .npy file (float32,
C order, shape (nz, ny, nx), voxel centres at -1 + (index + 0.5) * 2 / n); then times
``skimage.measure.marching_cubes`` on those fields at the same isovalue in the same run, padded
by one zero voxel as loudscape closes surfaces at the grid border, and prints the ratios and the
surface areas. When VTK is installed (``pip install vtk``) its flying edges
(``vtkFlyingEdges3D``) runs on the same padded fields too: on one thread (the PyPI build's
default SMP backend, Sequential) and on every core (STDThread), each with the geometry alone
(normals, gradients and scalars off: the set-up issue 37 measured) and with its vertices made
as ours are (a unit normal from the interpolated gradient, one more point array interpolated as
our hp). Our CPU engine on every core is held to the second on every core, on one thread to
the second on one thread.

Usage: python bench/bench_surface.py [--loudscape target/release/loudscape] [--runs 10]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from skimage import measure


def skimage_median_ms(field: np.ndarray, iso: float, runs: int) -> tuple[float, int, float]:
    """Median time (ms), triangle count and area (data units) of scikit-image's marching cubes."""
    padded = np.pad(field, 1)
    spacing = (2.0 / field.shape[0], 2.0 / field.shape[1], 2.0 / field.shape[2])
    times = []
    verts = faces = None
    for _ in range(runs):
        start = time.perf_counter()
        verts, faces, _, _ = measure.marching_cubes(padded, iso, spacing=spacing)
        times.append((time.perf_counter() - start) * 1e3)
    area = float(measure.mesh_surface_area(verts, faces))
    return float(np.median(times)), len(faces), area


def vtk_median_ms(
    field: np.ndarray, iso: float, runs: int, threads: str, vertices: bool
) -> tuple[float, int] | None:
    """Median time (ms) and triangle count of VTK's flying edges, or None without VTK.

    ``threads``: VTK's SMP backend, "Sequential" (one thread, the PyPI build's default) or
    "STDThread" (every core). ``vertices``: the vertices as ours are made (a unit normal from the
    interpolated gradient and one more point array interpolated, as our hp); otherwise the
    geometry alone (normals, gradients and scalars off), the set-up the issue measured.
    """
    try:
        from vtkmodules.util.numpy_support import numpy_to_vtk
        from vtkmodules.vtkCommonCore import vtkSMPTools
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D
    except ImportError:
        return None
    padded = np.ascontiguousarray(np.pad(field, 1))
    image = vtkImageData()
    # VTK's x varies fastest, as in the (z, y, x) C-order array.
    image.SetDimensions(padded.shape[2], padded.shape[1], padded.shape[0])
    scalars = numpy_to_vtk(padded.ravel(), deep=True)
    scalars.SetName("density")
    image.GetPointData().SetScalars(scalars)
    if vertices:
        # A second point array of the field's size, interpolated at every vertex as our hp is
        # (its values do not change the work).
        hp = numpy_to_vtk(np.clip(padded.ravel(), 0.0, 1.0), deep=True)
        hp.SetName("hp")
        image.GetPointData().AddArray(hp)
    tools = vtkSMPTools()
    tools.SetBackend(threads)
    times = []
    triangles = 0
    try:
        for _ in range(runs):
            edges = vtkFlyingEdges3D()
            edges.SetInputData(image)
            edges.SetValue(0, iso)
            edges.SetComputeNormals(vertices)
            edges.SetInterpolateAttributes(vertices)
            edges.ComputeGradientsOff()
            edges.ComputeScalarsOff()
            start = time.perf_counter()
            edges.Update()
            times.append((time.perf_counter() - start) * 1e3)
            triangles = edges.GetOutput().GetNumberOfPolys()
    finally:
        tools.SetBackend("Sequential")
    return float(np.median(times)), triangles


def vtk_threads(backend: str) -> int:
    """The threads VTK's flying edges runs on with SMP backend ``backend``."""
    from vtkmodules.vtkCommonCore import vtkSMPTools

    tools = vtkSMPTools()
    tools.SetBackend(backend)
    try:
        return tools.GetEstimatedNumberOfThreads()
    finally:
        tools.SetBackend("Sequential")


def versus(vtk: dict, our_ms: float, threads: str, vertices: bool, label: str) -> str:
    """ ", R x VTK label": our time over VTK's with ``threads`` and ``vertices`` (none: "")."""
    peer = vtk[(threads, vertices)]
    return "" if peer is None else f", {our_ms / peer[0]:.2f}x VTK {label}"


def load_average() -> str:
    """The 1-minute load average and the CPU count, for reading the figures."""
    if not hasattr(os, "getloadavg"):
        return "unknown"
    return f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loudscape", default="target/release/loudscape")
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--iso", type=float, default=0.3)
    args = parser.parse_args()
    print(f"load average before: {load_average()}")
    with tempfile.TemporaryDirectory() as tmp:
        command = [
            args.loudscape,
            "bench",
            "--only",
            "surface",
            "--runs",
            str(args.runs),
            "--iso",
            str(args.iso),
            "--fields-dir",
            tmp,
        ]
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        print(done.stdout, end="")
        if done.returncode != 0:
            print(done.stderr.strip().splitlines()[-1], file=sys.stderr)
            return 1
        ours = {}
        pattern = (
            r"surface (\S+) (mt|dc) engine=(gpu|cpu) median_ms=([\d.]+) triangles=(\d+)"
            r" area=([\d.]+)"
        )
        for match in re.finditer(pattern, done.stdout):
            name, method, engine, ms, tris, area = match.groups()
            ours[(name, method, engine)] = (float(ms), int(tris), float(area))
        # The CPU engine on one thread, against VTK on one thread.
        one_thread = {
            (name, method): float(ms)
            for name, method, ms in re.findall(
                r"surface (\S+) (mt|dc) engine=cpu threads=1 median_ms=([\d.]+)", done.stdout
            )
        }
        print(f"\nscikit-image {args.runs} runs each, iso {args.iso}:")
        for npy in sorted(Path(tmp).glob("*.npy")):
            name = npy.stem
            field = np.load(npy)
            ms, tris, area = skimage_median_ms(field, args.iso, args.runs)
            print(f"  {name}: marching_cubes {ms:.1f} ms, {tris} triangles, area {area:.4f}")
            # VTK on one thread (its PyPI build's default) and on every core, the geometry
            # alone (the set-up) and with vertices made as ours are (like for like).
            vtk = {
                (threads, vertices): vtk_median_ms(field, args.iso, args.runs, threads, vertices)
                for vertices in (False, True)
                for threads in ("Sequential", "STDThread")
            }
            if vtk[("Sequential", False)] is None:
                print("    VTK flying edges: not installed (pip install vtk)")
            else:
                cores = vtk_threads("STDThread")
                for vertices, what in (
                    (False, "geometry only"),
                    (True, "with unit normals and hp interpolated, as ours"),
                ):
                    one, every = vtk[("Sequential", vertices)], vtk[("STDThread", vertices)]
                    print(
                        f"    VTK flying edges, {what}: 1 thread {one[0]:.1f} ms,"
                        f" {cores} threads {every[0]:.1f} ms, {one[1]} triangles"
                    )

            for method in ("mt", "dc"):
                for engine in ("gpu", "cpu"):
                    if (name, method, engine) not in ours:
                        print(f"    {method} ({engine} engine): no result")
                        continue
                    our_ms, _, our_area = ours[(name, method, engine)]
                    ratios = versus(vtk, our_ms, "Sequential", False, "geometry, 1 thread")
                    if engine == "cpu":
                        ratios += versus(vtk, our_ms, "STDThread", True, "as ours, every core")
                    print(
                        f"    {method} ({engine} engine): {our_ms:.1f} ms,"
                        f" {ms / our_ms:.2f}x scikit-image's speed{ratios},"
                        f" area {100 * (our_area / area - 1):+.2f}% vs scikit-image"
                    )
                if (name, method) in one_thread:
                    our_ms = one_thread[(name, method)]
                    ratios = versus(vtk, our_ms, "Sequential", False, "geometry, 1 thread")
                    ratios += versus(vtk, our_ms, "Sequential", True, "as ours, 1 thread")
                    print(f"    {method} (cpu engine, 1 thread): {our_ms:.1f} ms{ratios}")
    # The ratio moves with the machine's load: llvmpipe's threads share the cores with any
    # other work, single-threaded scikit-image less so.
    print(f"load average after: {load_average()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
