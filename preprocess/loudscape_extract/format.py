"""The file format's names: version, modes, and the builders of the ``axes`` objects.

Both modes describe their five columns with the same axis objects (see docs/FORMAT.md)::

    {"label": ..., "unit": ..., "min": ..., "max": ..., "scale": "linear" | "log",
     "ticks": [{"at": -1..1, "label": ...}, ...]}   # ticks optional

Everything that writes metadata builds its axes here, so a label or unit is spelled once.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "FORMAT_VERSION",
    "METRIC_KEYS",
    "MODE_SONG",
    "MODE_TIMELINE",
    "axis",
    "frequency_axis",
    "hp_axis",
    "level_axis",
    "rounded",
    "scalar_axis",
]

#: ``format_version`` of the metadata; readers refuse versions they do not know.
FORMAT_VERSION = 2
MODE_SONG = "song"
MODE_TIMELINE = "timeline"
#: The metrics of a timeline's song entries (docs/FORMAT.md), in the order they are written; the
#: song report's per-song columns are these, in this order.
METRIC_KEYS = (
    "integrated_lufs",
    "lra_lu",
    "sample_peak_dbfs",
    "true_peak_dbtp",
    "plr_db",
    "max_momentary_lufs",
    "max_momentary_s",
    "max_short_term_lufs",
    "max_short_term_s",
    "crest_median_db",
    "crest_p95_db",
    "dc_offset",
    "dr_db",
    "psr_median_db",
    "psr_p10_db",
    "psr_p90_db",
    "psr_spread_db",
    "crest_3s_median_db",
    "hp_mean",
)
_TICK_FREQUENCIES = (20, 50, 100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000)


def axis(
    label: str,
    unit: str,
    low: float,
    high: float,
    *,
    scale: str = "linear",
    ticks: list[dict] | None = None,
) -> dict:
    """One ``axes`` entry: what the normalized column's [-1, 1] (or [0, 1]) means physically."""
    out = {"label": label, "unit": unit, "min": low, "max": high, "scale": scale}
    if ticks is not None:
        out["ticks"] = ticks
    return out


def level_axis(low: float, high: float) -> dict:
    """y: level in dB (re a full-scale sine in Song mode, dBFS RMS in Timeline mode)."""
    return axis("level", "dB", low, high)


def scalar_axis(low: float, high: float) -> dict:
    """scalar: A-weighted level in dB."""
    return axis("A-weighted level", "dB", low, high)


def hp_axis() -> dict:
    """hp: harmonic-percussive ratio, 0 percussive .. 1 harmonic."""
    return axis("harmonic-percussive ratio", "", 0.0, 1.0)


def _frequency_label(hz: float) -> str:
    return f"{hz / 1000:g} kHz" if hz >= 1000 else f"{hz:g} Hz"


def frequency_axis(frequencies: np.ndarray, scale: str) -> tuple[np.ndarray, dict]:
    """Song mode's z: the position of each bin (NaN for bins not drawn) and the axis object.

    Parameters
    ----------
    frequencies : np.ndarray [shape=(n_bins,)]
        Bin centre frequencies in Hz, ascending from 0.
    scale : {"linear", "log"}
        Linear in bin index, or in log10 of frequency (the 0 Hz bin gets NaN).

    Returns
    -------
    z : np.ndarray [shape=(n_bins,)]
    axis : dict
    """
    low = float(frequencies[0] if scale == "linear" else frequencies[1])
    high = float(frequencies[-1])
    z = np.full(frequencies.shape, np.nan)
    if scale == "linear":
        index = np.arange(frequencies.size, dtype=np.float64)
        z[:] = np.clip(index * (2.0 / (frequencies.size - 1)) - 1.0, -1.0, 1.0).astype(np.float32)
        position = lambda f: 2.0 * (f - low) / (high - low) - 1.0  # noqa: E731
    else:
        log_low, log_high = math.log10(low), math.log10(high)
        z[1:] = 2.0 * (np.log10(frequencies[1:]) - log_low) / (log_high - log_low) - 1.0
        position = lambda f: 2.0 * (math.log10(f) - log_low) / (log_high - log_low) - 1.0  # noqa: E731
    ticks = [
        {"at": round(position(f), 6), "label": _frequency_label(f)}
        for f in _TICK_FREQUENCIES
        if low <= f <= high
    ]
    return z, axis("frequency", "Hz", low, high, scale=scale, ticks=ticks)


def rounded(value, digits: int):
    """Round floats (recursively) for stable, readable metadata; NaN/inf become None."""
    if isinstance(value, dict):
        return {key: rounded(item, digits) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [rounded(item, digits) for item in value]
    if isinstance(value, bool | int | str) or value is None:
        return value
    number = float(value)
    if not math.isfinite(number):
        return None
    result = round(number, digits)
    return 0.0 if result == 0 else result
