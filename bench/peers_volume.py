"""The volume frame against VTK's CPU ray caster, like for like.

``loudscape bench --only volume --fields-dir DIR`` writes the demo's density grid
(``volume_density.npy``) and its frame (``volume_view.json``: camera, box, step, transfer
function). This script sets up ``vtkFixedPointVolumeRayCastMapper`` on the same grid, in the same
world box, seen by the same camera at the same size, with the same colour ramp and opacity per
voxel, the same number of samples per ray (VTK's sample distance is chosen so that its samples
over all covered rays equal loudscape's: one per voxel of ray length in voxel space), shaded
and unshaded. Then it alternates runs: ``loudscape bench --only volume`` and VTK's frames, and
prints the medians of each and the ratios (loudscape's time over VTK's), with the load average.
With ``--baseline OTHER_BINARY``, each round also runs that build's ``bench`` (alternated with the
first), and the table gains its figures and the ratio of the two (A/B, first over baseline).

Usage (from the repository root; VTK comes from the development venv, as for ``make test-mesh``)::

    .venv/bin/python bench/peers_volume.py --loudscape target/release/loudscape --rounds 3
    .venv/bin/python bench/peers_volume.py --loudscape new/loudscape --baseline old/loudscape
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FRAME = re.compile(
    r"^volume frame (\d+)x(\d+) \(at rest, \d+\^3, step [\d.]+ voxel, (shaded|unshaded)\): "
    r"([\d.]+) ms \(full march ([\d.]+) ms\)$"
)


class PeerError(Exception):
    """A bad input or a failed run, said in one line."""


def ray_lengths(view: dict) -> tuple[np.ndarray, np.ndarray]:
    """Lengths, in world units and in voxels, of every pixel's ray inside the grid's box.

    Returns two arrays of shape (covered pixels,): the covered pixels only.
    """
    width, height = view["width"], view["height"]
    eye = np.asarray(view["eye"], dtype=np.float64)
    target = np.asarray(view["target"], dtype=np.float64)
    up = np.asarray(view["up"], dtype=np.float64)
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    true_up = np.cross(back, right)
    half_h = np.tan(np.radians(view["fov_y_degrees"]) / 2)
    half_w = half_h * width / height
    xs = ((np.arange(width) + 0.5) / width * 2 - 1) * half_w
    ys = (1 - (np.arange(height) + 0.5) / height * 2) * half_h
    gx, gy = np.meshgrid(xs, ys)
    dirs = gx[..., None] * right + gy[..., None] * true_up - back
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    lo = np.asarray(view["box_min_world"], dtype=np.float64)
    hi = np.asarray(view["box_max_world"], dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo - eye) / dirs
        t1 = (hi - eye) / dirs
    t_enter = np.maximum(np.nanmax(np.minimum(t0, t1), axis=-1), 0.0)
    t_exit = np.nanmin(np.maximum(t0, t1), axis=-1)
    covered = t_exit > t_enter
    world = (t_exit - t_enter)[covered]
    per_world = np.asarray(view["dims"], dtype=np.float64) / (hi - lo)
    voxels = world * np.linalg.norm(dirs[covered] * per_world, axis=-1)
    return world, voxels


def vtk_scene(density: np.ndarray, view: dict, *, shaded: bool, sample_distance: float):
    """A render window drawing the grid with vtkFixedPointVolumeRayCastMapper, offscreen."""
    import vtk
    from vtk.util import numpy_support

    nz, ny, nx = density.shape
    lo = np.asarray(view["box_min_world"])
    hi = np.asarray(view["box_max_world"])
    spacing = (hi - lo) / np.array([nx, ny, nz])
    image = vtk.vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    image.SetOrigin(*(lo + spacing / 2))
    scaled = np.ascontiguousarray(density * view["density_scale"], dtype=np.float32)
    image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(scaled.ravel(), deep=True))

    # loudscape's Classic transfer: ramp position and opacity per voxel both rise linearly with
    # the scaled density; the colour is the preset's four stops, evenly spaced.
    if view["preset"] != "Classic":
        raise PeerError(f"preset {view['preset']}: only Classic is set up for VTK")
    colour = vtk.vtkColorTransferFunction()
    stops = view["ramp"]
    for i, rgb in enumerate(stops):
        colour.AddRGBPoint(i / (len(stops) - 1), *rgb)
    opacity = vtk.vtkPiecewiseFunction()
    opacity.AddPoint(0.0, 0.0)
    opacity.AddPoint(0.002, 0.0)
    opacity.AddPoint(1.0, min(view["opacity_per_voxel"], 1.0))
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    # Opacity per voxel of ray length: the unit distance is a voxel (the mean side).
    prop.SetScalarOpacityUnitDistance(float(np.mean(spacing)))
    prop.SetInterpolationTypeToLinear()
    if shaded:
        prop.ShadeOn()
        prop.SetAmbient(0.5)
        prop.SetDiffuse(0.7)
        prop.SetSpecular(0.0)
    else:
        prop.ShadeOff()

    mapper = vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputData(image)
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetSampleDistance(sample_distance)
    mapper.SetImageSampleDistance(1.0)
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    renderer = vtk.vtkRenderer()
    renderer.AddVolume(volume)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(*view["eye"])
    camera.SetFocalPoint(*view["target"])
    camera.SetViewUp(*view["up"])
    camera.SetViewAngle(view["fov_y_degrees"])
    renderer.ResetCameraClippingRange()
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(view["width"], view["height"])
    window.AddRenderer(renderer)
    return window, renderer


def vtk_median_ms(window, renderer, frames: int) -> float:
    """Median wall time of `frames` renders, after one warm-up; each one recasts every ray."""
    window.Render()
    times = []
    for i in range(frames):
        # A turn of the camera too small to see makes the frame a new one.
        renderer.GetActiveCamera().Azimuth(1e-4 * (1 if i % 2 else -1))
        start = time.perf_counter()
        window.Render()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def loudscape_frames(binary: Path, song: Path, runs: int, fields_dir: Path | None) -> dict:
    """One `loudscape bench --only volume` run: {(shading, path): median ms}."""
    command = [str(binary), "bench", "--only", "volume", "--runs", str(runs), str(song)]
    if fields_dir is not None:
        command += ["--fields-dir", str(fields_dir)]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise PeerError(f"{binary}: bench failed: {last}")
    figures = {}
    for line in done.stdout.splitlines():
        match = FRAME.match(line)
        if match:
            shading = match.group(3)
            figures[(shading, "fast")] = float(match.group(4))
            figures[(shading, "full")] = float(match.group(5))
    if len(figures) != 4:
        raise PeerError(f"{binary}: bench printed no shaded and unshaded volume frames")
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--loudscape", type=Path, default=Path("target/release/loudscape"))
    parser.add_argument(
        "--baseline", type=Path, help="another build, alternated with --loudscape (A/B)"
    )
    parser.add_argument("--song", type=Path, default=Path("data/demo_song.ply"))
    parser.add_argument("--rounds", type=int, default=3, help="alternations (default 3)")
    parser.add_argument("--runs", type=int, default=5, help="frames per measurement")
    args = parser.parse_args(argv)
    # SIGTERM unwinds like Ctrl-C, so the scratch folder is removed either way.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    try:
        for path in (args.loudscape, args.song, args.baseline):
            if path is not None and not path.is_file():
                raise PeerError(f"{path}: no such file")
        if args.rounds < 1 or args.runs < 1:
            raise PeerError("--rounds and --runs must be at least 1")
        try:
            import vtk  # noqa: F401
        except ImportError as error:
            raise PeerError(f"VTK is not installed in this Python ({error})") from None
        load_start = os.getloadavg()
        with tempfile.TemporaryDirectory(prefix="peers_volume_") as scratch:
            scratch = Path(scratch)
            ours = [loudscape_frames(args.loudscape, args.song, args.runs, scratch)]
            view = json.loads((scratch / "volume_view.json").read_text())
            density = np.load(scratch / "volume_density.npy")
        world, voxels = ray_lengths(view)
        samples_per_ray = voxels.mean() / view["step_voxels"]
        sample_distance = world.sum() / voxels.sum() * view["step_voxels"]
        coverage = world.size / (view["width"] * view["height"])
        print(
            f"grid {'x'.join(map(str, density.shape[::-1]))}, frame "
            f"{view['width']}x{view['height']}, coverage {coverage:.1%}, "
            f"{samples_per_ray:.1f} samples per covered ray (VTK sample distance "
            f"{sample_distance:.5f} world units)"
        )
        scenes = {
            shading: vtk_scene(
                density, view, shaded=shading == "shaded", sample_distance=sample_distance
            )
            for shading in ("shaded", "unshaded")
        }
        theirs = []
        baseline = []
        for round_index in range(args.rounds):
            if round_index > 0:
                ours.append(loudscape_frames(args.loudscape, args.song, args.runs, None))
            if args.baseline is not None:
                baseline.append(loudscape_frames(args.baseline, args.song, args.runs, None))
            theirs.append(
                {shading: vtk_median_ms(*scenes[shading], args.runs) for shading in scenes}
            )
        load_end = os.getloadavg()
    except PeerError as error:
        print(f"peers_volume: {error}", file=sys.stderr)
        return 1
    print(
        f"load average {load_start[0]:.2f} at the start, {load_end[0]:.2f} at the end; "
        f"{args.rounds} rounds alternated, medians of the rounds' medians of {args.runs} frames"
    )
    header = "| frame | loudscape | full march | VTK fixed-point ray caster | ratio (time) |"
    rule = "|---|---|---|---|---|"
    if baseline:
        header += f" baseline ({args.baseline.name}) | baseline / VTK | A/B (time) |"
        rule += "---|---|---|"
    print(header)
    print(rule)
    for shading in ("shaded", "unshaded"):
        fast = statistics.median(run[(shading, "fast")] for run in ours)
        full = statistics.median(run[(shading, "full")] for run in ours)
        peer = statistics.median(run[shading] for run in theirs)
        row = (
            f"| {shading} | {fast:.0f} ms | {full:.0f} ms | {peer:.0f} ms | "
            f"{fast / peer:.2f}x (full march {full / peer:.2f}x) |"
        )
        if baseline:
            old = statistics.median(run[(shading, "fast")] for run in baseline)
            row += f" {old:.0f} ms | {old / peer:.2f}x | {fast / old:.2f} |"
        print(row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
