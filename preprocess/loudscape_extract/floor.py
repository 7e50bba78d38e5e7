"""The one rule that drops and keeps Song-mode bins near the noise floor.

A hard floor (keep ``L >= L_peak - floor_db``, drop the rest) cuts a band at whatever density
it has at that level. On a quiet track the 4-22 kHz band's noise hump sits right there, so the
cloud ended in a wall at exactly the floor, at that band's densest level. The rule here fades
the floor instead: a bin at level ``L`` is kept when

    u(frame, bin) < clip((L - y_min) / taper_db, 0, 1)

with ``y_min = L_peak - floor_db`` and ``u`` a fixed pseudo-random number in [0, 1) computed
from the absolute frame and bin indices (a SplitMix64 hash, so the same bin is kept or dropped
in the whole-track and the streamed path, on every machine). Bins at or above
``y_min + taper_db`` are always kept; bins below ``y_min`` never (the ramp is 0 and ``u >= 0``);
in between, the fraction kept rises linearly, so every band's point density falls to zero at
the floor instead of stopping at its densest level. The kept bins keep their exact values.
docs/FORMAT.md (step 6) and docs/DYNAMICS.md hold the rule and its measurements.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FLOOR_TAPER_DB", "bin_uniform", "floor_keep_mask", "taper_width"]

#: Width of the fade above the floor in dB (at most half the floor).
FLOOR_TAPER_DB = 12.0

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


def taper_width(floor_db: float) -> float:
    """The fade's width in dB for a floor of ``floor_db`` (0 when the floor is disabled)."""
    return min(FLOOR_TAPER_DB, 0.5 * floor_db) if floor_db > 0 else 0.0


def bin_uniform(frame_index: np.ndarray, bin_index: np.ndarray) -> np.ndarray:
    """A fixed number in [0, 1) per (frame, bin) pair, from their absolute indices.

    Parameters
    ----------
    frame_index, bin_index : np.ndarray [shape=(n,)]
        STFT frame indices (of the whole track, silent frames counted) and FFT bin indices
        (0 = DC), or any shapes that broadcast together.

    Returns
    -------
    u : np.ndarray [dtype=float64]
        The broadcast shape; uniform over [0, 1) in distribution.
    """
    frames = np.asarray(frame_index, dtype=np.uint64)
    bins = np.asarray(bin_index, dtype=np.uint64)
    x = (frames * np.uint64(1 << 20) + bins + np.uint64(1)) * _GOLDEN
    x ^= x >> np.uint64(30)
    x *= _MIX1
    x ^= x >> np.uint64(27)
    x *= _MIX2
    x ^= x >> np.uint64(31)
    return (x >> np.uint64(11)).astype(np.float64) * (1.0 / (1 << 53))


def floor_keep_mask(
    levels: np.ndarray,
    *,
    frame_index: np.ndarray,
    bin_index: np.ndarray,
    y_min: float,
    floor_db: float,
) -> np.ndarray:
    """Which bins the floor keeps (see the module docstring).

    Parameters
    ----------
    levels : np.ndarray [shape=(n_frames, n_bins), dtype=float32]
        Bin levels in dB, frame-major.
    frame_index, bin_index : np.ndarray
        Absolute indices of the rows and columns of ``levels``.
    y_min : float
        ``L_peak - floor_db``.
    floor_db : float
        > 0 (a disabled floor keeps every bin and does not call this).

    Returns
    -------
    keep : np.ndarray [shape=levels.shape, dtype=bool]
    """
    taper = taper_width(floor_db)
    keep = levels >= np.float32(y_min + taper)
    rows, cols = np.nonzero(~keep & (levels > np.float32(y_min)))
    if rows.size:
        ramp = (levels[rows, cols].astype(np.float64) - y_min) * (1.0 / taper)
        u = bin_uniform(np.asarray(frame_index)[rows], np.asarray(bin_index)[cols])
        keep[rows, cols] = u < ramp
    return keep


def floor_edge_ratio(levels_db: np.ndarray, *, y_min: float, span_db: float = 40.0) -> float:
    """How hard a band stops at the floor: its point density in the 1 dB just above the floor
    over its densest 1 dB in ``[y_min, y_min + span_db)`` (1: a wall at its densest level;
    near 0: the density fades out before the floor).

    Parameters
    ----------
    levels_db : np.ndarray [shape=(n,)]
        Levels of the band's drawn points in dB.
    y_min : float
        The floor level.

    Returns
    -------
    ratio : float
        NaN when no point lies in the span.
    """
    counts, _ = np.histogram(levels_db, bins=int(span_db), range=(y_min, y_min + span_db))
    return float(counts[0] / counts.max()) if counts.max() > 0 else float("nan")
