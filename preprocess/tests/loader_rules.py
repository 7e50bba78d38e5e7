"""The app loader's rules (docs/FORMAT.md, src/data/cloud/, src/data/axes.rs), written out again
independently of the package's own check, for tests that must see what the app would see."""

import json
import math

import numpy as np

from test_ply import tiny_read

AXES = ("x", "y", "z", "scalar", "hp")


def _no_constants(name):
    raise ValueError(f"non-standard JSON constant {name}")


def loader_problems(path):
    """Why the app's loader would refuse ``path`` (empty list: it loads)."""
    problems = []
    header, metadata, records = tiny_read(path)
    # The JSON text as written: one line (format 1) or numbered chunks (format 2).
    v1 = [line.split(" ", 2)[2] for line in header if line.startswith("comment loudscape-meta ")]
    v2 = [line.split(" ")[3] for line in header if line.startswith("comment loudscape-meta-v2 ")]
    try:
        json.loads("".join(v2) if v2 else v1[0], parse_constant=_no_constants)
    except ValueError as exc:
        problems.append(str(exc))
    if metadata.get("format_version") not in (1, 2) or metadata.get("mode") not in (
        "song",
        "timeline",
    ):
        problems.append("format_version or mode")
    if metadata.get("point_count") != records.shape[0]:
        problems.append("point_count")
    for name in AXES:
        axis = metadata["axes"][name]
        low, high = axis.get("min"), axis.get("max")
        if not all(isinstance(v, int | float) and math.isfinite(v) for v in (low, high)):
            problems.append(f"axes.{name}: min {low!r} max {high!r} not finite numbers")
        elif low == high:
            problems.append(f"axes.{name}: min and max are both {low}")
        elif axis.get("scale") == "log" and min(low, high) <= 0:
            problems.append(f"axes.{name}: log axis with a non-positive end")
    if not np.isfinite(records).all():
        problems.append("non-finite value in the records")
    elif records.size:
        if np.abs(records[:, :3]).max() > 1:
            problems.append("x, y or z outside [-1, 1]")
        if records[:, 3:].min() < 0 or records[:, 3:].max() > 1:
            problems.append("scalar or hp outside [0, 1]")
    for index, song in enumerate(metadata.get("songs") or []):
        if not isinstance(song.get("year"), int):
            problems.append(f"songs[{index}].year")
    return problems


def no_null(value, where="metadata"):
    """Paths of every null in a JSON value."""
    if value is None:
        return [where]
    if isinstance(value, dict):
        return [p for key, item in value.items() for p in no_null(item, f"{where}.{key}")]
    if isinstance(value, list):
        return [p for i, item in enumerate(value) for p in no_null(item, f"{where}[{i}]")]
    return []
