"""Timeline layout: song order and spans on x, the x axis, frame sampling, and the points."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import METRIC_KEYS, axis, hp_axis, scalar_axis
from loudscape_extract.notices import track_warnings
from loudscape_extract.timeline.frames import SongFrames
from loudscape_extract.timeline.inputs import SongEntry
from loudscape_extract.timeline.series import (
    DEFAULT_Y_MEASURE,
    DEFAULT_Z_MEASURE,
    Y_MEASURES,
    Z_MEASURES,
    y_measure_of,
    z_measure_of,
)

__all__ = [
    "CREST_PERCENTILES",
    "DEFAULT_MAX_POINTS",
    "MIN_FRAMES_PER_SONG",
    "SampledSong",
    "frames_per_song_for",
    "sample_song",
    "LEVEL_MAX_DBFS",
    "LEVEL_MIN_DBFS",
    "METRIC_KEYS",
    "SCALAR_FLOOR_DB",
    "DEFAULT_Y_MEASURE",
    "DEFAULT_Z_MEASURE",
    "Y_MEASURES",
    "y_axis",
    "X_BY",
    "Z_MEASURES",
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
#: Default cap on a timeline's points (``--max-points``): see :func:`frames_per_song_for`.
DEFAULT_MAX_POINTS = 4_000_000
#: No song is drawn with fewer frames than this because of the cap.
MIN_FRAMES_PER_SONG = 64


def frames_per_song_for(n_songs: int, requested: int, max_points: int | None) -> int:
    """Frames drawn per song: ``requested``, lowered so ``n_songs`` songs stay under
    ``max_points`` points, but never below :data:`MIN_FRAMES_PER_SONG` (or ``requested``).

    ``min(requested, max(MIN_FRAMES_PER_SONG, max_points // n_songs))``; ``max_points`` None
    or 0: no cap. With the defaults (1024 frames, 4,000,000 points) up to 3,906 songs keep
    1024 frames, 10,000 songs get 400 and more than 62,500 songs get 64 each.
    """
    if requested < 1:
        raise ExtractError(f"frames per song must be >= 1, got {requested}")
    if not max_points or n_songs <= 0:
        return requested
    return min(requested, max(MIN_FRAMES_PER_SONG, max_points // n_songs))


@dataclass(frozen=True)
class SampledSong:
    """What the layout keeps of one song: its drawn frames only, so a timeline of many songs
    holds a few hundred numbers per song, not every frame (computed where the song is).

    Attributes
    ----------
    rms_dbfs, measure, loudness_a_db, hp_mean : np.ndarray [shape=(n_drawn,)]
        The drawn frames' series; ``measure`` is the chosen z measure's.
    momentary_lufs, short_term_lufs : np.ndarray [shape=(n_drawn,)]
        The drawn frames' loudness (the y measures besides ``rms_dbfs`` and
        ``loudness_a_db``).
    neutral : float or None
        Median of the z measure over all the song's non-silent frames (frames without a value
        take it); None when no frame has one.
    frames_non_silent, frames_total : int
    metrics : dict
    warning : str
        The decoder's note on a truncated or corrupt file (:attr:`SongFrames.warning`).
    warnings : list of dict
        Every warning about the song (:func:`notices.track_warnings`), as its ``songs[i]``
        metadata carries them.
    """

    rms_dbfs: np.ndarray
    measure: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    neutral: float | None
    frames_non_silent: int
    frames_total: int
    metrics: dict
    warning: str = ""
    warnings: list = field(default_factory=list)
    momentary_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    short_term_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))

    def level(self, y_measure: str) -> np.ndarray:
        """The drawn frames' y measure (one of :data:`Y_MEASURES`), NaN where unknown."""
        values = getattr(self, y_measure_of(y_measure).series)
        if values.shape != self.rms_dbfs.shape:  # a series the song was computed without
            return np.full(self.rms_dbfs.shape, np.nan, np.float32)
        return values


def sample_song(song: SongFrames, *, frames_per_song: int, z_measure: str) -> SampledSong:
    """The frames :func:`timeline_points` draws of ``song`` (:func:`sample_frames`)."""
    series = z_measure_of(z_measure).series
    index = sample_frames(song.rms_dbfs.shape[0], frames_per_song)
    measure = getattr(song, series)
    finite = measure[np.isfinite(measure)].astype(np.float64)
    return SampledSong(
        rms_dbfs=song.rms_dbfs[index],
        measure=measure[index],
        loudness_a_db=song.loudness_a_db[index],
        hp_mean=song.hp_mean[index],
        neutral=float(np.median(finite)) if finite.size else None,
        frames_non_silent=int(song.rms_dbfs.shape[0]),
        frames_total=int(song.n_frames_total),
        metrics=dict(song.metrics),
        warning=song.warning,
        warnings=track_warnings(
            decode_warning=song.warning, metrics=song.metrics, signal=song.signal
        ),
        momentary_lufs=_drawn(song.momentary_lufs, index, song.rms_dbfs.shape[0]),
        short_term_lufs=_drawn(song.short_term_lufs, index, song.rms_dbfs.shape[0]),
    )


def _drawn(values: np.ndarray, index: np.ndarray, n: int) -> np.ndarray:
    """``values[index]``, or NaN when the series is missing (a song built without it)."""
    if values.shape[0] != n:
        return np.full(index.shape, np.nan, np.float32)
    return values[index]


def sample_frames(n_frames: int, count: int) -> np.ndarray:
    """Indices of ``count`` frames spread evenly over ``n_frames`` (all of them if fewer)."""
    if n_frames <= count:
        return np.arange(n_frames)
    return np.round(np.linspace(0, n_frames - 1, count)).astype(np.int64)


def sort_entries(entries: Sequence[SongEntry]) -> list[SongEntry]:
    """By year, then artist, then title (case-insensitive), then path; songs without a year
    (only with ``x_by="order"``) last."""
    return sorted(
        entries,
        key=lambda e: (
            e.year is None,
            e.year or 0,
            e.artist.casefold(),
            e.title.casefold(),
            e.path,
        ),
    )


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
    per_year: dict[int, int] = {}
    for entry in entries:
        per_year[entry.year] = per_year.get(entry.year, 0) + 1
    seen: dict[int, int] = {}
    spans = []
    for entry in entries:
        k = seen.get(entry.year, 0)
        seen[entry.year] = k + 1
        same = per_year[entry.year]
        start = entry.year - first + k / same
        end = entry.year - first + (k + 1) / same
        spans.append((2.0 * start / width - 1.0, 2.0 * end / width - 1.0))
    return spans


#: At most this many year ticks on the x axis (the pictures lay out 8 ticks an axis).
MAX_YEAR_TICKS = 8


def _year_step(first: int, last: int) -> int:
    """The smallest of 1, 2, 5, 10, 20, 50, ... years that puts at most ``MAX_YEAR_TICKS``
    multiples of itself in ``first .. last`` (1996 to 2009: every 2 years)."""
    step, factors = 1, (2, 2.5, 2)
    k = 0
    while last // step - (first + step - 1) // step + 1 > MAX_YEAR_TICKS:
        step = round(step * factors[k % 3])
        k += 1
    return step


def _tick_years(first: int, last: int) -> list[int]:
    if last - first < MAX_YEAR_TICKS:
        return list(range(first, last + 1))
    step = _year_step(first, last)
    return [y for y in range(first - first % step, last + 1, step) if y >= first]


def x_axis(entries: Sequence[SongEntry], spans, x_by: str) -> dict:
    """The x axis object: years proportional (``x_by="year"``) or a tick per year group."""
    dated = [e.year for e in entries if e.year is not None]
    if not dated:  # by order, no song has a year: the axis counts songs, song k in [k-1, k]
        return axis("song", "", 0, len(entries), ticks=[])
    first, last = min(dated), max(dated)
    ticks = []
    if x_by == "year":
        years = _tick_years(first, last)
        width = last + 1 - first
        for year in years:
            ticks.append({"at": round(2.0 * (year - first) / width - 1.0, 6), "label": str(year)})
        return axis("year", "year", first, last + 1, ticks=ticks)
    # By order: a tick at the first song of each year (short ranges) or decade, where one is.
    step = 1 if last - first < MAX_YEAR_TICKS else _year_step(first, last)
    seen = set()
    for entry, span in zip(entries, spans, strict=True):
        if entry.year is None:
            continue
        group = entry.year - entry.year % step
        if group not in seen:
            seen.add(group)
            ticks.append({"at": round(span[0], 6), "label": str(max(group, first))})
    # All songs of one year: the axis ends where that year does, as with x by year.
    return axis("year", "year", first, last if last > first else last + 1, ticks=ticks)


def y_axis(y_measure: str) -> dict:
    """The y axis object of ``y_measure``: its label and unit, -60 .. 0, and ``measure``."""
    measure = y_measure_of(y_measure)
    return {
        **axis(measure.label, measure.unit, LEVEL_MIN_DBFS, LEVEL_MAX_DBFS),
        "measure": y_measure,
    }


def _scalar_range(levels: Sequence[np.ndarray]) -> tuple[float, float]:
    """[-100, 0] dB, widened to whole dB so that no drawn frame's level is clipped."""
    values = np.concatenate([np.asarray(v, dtype=np.float64) for v in levels]) if levels else []
    values = np.asarray(values)[np.isfinite(values)] if len(values) else np.zeros(0)
    low, high = SCALAR_FLOOR_DB, 0.0
    if values.size:
        low = min(low, math.floor(float(values.min())))
        high = max(high, math.ceil(float(values.max())))
    return float(low), float(high)


def _round(value, digits=4):
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


def timeline_points(
    entries: Sequence[SongEntry],
    songs: dict[str, SongFrames | SampledSong],
    *,
    frames_per_song: int,
    x_by: str = "year",
    z_measure: str = DEFAULT_Z_MEASURE,
    y_measure: str = DEFAULT_Y_MEASURE,
) -> tuple[np.ndarray, dict]:
    """Points and the ``axes`` / ``songs`` metadata for songs that all have features.

    ``songs`` holds each song's :class:`SongFrames` (sampled here) or its
    :class:`SampledSong` (sampled already, with the same ``frames_per_song`` and
    ``z_measure``, where the song was computed). ``y_measure`` (:data:`Y_MEASURES`) is the
    frame level drawn on y, on the same -60 .. 0 scale whatever its unit.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    layout : dict
        ``axes``, ``songs`` (one object per song, in order), ``crest_percentiles_db``.
    """
    if x_by not in X_BY:
        raise ExtractError(f"x_by must be one of {', '.join(X_BY)}, got {x_by!r}")
    z_axis_of = z_measure_of(z_measure)
    y_measure_of(y_measure)  # refused here, before any work
    if x_by == "year" and any(e.year is None for e in entries):
        raise ExtractError("x_by='year' needs a year for every song")
    entries = sort_entries(entries)
    drawn = {
        e.path: songs[e.path]
        if isinstance(songs[e.path], SampledSong)
        else sample_song(songs[e.path], frames_per_song=frames_per_song, z_measure=z_measure)
        for e in entries
    }
    # The z axis spans the 1st-99th percentiles of the drawn frames of all songs.
    all_crest = np.concatenate([drawn[e.path].measure for e in entries]).astype(np.float64)
    all_crest = all_crest[np.isfinite(all_crest)]
    if all_crest.size:
        crest_low, crest_high = (float(v) for v in np.percentile(all_crest, CREST_PERCENTILES))
    else:
        crest_low = crest_high = 0.0
    spans = song_spans(entries, x_by)
    s_low, s_high = _scalar_range([drawn[e.path].loudness_a_db for e in entries])
    blocks, described = [], []
    offset = 0
    for entry, (x_min, x_max) in zip(entries, spans, strict=True):
        song = drawn[entry.path]
        m = song.rms_dbfs.shape[0]
        x = x_min + (x_max - x_min) * (np.arange(m) + 0.5) / max(m, 1)
        level = song.level(y_measure).astype(np.float64)
        level = np.nan_to_num(level, nan=-200.0, neginf=-200.0)
        y = np.clip(
            2.0 * (level - LEVEL_MIN_DBFS) / (LEVEL_MAX_DBFS - LEVEL_MIN_DBFS) - 1.0, -1.0, 1.0
        )
        # A frame without a value (a 3 s window under -70 LUFS) takes the song's median.
        neutral = crest_low if song.neutral is None else song.neutral
        measure = song.measure.astype(np.float64)
        z = percentile_map(np.nan_to_num(measure, nan=neutral), crest_low, crest_high)
        la = np.nan_to_num(song.loudness_a_db.astype(np.float64), nan=-200.0, neginf=-200)
        scalar = np.clip((la - s_low) / (s_high - s_low), 0.0, 1.0)
        hp = np.clip(np.nan_to_num(song.hp_mean.astype(np.float64), nan=0.5), 0.0, 1.0)
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
                "frames_non_silent": song.frames_non_silent,
                "frames_total": song.frames_total,
                "metrics": {k: _round(song.metrics.get(k)) for k in METRIC_KEYS},
            }
        )
        if song.warnings:  # absent: nothing to say
            described[-1]["warnings"] = [dict(item) for item in song.warnings]
        offset += m
    points = np.concatenate(blocks).astype(np.float32) if blocks else np.zeros((0, 5), np.float32)
    axes = {
        "x": x_axis(entries, spans, x_by),
        "y": y_axis(y_measure),
        "z": {
            **axis(
                z_axis_of.label,
                z_axis_of.unit,
                # A constant z: every z is 0, the axis spans half a dB either side.
                *(round(v, 6) for v in spread_range(crest_low, crest_high, 0.5)),
            ),
            "measure": z_measure,
        },
        "scalar": scalar_axis(s_low, s_high),
        "hp": hp_axis(),
    }
    return points, {"axes": axes, "songs": described}
