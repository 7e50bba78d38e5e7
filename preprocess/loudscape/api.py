"""``render``, ``show`` and ``read_cloud``: the notebook API over the ``loudscape`` binary."""

from __future__ import annotations

import numbers
import os
import re
import subprocess
import tempfile
import threading
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from loudscape.binary import find_binary
from loudscape.page import Page
from loudscape.picture import Picture
from loudscape_extract.errors import ExtractError
from loudscape_extract.paths import check_regular_input
from loudscape_extract.ply import read_ply, write_ply

__all__ = ["Cloud", "LoudscapeWarning", "read_cloud", "render", "show"]

VIEWS = ("points", "surface", "volume")
METHODS = ("mt", "dc")
COLORMAPS = ("classic", "puor", "cividis", "viridis")
BACKGROUNDS = ("dark", "light")
FREQ_AXES = ("linear", "log", "mel")
#: Each side of a picture, in pixels (the renderer's own range).
SIZE_RANGE = (16, 8192)
#: Point disc diameters the renderer draws, in pixels.
POINT_SIZE_RANGE = (0.5, 64.0)
#: A warning line of the binary's stderr: ``warning: FILE: MESSAGE`` (a cloud's warnings,
#: docs/FORMAT.md "Warnings") or ``loudscape: warning: ...`` (the renderer's own).
_WARNING_LINE = re.compile(r"(?:loudscape: )?warning: (.+)")


class LoudscapeWarning(UserWarning):
    """What the extractor or the renderer found wrong or odd about an input: a truncated or
    corrupt file (``decoded 14.12 s of the 30.00 s``), channels that cancel, a large DC
    offset, clipping, a cache that cannot be written. The file is still drawn.

    :func:`render` raises one for each line (once), and keeps the lines on the picture
    (:attr:`Picture.warnings`); a cloud's own (its metadata's ``warnings``) are among them.
    """


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

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the extractor found wrong or odd about the input, ``"FILE: MESSAGE"`` each
        (the metadata's ``warnings``; empty when there is nothing to say).

        Examples
        --------
        >>> Cloud(np.zeros((1, 5), np.float32), {"source": {"path": "a.flac"}, "warnings": [
        ...     {"kind": "truncated", "message": "decoded 1.00 s of the 2.00 s"}]}).warnings
        ('a.flac: decoded 1.00 s of the 2.00 s',)
        """
        return tuple(_metadata_warnings(self.metadata))


def _metadata_warnings(metadata) -> list[str]:
    """``"FILE: MESSAGE"`` for each of the metadata's ``warnings`` (docs/FORMAT.md)."""
    if not isinstance(metadata, dict) or not isinstance(metadata.get("warnings"), list):
        return []
    source = metadata.get("source")
    default = source.get("path") if isinstance(source, dict) else None
    lines = []
    for item in metadata["warnings"]:
        if isinstance(item, dict) and isinstance(item.get("message"), str):
            file = item.get("path") if isinstance(item.get("path"), str) else default
            lines.append(f"{file}: {item['message']}" if isinstance(file, str) else item["message"])
    return lines


def read_cloud(path: str | os.PathLike) -> Cloud:
    """Read a loudscape point cloud (.ply, song or timeline).

    Only a regular file is read: a FIFO, a device or a directory is refused at once, and the
    memory used is the points' own whatever the file holds (docs/RELIABILITY.md).

    Parameters
    ----------
    path : str or os.PathLike
        A PLY file written by ``loudscape-extract``.

    Returns
    -------
    Cloud
        Its points and metadata (the extractor's warnings about the input:
        :attr:`Cloud.warnings`).

    Raises
    ------
    ExtractError
        The file cannot be read or is not a loudscape PLY.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ExtractError(f"path must be a file name, not {type(path).__name__}: {_shown(path)}")
    name = os.fspath(path)
    if not isinstance(name, str) or not name.lower().endswith(".ply"):
        raise ExtractError("read_cloud reads .ply point clouds (render takes audio)", path=name)
    points, metadata = read_ply(name)
    return Cloud(points, metadata)


# --- checking the arguments ---------------------------------------------------------------


def _shown(value) -> str:
    """``value`` for a message: its repr on one line, cut short."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 80 else text[:77] + "..."


def _is_number(value) -> bool:
    return isinstance(value, (numbers.Real, np.number)) and not isinstance(value, (bool, np.bool_))


def _number(name: str, value, *, low: float, high: float, what: str) -> float:
    """``value`` as a float in [low, high]; an ExtractError naming ``name`` otherwise."""
    if not _is_number(value):
        raise ExtractError(f"{name} must be {what}, got {_shown(value)}")
    number = float(value)
    if not (low <= number <= high):  # NaN fails too
        raise ExtractError(f"{name} must be {what}, got {_shown(value)}")
    return number


def _choice(name: str, value, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ExtractError(f"{name}={_shown(value)} is not one of {', '.join(choices)}")
    return value


def _flag(name: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ExtractError(f"{name} must be True or False, got {_shown(value)}")
    return bool(value)


def _size(size) -> tuple[int, int]:
    low, high = SIZE_RANGE
    what = f"(width, height): two whole numbers of pixels from {low} to {high}"
    if isinstance(size, (str, bytes)) or not isinstance(size, (tuple, list, np.ndarray)):
        raise ExtractError(f"size must be {what}, got {_shown(size)}")
    if len(size) != 2 or not all(_is_number(side) for side in size):
        raise ExtractError(f"size must be {what}, got {_shown(size)}")
    sides = [float(side) for side in size]
    if not all(low <= side <= high and side == int(side) for side in sides):
        raise ExtractError(f"size must be {what}, got {_shown(size)}")
    return int(sides[0]), int(sides[1])


def _camera(camera) -> tuple[float, float, float]:
    what = "(azimuth degrees, elevation degrees, distance > 0): three finite numbers"
    if isinstance(camera, (str, bytes)) or not isinstance(camera, (tuple, list, np.ndarray)):
        raise ExtractError(f"camera must be {what}, got {_shown(camera)}")
    if len(camera) != 3 or not all(_is_number(v) for v in camera):
        raise ExtractError(f"camera must be {what}, got {_shown(camera)}")
    azimuth, elevation, distance = (float(v) for v in camera)
    if not all(np.isfinite([azimuth, elevation, distance])) or distance <= 0:
        raise ExtractError(f"camera must be {what}, got {_shown(camera)}")
    return azimuth, elevation, distance


def _plain_json(value, where: str, depth: int = 0):
    """``value`` as plain JSON for the file's metadata: numpy numbers become Python numbers;
    an ExtractError naming where (``metadata['axes']['x']['min']``) for NaN, infinity, a key
    that is not a string or a value JSON has no type for."""
    if depth > 64:
        raise ExtractError(f"{where} is nested more than 64 levels deep")
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        if not np.isfinite(value):
            raise ExtractError(f"{where} is {value!r}: JSON has no NaN or infinity")
        return float(value)
    if isinstance(value, dict):
        plain = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise ExtractError(f"{where} has the key {_shown(key)}: keys must be strings")
            plain[key] = _plain_json(item, f"{where}[{key!r}]", depth + 1)
        return plain
    if isinstance(value, (list, tuple)):
        return [_plain_json(item, f"{where}[{i}]", depth + 1) for i, item in enumerate(value)]
    raise ExtractError(f"{where} is a {type(value).__name__}, which is not JSON")


def _options(
    *,
    view,
    size,
    camera,
    point_size,
    iso,
    method,
    colormap,
    background,
    freq_axis,
    labels,
    legend,
) -> list[str]:
    """The ``loudscape render`` options for the arguments of :func:`render`, each checked
    first (an ExtractError naming the argument and its value). Every value is passed as
    ``--name=value``, so none (``-1``) can be read as an option."""
    low, high = POINT_SIZE_RANGE
    width, height = _size(size)
    options = [
        f"--view={_choice('view', view, VIEWS)}",
        f"--size={width}x{height}",
        f"--iso={_number('iso', iso, low=0.0, high=1.0, what='a number from 0 to 1'):g}",
        f"--method={_choice('method', method, METHODS)}",
        f"--colormap={_choice('colormap', colormap, COLORMAPS)}",
        f"--background={_choice('background', background, BACKGROUNDS)}",
        f"--freq-axis={_choice('freq_axis', freq_axis, FREQ_AXES)}",
    ]
    if camera is not None:
        azimuth, elevation, distance = _camera(camera)
        options.append(f"--camera={azimuth!r},{elevation!r},{distance!r}")
    if point_size is not None:
        what = f"a number of pixels from {low:g} to {high:g}"
        options.append(
            f"--point-size={_number('point_size', point_size, low=low, high=high, what=what)!r}"
        )
    if not _flag("labels", labels):
        options.append("--no-labels")
    if not _flag("legend", legend):
        options.append("--no-legend")
    return options


def _timeout(timeout) -> float | None:
    if timeout is None:
        return None
    what = "None or a positive number of seconds"
    return _number("timeout", timeout, low=np.nextafter(0, 1), high=np.inf, what=what)


def _as_input(source, metadata, folder: str) -> tuple[str, str]:
    """A file the binary can open for ``source`` and the name its warnings should give: the
    path itself (absolute, so no name is read as an option), or a PLY written in ``folder``
    for arrays (named by the metadata's source, else ``points``)."""
    if isinstance(source, (str, os.PathLike)):
        name = os.fspath(source)
        if not isinstance(name, str):
            raise ExtractError(f"source must be a file name as str, got {_shown(source)}")
        check_regular_input(name)
        return os.path.abspath(name), _display(name)
    if isinstance(source, tuple) and len(source) == 2:
        points, meta = source
        where = "source's metadata"
        if metadata is not None:
            raise ExtractError("metadata is given twice: in the source pair and as metadata=")
    elif isinstance(source, (np.ndarray, list)):
        points, meta, where = source, metadata, "metadata"
    else:
        raise ExtractError(
            f"source must be a path, a Cloud, a (points, metadata) pair or a points array, "
            f"not {type(source).__name__}"
        )
    try:
        array = np.asarray(points)
    except (ValueError, TypeError) as exc:
        raise ExtractError(f"points must be an array of shape (n_points, 5) ({exc})") from None
    if array.dtype.kind not in "iuf":
        raise ExtractError(f"points must be numbers, got an array of dtype {array.dtype}")
    if array.ndim != 2 or array.shape[1] != 5 or array.shape[0] == 0:
        raise ExtractError(f"points must have shape (n_points, 5), n_points > 0, got {array.shape}")
    with np.errstate(over="ignore"):
        array = array.astype(np.float32)
    if not np.isfinite(array).all():
        raise ExtractError("points hold NaN or infinite values (or values beyond float32)")
    if meta is None:
        meta = {}
    if not isinstance(meta, dict):
        raise ExtractError(f"{where} must be a dict, got {type(meta).__name__}: {_shown(meta)}")
    try:
        meta = _plain_json(meta, where)
    except ExtractError as exc:
        raise ExtractError(f"{exc} (the metadata must be plain JSON: docs/FORMAT.md)") from None
    if "point_count" in meta:
        # A selection of a cloud's points (``points[points[:, 4] > 0.5]``) keeps its metadata.
        meta["point_count"] = array.shape[0]
    name = os.path.join(folder, "cloud.ply")
    write_ply(name, points=array, metadata=meta)
    source_entry = meta.get("source")
    label = source_entry.get("path") if isinstance(source_entry, dict) else None
    return name, label if isinstance(label, str) else "points"


# --- running the binary -------------------------------------------------------------------


def _run(command: list[str], *, timeout: float | None) -> str:
    """Run the binary; its stderr. An ExtractError with its error line if it fails."""
    try:
        done = subprocess.run(
            command,
            capture_output=True,
            timeout=timeout,
            check=False,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired as exc:
        raise ExtractError(f"loudscape took longer than timeout={timeout:g} s") from exc
    except OSError as exc:
        raise ExtractError(
            f"cannot run the binary ({exc.strerror or exc})", path=command[0]
        ) from exc
    stderr = done.stderr.decode("utf-8", "surrogateescape")
    if done.returncode != 0:
        lines = [line.strip() for line in stderr.splitlines() if line.strip()]
        errors = [line for line in lines if line.startswith(("loudscape: error:", "error:"))]
        reason = (errors or lines or [f"exit status {done.returncode}"])[0]
        raise ExtractError(reason.removeprefix("loudscape: ").removeprefix("error: "))
    return stderr


def _display(name: str) -> str:
    """A file name as the binary prints it: undecodable bytes as U+FFFD."""
    return os.fsencode(name).decode("utf-8", "replace")


def _warnings(stderr: str, *, input_name: str, label: str) -> list[str]:
    """The warning lines of the binary's stderr, once each, in order, without their
    ``warning:`` prefix. The input is named ``label`` (the name the caller gave, or what the
    temporary cloud of arrays stands for). A line that repeats an earlier one's message
    behind a second file name (``FILE: FILE: MESSAGE``) is the same warning said twice."""
    found: list[str] = []
    messages: list[str] = []
    for line in stderr.splitlines():
        match = _WARNING_LINE.fullmatch(line.strip())
        if match is None:
            continue
        text = match.group(1)
        for form in (input_name, _display(input_name)):
            text = text.replace(form, label)
        if text in found or any(text.endswith(": " + message) for message in messages):
            continue
        found.append(text)
        messages.append(text.split(": ", 1)[-1])
    return found


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
        Any file name works, ``-i.ply`` included.
    view : {"points", "surface", "volume"}
    size : tuple of int
        (width, height) in pixels, each 16 to 8192.
    camera : tuple of float, optional
        (azimuth degrees, elevation degrees, distance > 0); fitted to the data when omitted.
    point_size : float, optional
        Point disc diameter in pixels, 0.5 to 64 (default: by the number of points).
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
        Metadata for a bare points array (``axes`` etc., see docs/FORMAT.md); plain JSON.
    timeout : float, optional
        Seconds to wait for the binary.

    Returns
    -------
    Picture
        Shown inline by Jupyter; ``.to_numpy()``, ``.save(path)``; ``.warnings``.

    Raises
    ------
    ExtractError
        The one exception of the package: a bad argument (the message names it and its
        value), an unreadable source, or the renderer's own one-line error.

    Warns
    -----
    LoudscapeWarning
        Once for each thing found wrong or odd about the input (a truncated or corrupt file,
        cancelling channels...), as the command line says it; also kept in
        :attr:`Picture.warnings`.
    """
    options = _options(
        view=view,
        size=size,
        camera=camera,
        point_size=point_size,
        iso=iso,
        method=method,
        colormap=colormap,
        background=background,
        freq_axis=freq_axis,
        labels=labels,
        legend=legend,
    )
    seconds = _timeout(timeout)
    binary = find_binary()
    with tempfile.TemporaryDirectory(prefix="loudscape-render-") as folder:
        output = os.path.join(folder, "picture.png")
        name, label = _as_input(source, metadata, folder)
        command = [str(binary), "--quiet", "render", *options, f"--output={output}", "--", name]
        stderr = _run(command, timeout=seconds)
        said = _warnings(stderr, input_name=name, label=label)
        for text in said:
            warnings.warn(text, LoudscapeWarning, stacklevel=2)
        return Picture(Path(output).read_bytes(), warnings=said)


def show(
    source,
    *,
    view: str | None = None,
    metadata: dict | None = None,
    wait: bool = True,
    inline: bool = False,
    timeout: float | None = None,
):
    """Open the loudscape window on ``source``, or with ``inline=True`` put the interactive
    view in the notebook cell.

    Parameters
    ----------
    source : str, os.PathLike, Cloud, tuple or np.ndarray
        As for :func:`render`.
    view : {"points", "surface", "volume"}, optional
        The view the window opens in (the window only: the inline page opens in the points
        view, and S, V and P switch).
    metadata : dict, optional
        Metadata for a bare points array.
    wait : bool
        Return when the window is closed (True), or at once with the running process.
    inline : bool
        Instead of the window, the song's web page (``loudscape page``: the app's viewer for
        the web, with the cloud thinned to fit 12 MB), which Jupyter shows in the cell
        without a server. Needs the viewer built (``make web`` in a checkout) and, to turn
        the song, a browser with WebGPU.
    timeout : float, optional
        Seconds to wait for the binary to write the page (``inline`` only).

    Returns
    -------
    Page, subprocess.Popen or None
        The page when ``inline`` (shown by Jupyter; ``.html``, ``.save(path)``,
        ``.warnings``); the window's process when ``wait`` is False.

    Raises
    ------
    ExtractError
        The one exception of the package: a bad argument (named, with its value), an
        unreadable source, the window's own error, or (``inline``) the viewer not built
        (the message says to run ``make web``).
    """
    if view is not None:
        _choice("view", view, VIEWS)
    _flag("wait", wait)
    _flag("inline", inline)
    if inline:
        if view not in (None, "points"):
            raise ExtractError(
                f"view={view!r} is for the window; the inline page opens in the points view "
                "(S: surface, V: volume, P: points)"
            )
        return _page(source, metadata=metadata, timeout=_timeout(timeout))
    if timeout is not None:
        raise ExtractError("timeout is for the inline page (inline=True)")
    binary = find_binary()
    folder = tempfile.mkdtemp(prefix="loudscape-show-")
    try:
        # An absolute path: no file name (``-i.ply``) is read as an option.
        command = [str(binary), _as_input(source, metadata, folder)[0]]
        if view is not None:
            command += ["--view", view]
        if wait:
            _run(command, timeout=None)  # the window shows the input's warnings itself
            return None
        process = subprocess.Popen(command)
    except BaseException:
        _remove(folder)
        raise
    threading.Thread(target=lambda: (process.wait(), _remove(folder)), daemon=True).start()
    return process


def _page(source, *, metadata: dict | None, timeout: float | None) -> Page:
    """``loudscape page`` of ``source``, written to a temporary folder (removed on every
    path) and read back."""
    binary = find_binary()
    with tempfile.TemporaryDirectory(prefix="loudscape-page-") as folder:
        output = os.path.join(folder, "page.html")
        name, label = _as_input(source, metadata, folder)
        command = [str(binary), "--quiet", "page", f"--output={output}", "--", name]
        stderr = _run(command, timeout=timeout)
        said = _warnings(stderr, input_name=name, label=label)
        for text in said:
            warnings.warn(text, LoudscapeWarning, stacklevel=3)
        return Page(Path(output).read_text(encoding="utf-8"), warnings=said)


def _remove(folder: str) -> None:
    for entry in Path(folder).iterdir():
        entry.unlink(missing_ok=True)
    os.rmdir(folder)
