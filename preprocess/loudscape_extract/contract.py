"""The file contract, checked before a cloud is written, and the rule for one-value axes.

docs/FORMAT.md lets an axis have ``min == max``, but a reader needs a range to map values
back (the app's loader refuses an empty one), so writers never produce one: when every value
on an axis is the same ``v`` (one kept frame, one song, a constant crest factor), the axis is
written as ``[v - w, v + w]`` with a half width ``w`` that means something on that axis (half
a hop of time, half a dB, ...) and every point sits at its middle, 0. :func:`check_cloud`
then refuses, before anything is written, a cloud the loader would reject.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.notices import warnings_problem

__all__ = [
    "AXIS_NAMES",
    "check_cloud",
    "check_loadable",
    "check_metadata",
    "check_points",
    "checked_blocks",
    "spread_range",
]

AXIS_NAMES = ("x", "y", "z", "scalar", "hp")
_COLUMN_RANGES = ((-1.0, 1.0), (-1.0, 1.0), (-1.0, 1.0), (0.0, 1.0), (0.0, 1.0))


def spread_range(low: float, high: float, half_width: float, *, digits: int = 6):
    """``(low, high)``, or ``(v - half_width, v + half_width)`` when the range is empty.

    Empty means ``high <= low`` after rounding to ``digits`` decimals, as the metadata stores
    them. ``half_width`` must be larger than the rounding step.
    """
    if round(high, digits) > round(low, digits):
        return low, high
    middle = (low + high) / 2.0
    return middle - half_width, middle + half_width


def _axis_problem(value: object) -> str:
    if not isinstance(value, dict):
        return f"must be an object, found {type(value).__name__}"
    low, high = value.get("min"), value.get("max")
    for key, number in (("min", low), ("max", high)):
        if isinstance(number, bool) or not isinstance(number, int | float):
            return f"{key} must be a number, found {number!r}"
        if not math.isfinite(number):
            return f"{key} {number} is not finite"
    if low == high:
        return f"min and max are both {low}"
    scale = value.get("scale", "linear")
    if scale not in ("linear", "log"):
        return f"scale must be linear or log, found {scale!r}"
    if scale == "log" and (low <= 0 or high <= 0):
        return f"a log axis needs positive min and max, found {low} and {high}"
    for tick in value.get("ticks") or []:
        at = tick.get("at") if isinstance(tick, dict) else None
        if isinstance(at, bool) or not isinstance(at, int | float) or not math.isfinite(at):
            return f"tick position {at!r} is not a finite number"
    return ""


_WRITING = "refusing to write a file the app cannot load"
_READING = "not a cloud the app loads"


def _fail(reason: str, path: str | None, refusal: str = _WRITING):
    raise ExtractError(f"{refusal}: {reason}", path=path)


def check_points(points: np.ndarray, *, path: str | None = None, refusal: str = _WRITING) -> None:
    """The point rules of :func:`check_cloud` alone: shape (n, 5), every value finite, x y z
    in [-1, 1], scalar and hp in [0, 1]. For a cloud written block by block, run on each block.

    Raises
    ------
    ExtractError
        Naming the first violation.
    """
    points = np.asarray(points)
    if points.ndim != 2 or points.shape[1] != 5:
        _fail(f"points must have shape (n, 5), found {points.shape}", path, refusal)
    for column, (name, (low, high)) in enumerate(zip(AXIS_NAMES, _COLUMN_RANGES, strict=True)):
        values = points[:, column]
        if values.size == 0:
            continue
        if not np.isfinite(values).all():
            _fail(f"column {name} has a NaN or infinite value", path, refusal)
        if values.min() < low or values.max() > high:
            _fail(f"column {name} leaves [{low:g}, {high:g}]", path, refusal)


def check_metadata(
    metadata: dict, *, n_points: int, path: str | None = None, refusal: str = _WRITING
) -> None:
    """The metadata rules of :func:`check_cloud` alone, for a cloud of ``n_points`` points:
    JSON-encodable without NaN or infinity, ``point_count`` equal to ``n_points``, five valid
    axes, and ``warnings`` (when present; also each timeline song's) an array of
    ``{"kind", "message"}`` objects, with ``"path"`` at the top of a timeline.

    Raises
    ------
    ExtractError
        Naming the first violation.
    """
    try:
        json.dumps(metadata, allow_nan=False)
    except (TypeError, ValueError) as exc:
        _fail(f"metadata is not plain JSON ({exc})", path, refusal)
    count = metadata.get("point_count")
    if isinstance(count, bool) or count != n_points:
        _fail(f"point_count {count!r} is not {n_points}", path, refusal)
    axes = metadata.get("axes")
    if not isinstance(axes, dict):
        _fail("metadata has no axes object", path, refusal)
    for name in AXIS_NAMES:
        problem = _axis_problem(axes.get(name))
        if problem:
            _fail(f"axes.{name}: {problem}", path, refusal)
    timeline = metadata.get("mode") == "timeline"
    if "warnings" in metadata:
        problem = warnings_problem(metadata["warnings"], with_path=timeline)
        if problem:
            _fail(f"warnings{problem}", path, refusal)
    for index, song in enumerate((metadata.get("songs") or []) if timeline else []):
        if isinstance(song, dict) and "warnings" in song:
            problem = warnings_problem(song["warnings"])
            if problem:
                _fail(f"songs[{index}].warnings{problem}", path, refusal)


def check_loadable(
    points: np.ndarray, metadata: dict, *, path: str | None = None, block: int = 1 << 20
) -> None:
    """Refuse a cloud read from a file that the app's loader would refuse (what
    ``loudscape-extract export`` accepts): ``format_version`` the integer 1 or 2 (``2``, not
    ``"2"`` or ``2.0``), ``mode`` song or timeline, and :func:`check_cloud`'s rules (the
    points checked ``block`` rows at a time, so a memory-mapped cloud of any size is checked
    in bounded memory).

    Raises
    ------
    ExtractError
        ``not a cloud the app loads: <the first violation>``.
    """
    version = metadata.get("format_version")
    if isinstance(version, bool) or not isinstance(version, int) or version not in (1, 2):
        _fail(f"format_version must be the integer 1 or 2, found {version!r}", path, _READING)
    if metadata.get("mode") not in ("song", "timeline"):
        _fail(f"mode must be song or timeline, found {metadata.get('mode')!r}", path, _READING)
    n = int(np.asarray(points).shape[0]) if np.ndim(points) else 0
    check_metadata(metadata, n_points=n, path=path, refusal=_READING)
    for start in range(0, n, block):
        check_points(points[start : start + block], path=path, refusal=_READING)


def check_cloud(points: np.ndarray, metadata: dict, *, path: str | None = None) -> None:
    """Refuse a cloud the app's loader would reject (docs/FORMAT.md and src/data/cloud/).

    Checks: shape (n, 5); every value finite, x y z in [-1, 1], scalar and hp in [0, 1];
    metadata JSON-encodable without NaN or infinity; ``point_count`` equal to n; five axes with
    finite, distinct ``min`` and ``max`` (positive on a log axis) and finite tick positions.

    Raises
    ------
    ExtractError
        Naming the first violation; nothing has been written.
    """
    check_points(points, path=path)
    check_metadata(metadata, n_points=np.asarray(points).shape[0], path=path)


def checked_blocks(
    blocks: Iterable[np.ndarray], metadata: dict, *, n_points: int, path: str | None = None
) -> Iterator[np.ndarray]:
    """``blocks`` of a cloud written as it is produced, with :func:`check_cloud`'s rules: the
    metadata is checked before the first block, each block before it is passed on. A writer
    that puts the file in place only after the last block (:func:`ply.write_ply_blocks`)
    therefore never leaves a file the app rejects."""
    check_metadata(metadata, n_points=n_points, path=path)
    for block in blocks:
        check_points(block, path=path)
        yield block
