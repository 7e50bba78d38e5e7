"""Song mode: one point per surviving STFT bin, ``[x, y, z, scalar, hp]``, and its metadata."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.features import HPSS_KERNEL, HPSS_MARGIN, HPSS_POWER, TrackFeatures
from loudscape_extract.floor import floor_keep_mask, taper_width
from loudscape_extract.format import (
    FORMAT_VERSION,
    MODE_SONG,
    axis,
    frequency_axis,
    hp_axis,
    level_axis,
    rounded,
    scalar_axis,
)
from loudscape_extract.normalization import streaming_gains
from loudscape_extract.spectrogram import a_weighting_db

__all__ = [
    "DEFAULT_FLOOR_DB",
    "MAX_FLOOR_DB",
    "FREQ_SCALES",
    "AUDIBLE_HZ",
    "SCALAR_MAX_DB",
    "SCALAR_MIN_DB",
    "SongCloud",
    "song_metadata",
    "song_points",
]

#: Bins more than this many dB below the track's loudest bin are dropped (0 keeps every bin);
#: above it the floor fades in (:mod:`loudscape_extract.floor`).
DEFAULT_FLOOR_DB = 80.0
#: The largest noise floor (dB below the loudest bin): beyond any audio's range (24-bit PCM
#: spans 144 dB), and small enough that 10 ** (floor / 10) stays a float64.
MAX_FLOOR_DB = 400.0
#: ``scalar`` maps the A-weighted bin level linearly to [0, 1] over a range that holds every
#: drawn bin at or above :data:`AUDIBLE_HZ`: ``[y_min + A_min, y_max + A_max]``, with ``A_min``,
#: ``A_max`` the A-weighting gains' range over those bins, widened to at least
#: [SCALAR_MIN_DB, SCALAR_MAX_DB]. 0 dB is a full-scale sine in the bin (at 1 kHz, where
#: A-weighting is 0 dB). The noise floor is the one rule that drops bins; no drawn audible bin
#: is clipped to 0 (the paper's low-frequency cliff), whatever the track's level.
SCALAR_MIN_DB = -100.0
SCALAR_MAX_DB = 0.0
#: Bins below this have no meaningful A-weighted level (0 Hz: -inf); their scalar clips to 0.
AUDIBLE_HZ = 20.0
FREQ_SCALES = ("linear", "log")


@dataclass(frozen=True)
class SongCloud:
    """Song-mode points and what is needed to describe them.

    Attributes
    ----------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
        Columns x (time), y (level), z (frequency), scalar (A-weighted level), hp; frame-major
        order (all points of the first kept frame by ascending frequency, then the next frame).
    axes : dict
        The ``axes`` metadata object (see docs/FORMAT.md).
    frames_total, frames_kept : int
        STFT frames, and frames left after dropping silent ones.
    peak_level_db : float
        Level of the loudest bin (dB re a full-scale sine).
    floor_db : float
        The floor used (0: disabled).
    freq_scale : str
    """

    points: np.ndarray
    axes: dict
    frames_total: int
    frames_kept: int
    peak_level_db: float
    floor_db: float
    freq_scale: str

    @property
    def point_count(self) -> int:
        return int(self.points.shape[0])


def _normalize(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """Map [low, high] to [-1, 1] (0 when the range is empty)."""
    if high <= low:
        return np.zeros(values.shape, dtype=np.float32)
    out = (values.astype(np.float64) - low) * (2.0 / (high - low)) - 1.0
    return np.clip(out, -1.0, 1.0).astype(np.float32)


def scalar_range(frequencies: np.ndarray, y_low: float, y_high: float) -> tuple[float, float]:
    """The scalar's dB range for drawn levels in ``[y_low, y_high]`` (see :data:`AUDIBLE_HZ`).

    Rounded outward to whole dB so the axis reads cleanly.
    """
    audible = frequencies[frequencies >= AUDIBLE_HZ]
    gains = a_weighting_db(audible) if audible.size else np.zeros(1)
    low = min(SCALAR_MIN_DB, math.floor(y_low + float(gains.min())))
    high = max(SCALAR_MAX_DB, math.ceil(y_high + float(gains.max())))
    return float(low), float(high)


def song_points(
    features: TrackFeatures, *, floor_db: float = DEFAULT_FLOOR_DB, freq_scale: str = "linear"
) -> SongCloud:
    """Turn per-bin features into Song-mode points.

    Silent frames are dropped; x is the frame time mapped from [first, last] kept frame to
    [-1, 1]. With ``freq_scale="log"`` the DC bin (0 Hz, no place on a log axis) is dropped.
    Bins whose level is more than ``floor_db`` below the loudest remaining bin are dropped, and
    the floor fades in over the :func:`~loudscape_extract.floor.taper_width` dB above it
    (:func:`~loudscape_extract.floor.floor_keep_mask`: the fraction of bins kept rises
    linearly from 0 at the floor to 1, so no band ends in a wall at the floor); y maps
    [peak - floor_db, peak] (or [quietest, peak] with the floor disabled) to [-1, 1].

    Parameters
    ----------
    features : TrackFeatures
    floor_db : float
        Noise floor below the track's peak bin level in dB, >= 0; 0 disables it.
    freq_scale : {"linear", "log"}
        z linear in bin index (the paper) or in log10 of frequency.

    Returns
    -------
    cloud : SongCloud
    """
    if freq_scale not in FREQ_SCALES:
        raise ExtractError(f"freq_scale must be one of {FREQ_SCALES}, got {freq_scale!r}")
    if not 0 <= floor_db <= MAX_FLOOR_DB:  # NaN fails too
        raise ExtractError(f"floor_db must be from 0 to {MAX_FLOOR_DB:g} dB, got {floor_db}")
    kept_frames = np.flatnonzero(~features.frames.silent)
    if kept_frames.size == 0:
        raise ExtractError("audio is entirely silent (no frame has a non-zero sample)")
    first_bin = 0 if freq_scale == "linear" else 1
    z_per_bin, z_axis = frequency_axis(features.frequencies_hz, freq_scale)
    z_per_bin = z_per_bin[first_bin:].astype(np.float32)

    levels = features.level_db[first_bin:, kept_frames].T  # (n_kept, n_bins_drawn)
    peak = float(levels.max())
    if floor_db > 0:
        y_low = peak - floor_db
        keep = floor_keep_mask(
            levels,
            frame_index=kept_frames,
            bin_index=np.arange(first_bin, first_bin + levels.shape[1]),
            y_min=y_low,
            floor_db=floor_db,
        )
    else:
        y_low = float(levels.min())
        keep = np.ones(levels.shape, dtype=bool)
    n_points = int(np.count_nonzero(keep))
    if n_points == 0:
        raise ExtractError("no bin is left above the noise floor")

    times = features.frames.times_s[kept_frames]
    t_first, t_last = float(times[0]), float(times[-1])
    points = np.empty((n_points, 5), dtype=np.float32)
    x_per_frame = _normalize(times, t_first, t_last)
    points[:, 0] = np.broadcast_to(x_per_frame[:, None], keep.shape)[keep]
    points[:, 1] = _normalize(levels[keep], y_low, peak)
    points[:, 2] = np.broadcast_to(z_per_bin[None, :], keep.shape)[keep]
    levels_a = features.level_a_db[first_bin:, kept_frames].T[keep]
    s_low, s_high = scalar_range(features.frequencies_hz[first_bin:], y_low, peak)
    scalar = (levels_a.astype(np.float64) - s_low) / (s_high - s_low)
    points[:, 3] = np.clip(scalar, 0.0, 1.0)
    points[:, 4] = features.hp[first_bin:, kept_frames].T[keep]

    # One kept frame, or one level everywhere: the axis gets a range around the single value
    # (half a hop of time, half a dB) and the points sit at its middle (docs/FORMAT.md).
    x_low, x_high = spread_range(t_first, t_last, features.hop_length / features.sample_rate / 2)
    y_axis_low, y_axis_high = spread_range(y_low, peak, 0.5)
    axes = {
        "x": axis("time", "s", x_low, x_high),
        "y": level_axis(y_axis_low, y_axis_high),
        "z": z_axis,
        "scalar": scalar_axis(s_low, s_high),
        "hp": hp_axis(),
    }
    return SongCloud(
        points=points,
        axes=axes,
        frames_total=int(features.frames.silent.size),
        frames_kept=int(kept_frames.size),
        peak_level_db=peak,
        floor_db=float(floor_db),
        freq_scale=freq_scale,
    )


def song_metadata(
    features: TrackFeatures, cloud: SongCloud, *, generator: str, source_format: str = ""
) -> dict:
    """The ``comment loudscape-meta`` object for a Song-mode file (see docs/FORMAT.md).

    Parameters
    ----------
    features : TrackFeatures
        Or anything with its attributes ``path``, ``sample_rate``, ``n_channels``,
        ``duration_s``, ``n_fft``, ``hop_length``, ``metrics``, ``highpass_hz`` (such as
        :class:`loudscape_extract.stream.StreamedTrack`).
    cloud : SongCloud
        Or anything with its attributes but ``point_count`` for ``points`` (such as
        :class:`loudscape_extract.stream_points.StreamedCloud`).
    generator : str
        Program name and version, e.g. ``"loudscape-extract 0.1.0"``.
    source_format : str
        Container/encoding of the source, e.g. ``"WAV/PCM_16"``.

    Returns
    -------
    metadata : dict
        JSON-ready; floats rounded to 6 decimals (metrics to 4).
    """
    metadata = {
        "format_version": FORMAT_VERSION,
        "mode": MODE_SONG,
        "point_count": cloud.point_count,
        "source": {
            "path": features.path,
            "format": source_format,
            "sample_rate": features.sample_rate,
            "channels": features.n_channels,
            "duration_s": rounded(features.duration_s, 6),
        },
        "stft": {
            "n_fft": features.n_fft,
            "hop_length": features.hop_length,
            "window": "hann",
            "center": True,
            "frames": cloud.frames_total,
            "frames_kept": cloud.frames_kept,
        },
        "axes": rounded(cloud.axes, 6),
        "metrics": rounded(features.metrics, 4),
        "streaming": rounded(streaming_gains(features.metrics), 2),
        "extraction": {
            "floor_db": rounded(cloud.floor_db, 6),
            "floor_taper_db": rounded(taper_width(cloud.floor_db), 6),
            "freq_scale": cloud.freq_scale,
            "dc_removed": True,
            "highpass_hz": features.highpass_hz,
            "hpss": {"kernel_size": HPSS_KERNEL, "power": HPSS_POWER, "margin": HPSS_MARGIN},
            "generator": generator,
        },
    }
    curves = getattr(features, "curves", None)
    if curves is not None:
        metadata["loudness"] = curves
    return metadata
