"""``render``, ``show`` and ``read_cloud``: the notebook API over the ``loudscape`` binary."""

from __future__ import annotations

import os
import subprocess
import tempfile
import threading
from pathlib import Path
from typing import NamedTuple

import numpy as np

from loudscape.binary import find_binary
from loudscape.picture import Picture
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import read_ply, write_ply

__all__ = ["Cloud", "read_cloud", "render", "show"]

VIEWS = ("points", "surface", "volume")


class Cloud(NamedTuple):
    """A point cloud: what :func:`read_cloud` returns and :func:`render` accepts.

    Unpacks as ``points, metadata = cloud``, the pair ``loudscape_extract.read_ply`` returns.

    Attributes
    ----------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
        x (time), y (level), z (frequency), scalar (A-weighted level), hp; see docs/FORMAT.md.
    metadata : dict
        The ``loudscape-meta`` object (axes, source, loudness metrics...).
    """

    points: np.ndarray
    metadata: dict


def read_cloud(path: str | os.PathLike) -> Cloud:
    """Read a loudscape point cloud (.ply, song or timeline).

    Parameters
    ----------
    path : str or os.PathLike
        A PLY file written by ``loudscape-extract``.

    Returns
    -------
    Cloud
        Its points and metadata.

    Raises
    ------
    ExtractError
        The file cannot be read or is not a loudscape PLY.
    """
    name = os.fspath(path)
    if not name.lower().endswith(".ply"):
        raise ExtractError("read_cloud reads .ply point clouds (render takes audio)", path=name)
    points, metadata = read_ply(name)
    return Cloud(points, metadata)


def _as_input(source, metadata: dict | None, folder: str) -> str:
    """A file the binary can open for ``source``: the path itself, or a PLY written in
    ``folder`` for arrays."""
    if isinstance(source, (str, os.PathLike)):
        name = os.fspath(source)
        if not os.path.isfile(name):
            raise ExtractError("no such file", path=name)
        return name
    if isinstance(source, tuple) and len(source) == 2:
        points, meta = source
        if metadata is not None:
            raise ExtractError("metadata is given twice: in the source pair and as metadata=")
    elif isinstance(source, np.ndarray):
        points, meta = source, metadata
    else:
        raise ExtractError(
            f"source must be a path, a Cloud, a (points, metadata) pair or a points array, "
            f"not {type(source).__name__}"
        )
    points = np.asarray(points, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] != 5 or points.shape[0] == 0:
        raise ExtractError(
            f"points must have shape (n_points, 5), n_points > 0, got {points.shape}"
        )
    if not np.isfinite(points).all():
        raise ExtractError("points hold NaN or infinite values")
    meta = dict(meta or {})
    if "point_count" in meta:
        # A selection of a cloud's points (``points[points[:, 4] > 0.5]``) keeps its metadata.
        meta["point_count"] = points.shape[0]
    name = os.path.join(folder, "cloud.ply")
    write_ply(name, points=points, metadata=meta)
    return name


def _run(command: list[str], *, timeout: float | None) -> None:
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired as exc:
        raise ExtractError(f"loudscape took longer than {timeout} s") from exc
    except OSError as exc:
        raise ExtractError(
            f"cannot run the binary ({exc.strerror or exc})", path=command[0]
        ) from exc
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        reason = lines[-1].strip() if lines else f"exit status {done.returncode}"
        raise ExtractError(reason)


def render(
    source,
    *,
    view: str = "points",
    size: tuple[int, int] = (1280, 720),
    camera: tuple[float, float, float] | None = None,
    point_size: float | None = None,
    iso: float = 0.5,
    method: str = "mt",
    colormap: str = "classic",
    background: str = "dark",
    freq_axis: str = "linear",
    labels: bool = True,
    legend: bool = True,
    metadata: dict | None = None,
    timeout: float | None = None,
) -> Picture:
    """Draw a loudscape with ``loudscape render`` and return the picture.

    Parameters
    ----------
    source : str, os.PathLike, Cloud, tuple or np.ndarray
        A point cloud (.ply) or an audio file (extracted by ``loudscape-extract`` and cached,
        as the app does); a :class:`Cloud` or the ``(points, metadata)`` pair
        ``loudscape_extract.read_ply`` returns; or a points array of shape (n_points, 5).
    view : {"points", "surface", "volume"}
    size : tuple of int
        (width, height) in pixels.
    camera : tuple of float, optional
        (azimuth degrees, elevation degrees, distance); fitted to the data when omitted.
    point_size : float, optional
        Point disc diameter in pixels (default: by the number of points).
    iso : float
        Surface isovalue in [0, 1] of the normalized loudness density.
    method : {"mt", "dc"}
        Surface extraction: marching tetrahedra or dual contouring.
    colormap : {"classic", "puor", "cividis", "viridis"}
        Colour map of hp.
    background : {"dark", "light"}
    freq_axis : {"linear", "log", "mel"}
        Frequency axis of a song cloud.
    labels, legend : bool
        Draw the axis labels, and the legend.
    metadata : dict, optional
        Metadata for a bare points array (``axes`` etc., see docs/FORMAT.md).
    timeout : float, optional
        Seconds to wait for the binary.

    Returns
    -------
    Picture
        Shown inline by Jupyter; ``.to_numpy()``, ``.save(path)``.

    Raises
    ------
    ExtractError
        Bad arguments, an unreadable source, or the renderer's own one-line error.
    """
    if view not in VIEWS:
        raise ExtractError(f"view {view!r} is not one of {', '.join(VIEWS)}")
    width, height = (int(v) for v in size)
    if width <= 0 or height <= 0:
        raise ExtractError(f"size must be two positive integers, got {size!r}")
    binary = find_binary()
    with tempfile.TemporaryDirectory(prefix="loudscape-render-") as folder:
        output = os.path.join(folder, "picture.png")
        command = [str(binary), "--quiet", "render", _as_input(source, metadata, folder)]
        command += ["--view", view, "--size", f"{width}x{height}", "--output", output]
        command += ["--iso", str(iso), "--method", method, "--colormap", colormap]
        command += ["--background", background, "--freq-axis", freq_axis]
        if camera is not None:
            azimuth, elevation, distance = (float(v) for v in camera)
            command += ["--camera", f"{azimuth},{elevation},{distance}"]
        if point_size is not None:
            command += ["--point-size", str(float(point_size))]
        if not labels:
            command.append("--no-labels")
        if not legend:
            command.append("--no-legend")
        _run(command, timeout=timeout)
        return Picture(Path(output).read_bytes())


def show(source, *, view: str | None = None, metadata: dict | None = None, wait: bool = True):
    """Open the loudscape window on ``source``.

    Parameters
    ----------
    source : str, os.PathLike, Cloud, tuple or np.ndarray
        As for :func:`render`.
    view : {"points", "surface", "volume"}, optional
        The view the window opens in.
    metadata : dict, optional
        Metadata for a bare points array.
    wait : bool
        Return when the window is closed (True), or at once with the running process.

    Returns
    -------
    subprocess.Popen or None
        The window's process when ``wait`` is False.

    Raises
    ------
    ExtractError
        Bad arguments, an unreadable source, or the window's own error.
    """
    if view is not None and view not in VIEWS:
        raise ExtractError(f"view {view!r} is not one of {', '.join(VIEWS)}")
    binary = find_binary()
    folder = tempfile.mkdtemp(prefix="loudscape-show-")
    try:
        command = [str(binary), _as_input(source, metadata, folder)]
        if view is not None:
            command += ["--view", view]
        if wait:
            _run(command, timeout=None)
            return None
        process = subprocess.Popen(command)
    except BaseException:
        _remove(folder)
        raise
    threading.Thread(target=lambda: (process.wait(), _remove(folder)), daemon=True).start()
    return process


def _remove(folder: str) -> None:
    for entry in Path(folder).iterdir():
        entry.unlink(missing_ok=True)
    os.rmdir(folder)
