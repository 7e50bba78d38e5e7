"""Loudness over time for the song metadata: momentary and short-term BS.1770 loudness, PSR,
and the true-peak overs, on the 100 ms segment grid the dynamics already use.

- momentary loudness: 400 ms windows (4 segments), one every 100 ms;
- short-term loudness: 3 s windows (30 segments), one every 100 ms (:class:`Dynamics`);
- PSR: the short-term window's true peak minus its loudness (NaN below -70 LUFS);
- overs: runs of segments whose true peak (4x oversampled, DC-free signal as PSR's) exceeds
  0 dBTP, and -1 dBTP, as ``[start_s, end_s]`` intervals; at most :data:`MAX_OVERS`, the
  closest neighbours merged past that.

A curve has at most :data:`MAX_CURVE_POINTS` values: past 20 minutes at 10 Hz every k-th
window is kept (``rate_hz`` says which). Values are rounded to 0.1 dB; ``null`` where not
measurable (digital silence). docs/FORMAT.md ("loudness") holds the keys.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.dynamics import SHORT_TERM_SEGMENTS, Dynamics

__all__ = ["MAX_CURVE_POINTS", "MAX_OVERS", "MOMENTARY_SEGMENTS", "loudness_curves"]

MOMENTARY_SEGMENTS = 4
#: 20 minutes at 10 Hz; a 60-minute song's three curves stay near 250 KB of JSON.
MAX_CURVE_POINTS = 12000
#: Intervals kept per overs list; past it, neighbouring intervals are merged (the smallest gaps
#: first) so the list still covers the whole song; ``*_count`` says how many there were.
MAX_OVERS = 2000
_OVER_LEVELS = (("overs_0dbtp", 0.0), ("overs_1dbtp", -1.0))


def _rounded(values: np.ndarray) -> list:
    return [round(float(v), 1) if math.isfinite(v) else None for v in values]


def _intervals(flags: np.ndarray, boundaries: np.ndarray, rate: float) -> list[list[float]]:
    """Runs of True in ``flags`` (one per segment) as ``[start_s, end_s]``."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [
        [round(boundaries[a] / rate, 3), round(boundaries[b] / rate, 3)]
        for a, b in zip(starts, stops, strict=True)
    ]


def _merged(intervals: list[list[float]], limit: int) -> list[list[float]]:
    """At most ``limit`` intervals covering every one of ``intervals``: the gaps between
    neighbours are closed, smallest first, until ``limit`` remain (a long song's overs stay
    marked everywhere they occur instead of only in its first part)."""
    if len(intervals) <= limit:
        return intervals
    if limit <= 0:
        return []
    starts = np.array([a for a, _ in intervals])
    ends = np.array([b for _, b in intervals])
    gaps = starts[1:] - ends[:-1]
    # Keep the (limit - 1) widest gaps open; ties close the later ones first (stable sort).
    keep = np.sort(np.argsort(-gaps, kind="stable")[: limit - 1])
    first = np.concatenate([[0], keep + 1])
    last = np.concatenate([keep, [len(intervals) - 1]])
    return [[float(starts[a]), float(ends[b])] for a, b in zip(first, last, strict=True)]


def loudness_curves(
    energy: np.ndarray,
    boundaries: np.ndarray,
    *,
    segment_peak: np.ndarray,
    dynamics: Dynamics,
    sample_rate: float,
) -> dict:
    """The ``loudness`` metadata object.

    Parameters
    ----------
    energy : np.ndarray [shape=(n_segments,)]
        Channel-weighted K-filtered energy (sum of squares) per 100 ms segment.
    boundaries : np.ndarray [shape=(n_segments + 1,)]
        Segment boundaries in samples.
    segment_peak : np.ndarray [shape=(n_segments,)]
        Linear true peak per segment.
    dynamics : Dynamics
        The 3 s windows of the same segments.
    sample_rate : float

    Returns
    -------
    curves : dict
        ``rate_hz``, ``momentary_start_s``, ``momentary_lufs``, ``short_term_start_s``,
        ``short_term_lufs``, ``psr_db``, ``overs_0dbtp``, ``overs_0dbtp_count``,
        ``overs_1dbtp``, ``overs_1dbtp_count`` (see the module docstring).
    """
    n_segments = energy.shape[0]
    segment_s = 0.1
    lengths = np.diff(boundaries).astype(np.float64)
    step = max(1, -(-max(n_segments, 1) // MAX_CURVE_POINTS))
    n = min(MOMENTARY_SEGMENTS, n_segments)
    if n_segments:
        sums = sliding_window_view(energy, n).sum(axis=-1)
        counts = sliding_window_view(lengths, n).sum(axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            momentary = -0.691 + 10.0 * np.log10(sums / counts)
    else:
        momentary = np.zeros(0)
    short_n = min(SHORT_TERM_SEGMENTS, n_segments)
    curves = {
        "rate_hz": round(1.0 / (segment_s * step), 6),
        "momentary_start_s": round(n * segment_s / 2.0, 3),
        "momentary_lufs": _rounded(momentary[::step]),
        "short_term_start_s": round(short_n * segment_s / 2.0, 3),
        "short_term_lufs": _rounded(dynamics.short_term_lufs[::step]),
        "psr_db": _rounded(dynamics.psr_db[::step]),
    }
    for key, level in _OVER_LEVELS:
        over = np.asarray(segment_peak) > 10.0 ** (level / 20.0)
        intervals = _intervals(over, boundaries, float(sample_rate))
        curves[key] = _merged(intervals, MAX_OVERS)
        curves[f"{key}_count"] = len(intervals)
    return curves
