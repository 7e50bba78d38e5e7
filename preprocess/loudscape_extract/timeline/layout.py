"""Timeline layout: song order and spans on x, the x axis, frame sampling, and the points."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import axis, hp_axis, level_axis, scalar_axis
from loudscape_extract.timeline.frames import SongFrames
from loudscape_extract.timeline.inputs import SongEntry

__all__ = [
    "CREST_PERCENTILES",
    "LEVEL_MAX_DBFS",
    "LEVEL_MIN_DBFS",
    "METRIC_KEYS",
    "SCALAR_FLOOR_DB",
    "X_BY",
    "percentile_map",
    "sample_frames",
    "song_spans",
    "sort_entries",
    "timeline_points",
    "x_axis",
]

LEVEL_MIN_DBFS = -60.0
LEVEL_MAX_DBFS = 0.0
SCALAR_FLOOR_DB = -100.0
CREST_PERCENTILES = (1.0, 99.0)
X_BY = ("year", "order")
METRIC_KEYS = (
    "integrated_lufs",
    "lra_lu",
    "sample_peak_dbfs",
    "true_peak_dbtp",
    "plr_db",
    "crest_median_db",
    "crest_p95_db",
    "hp_mean",
)


def sample_frames(n_frames: int, count: int) -> np.ndarray:
    """Indices of ``count`` frames spread evenly over ``n_frames`` (all of them if fewer)."""
    if n_frames <= count:
        return np.arange(n_frames)
    return np.round(np.linspace(0, n_frames - 1, count)).astype(np.int64)


def sort_entries(entries: Sequence[SongEntry]) -> list[SongEntry]:
    """By year, then artist, then title (case-insensitive), then path."""
    return sorted(entries, key=lambda e: (e.year, e.artist.casefold(), e.title.casefold(), e.path))


def percentile_map(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """``[low, high] -> [-1, 1]``, clamped outside; 0 everywhere when ``low == high``."""
    if not high > low:
        return np.zeros_like(values, dtype=np.float64)
    return np.clip(2.0 * (values - low) / (high - low) - 1.0, -1.0, 1.0)


def song_spans(entries: Sequence[SongEntry], x_by: str) -> list[tuple[float, float]]:
    """Normalized ``(x_min, x_max)`` of each song (entries already sorted)."""
    n = len(entries)
    if x_by == "order":
        return [(2.0 * i / n - 1.0, 2.0 * (i + 1) / n - 1.0) for i in range(n)]
    first, last = entries[0].year, entries[-1].year
    width = last + 1 - first
    spans = []
    for i, entry in enumerate(entries):
        same = [e for e in entries if e.year == entry.year]
        k = sum(1 for e in entries[:i] if e.year == entry.year)
        start = entry.year - first + k / len(same)
        end = entry.year - first + (k + 1) / len(same)
        spans.append((2.0 * start / width - 1.0, 2.0 * end / width - 1.0))
    return spans


def _tick_years(first: int, last: int) -> list[int]:
    if last - first <= 12:
        return list(range(first, last + 1))
    step = 10 if last - first <= 80 else 20
    return [y for y in range(first - first % step, last + 1, step) if y >= first]


def x_axis(entries: Sequence[SongEntry], spans, x_by: str) -> dict:
    """The x axis object: years proportional (``x_by="year"``) or a tick per year group."""
    first, last = entries[0].year, entries[-1].year
    ticks = []
    if x_by == "year":
        years = _tick_years(first, last)
        width = last + 1 - first
        for year in years:
            ticks.append({"at": round(2.0 * (year - first) / width - 1.0, 6), "label": str(year)})
        return axis("year", "year", first, last + 1, ticks=ticks)
    # By order: a tick at the first song of each year (short ranges) or decade, where one is.
    step = 1 if last - first <= 12 else (10 if last - first <= 80 else 20)
    seen = set()
    for entry, span in zip(entries, spans, strict=True):
        group = entry.year - entry.year % step
        if group not in seen:
            seen.add(group)
            ticks.append({"at": round(span[0], 6), "label": str(max(group, first))})
    # All songs of one year: the axis ends where that year does, as with x by year.
    return axis("year", "year", first, last if last > first else last + 1, ticks=ticks)


def _round(value, digits=4):
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


def timeline_points(
    entries: Sequence[SongEntry],
    songs: dict[str, SongFrames],
    *,
    frames_per_song: int,
    x_by: str = "year",
) -> tuple[np.ndarray, dict]:
    """Points and the ``axes`` / ``songs`` metadata for songs that all have features.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    layout : dict
        ``axes``, ``songs`` (one object per song, in order), ``crest_percentiles_db``.
    """
    if x_by not in X_BY:
        raise ExtractError(f"x_by must be one of {', '.join(X_BY)}, got {x_by!r}")
    entries = sort_entries(entries)
    all_crest = np.concatenate([songs[e.path].crest_db for e in entries]).astype(np.float64)
    all_crest = all_crest[np.isfinite(all_crest)]
    if all_crest.size:
        crest_low, crest_high = (float(v) for v in np.percentile(all_crest, CREST_PERCENTILES))
    else:
        crest_low = crest_high = 0.0
    spans = song_spans(entries, x_by)
    blocks, described = [], []
    offset = 0
    for entry, (x_min, x_max) in zip(entries, spans, strict=True):
        song = songs[entry.path]
        index = sample_frames(song.rms_dbfs.shape[0], frames_per_song)
        m = index.shape[0]
        x = x_min + (x_max - x_min) * (np.arange(m) + 0.5) / max(m, 1)
        rms = np.nan_to_num(song.rms_dbfs[index].astype(np.float64), nan=-200.0, neginf=-200.0)
        y = np.clip(
            2.0 * (rms - LEVEL_MIN_DBFS) / (LEVEL_MAX_DBFS - LEVEL_MIN_DBFS) - 1.0, -1.0, 1.0
        )
        crest = song.crest_db[index].astype(np.float64)
        z = percentile_map(np.nan_to_num(crest, nan=crest_low), crest_low, crest_high)
        la = np.nan_to_num(song.loudness_a_db[index].astype(np.float64), nan=-200.0, neginf=-200)
        scalar = np.clip((la - SCALAR_FLOOR_DB) / -SCALAR_FLOOR_DB, 0.0, 1.0)
        hp = np.clip(np.nan_to_num(song.hp_mean[index].astype(np.float64), nan=0.5), 0.0, 1.0)
        blocks.append(np.stack([x, y, z, scalar, hp], axis=1))
        described.append(
            {
                "path": entry.path,
                "year": entry.year,
                "title": entry.title,
                "artist": entry.artist,
                "x_min": round(x_min, 6),
                "x_max": round(x_max, 6),
                "point_offset": offset,
                "point_count": int(m),
                "frames_non_silent": int(song.rms_dbfs.shape[0]),
                "frames_total": int(song.n_frames_total),
                "metrics": {k: _round(song.metrics.get(k)) for k in METRIC_KEYS},
            }
        )
        offset += m
    points = np.concatenate(blocks).astype(np.float32) if blocks else np.zeros((0, 5), np.float32)
    axes = {
        "x": x_axis(entries, spans, x_by),
        "y": level_axis(LEVEL_MIN_DBFS, LEVEL_MAX_DBFS),
        # A constant crest factor: every z is 0, the axis spans half a dB either side.
        "z": axis(
            "crest factor", "dB", *(round(v, 6) for v in spread_range(crest_low, crest_high, 0.5))
        ),
        "scalar": scalar_axis(SCALAR_FLOOR_DB, 0.0),
        "hp": hp_axis(),
    }
    return points, {"axes": axes, "songs": described}
