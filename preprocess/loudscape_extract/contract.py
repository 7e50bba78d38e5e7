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

import numpy as np

from loudscape_extract.errors import ExtractError

__all__ = ["AXIS_NAMES", "check_cloud", "spread_range"]

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


def check_cloud(points: np.ndarray, metadata: dict, *, path: str | None = None) -> None:
    """Refuse a cloud the app's loader would reject (docs/FORMAT.md and src/cloud.rs).

    Checks: shape (n, 5); every value finite, x y z in [-1, 1], scalar and hp in [0, 1];
    metadata JSON-encodable without NaN or infinity; ``point_count`` equal to n; five axes with
    finite, distinct ``min`` and ``max`` (positive on a log axis) and finite tick positions.

    Raises
    ------
    ExtractError
        Naming the first violation; nothing has been written.
    """

    def fail(reason: str):
        raise ExtractError(f"refusing to write a file the app cannot load: {reason}", path=path)

    points = np.asarray(points)
    if points.ndim != 2 or points.shape[1] != 5:
        fail(f"points must have shape (n, 5), found {points.shape}")
    for column, (name, (low, high)) in enumerate(zip(AXIS_NAMES, _COLUMN_RANGES, strict=True)):
        values = points[:, column]
        if values.size == 0:
            continue
        if not np.isfinite(values).all():
            fail(f"column {name} has a NaN or infinite value")
        if values.min() < low or values.max() > high:
            fail(f"column {name} leaves [{low:g}, {high:g}]")
    try:
        json.dumps(metadata, allow_nan=False)
    except (TypeError, ValueError) as exc:
        fail(f"metadata is not plain JSON ({exc})")
    if metadata.get("point_count") != points.shape[0]:
        fail(f"point_count {metadata.get('point_count')!r} is not {points.shape[0]}")
    axes = metadata.get("axes")
    if not isinstance(axes, dict):
        fail("metadata has no axes object")
    for name in AXIS_NAMES:
        problem = _axis_problem(axes.get(name))
        if problem:
            fail(f"axes.{name}: {problem}")
