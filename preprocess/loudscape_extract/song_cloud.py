"""Song mode's rules, one copy for the streamed pipeline and the whole-track reference.

Production (:func:`~loudscape_extract.song.extract_song`) places points block by block
(:mod:`loudscape_extract.stream_points`); the whole-track reference
(:func:`~loudscape_extract.points.song_points`, which tests hold the files equal to) places
them all at once. Both take from here: the options' checks, the keep rule (the noise floor and
its fade), the mapping of a bin to its ``[x, y, z, scalar, hp]`` row, the ``axes`` object and
the file's metadata, which reads its track and cloud through the :class:`SongSource` and
:class:`SongCloudFacts` protocols.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
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
from loudscape_extract.hpss import HPSS_KERNEL, HPSS_MARGIN, HPSS_POWER
from loudscape_extract.normalization import streaming_gains
from loudscape_extract.spectrogram import a_weighting_db

__all__ = [
    "AUDIBLE_HZ",
    "CloudDescription",
    "DEFAULT_FLOOR_DB",
    "FREQ_SCALES",
    "MAX_FLOOR_DB",
    "SCALAR_MAX_DB",
    "SCALAR_MIN_DB",
    "SongCloudFacts",
    "SongMapping",
    "SongSource",
    "check_song_options",
    "first_drawn_bin",
    "normalize",
    "scalar_range",
    "song_mapping",
    "song_metadata",
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


@runtime_checkable
class SongSource(Protocol):
    """What :func:`song_metadata` reads of a track: a :class:`~loudscape_extract.stream.
    StreamedTrack` (production) or a :class:`~loudscape_extract.features.TrackFeatures`."""

    @property
    def path(self) -> str: ...
    @property
    def sample_rate(self) -> int: ...
    @property
    def n_channels(self) -> int: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def n_fft(self) -> int: ...
    @property
    def hop_length(self) -> int: ...
    @property
    def metrics(self) -> dict: ...
    @property
    def highpass_hz(self) -> float | None: ...
    @property
    def curves(self) -> dict | None: ...


@runtime_checkable
class SongCloudFacts(Protocol):
    """What :func:`song_metadata` reads of a cloud: a :class:`~loudscape_extract.
    stream_points.StreamedCloud` (production) or a :class:`~loudscape_extract.points.SongCloud`."""

    @property
    def point_count(self) -> int: ...
    @property
    def axes(self) -> dict: ...
    @property
    def frames_total(self) -> int: ...
    @property
    def frames_kept(self) -> int: ...
    @property
    def floor_db(self) -> float: ...
    @property
    def freq_scale(self) -> str: ...


@dataclass(frozen=True)
class CloudDescription:
    """What a Song-mode cloud says of itself besides its points (and their count).

    Attributes
    ----------
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

    axes: dict
    frames_total: int
    frames_kept: int
    peak_level_db: float
    floor_db: float
    freq_scale: str


def check_song_options(*, floor_db: float, freq_scale: str) -> None:
    """Refuse a ``freq_scale`` or ``floor_db`` Song mode does not know.

    Raises
    ------
    ExtractError
    """
    if freq_scale not in FREQ_SCALES:
        raise ExtractError(f"freq_scale must be one of {FREQ_SCALES}, got {freq_scale!r}")
    if not 0 <= floor_db <= MAX_FLOOR_DB:  # NaN fails too
        raise ExtractError(f"floor_db must be from 0 to {MAX_FLOOR_DB:g} dB, got {floor_db}")


def normalize(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """Map [low, high] to [-1, 1] as float32 (0 when the range is empty)."""
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


def first_drawn_bin(freq_scale: str) -> int:
    """0, or 1 on a log frequency axis (the 0 Hz bin has no place on it)."""
    return 0 if freq_scale == "linear" else 1


@dataclass(frozen=True)
class SongMapping:
    """Where the kept bins of one cloud go: its final ``axes`` and the rules every row follows.

    Attributes
    ----------
    axes : dict
        The ``axes`` metadata object (docs/FORMAT.md).
    freq_scale : str
    floor_db : float
    first_bin : int
        :func:`first_drawn_bin`.
    y_low, y_high : float
        The bin levels mapped to y = -1 and y = 1 (the floor, or the quietest bin; the peak).
    scalar_low, scalar_high : float
        The A-weighted levels mapped to scalar 0 and 1.
    x_per_kept : np.ndarray [shape=(n_kept_frames,), dtype=float32]
        x of each kept frame.
    z_per_bin : np.ndarray [shape=(n_bins_drawn,), dtype=float32]
    """

    axes: dict
    freq_scale: str
    floor_db: float
    first_bin: int
    y_low: float
    y_high: float
    scalar_low: float
    scalar_high: float
    x_per_kept: np.ndarray
    z_per_bin: np.ndarray

    def keep(self, levels: np.ndarray, *, frame_index: np.ndarray) -> np.ndarray:
        """Which bins of ``levels`` (kept frames x drawn bins, dB; ``frame_index`` their
        absolute frame numbers) become points: the noise floor and its fade
        (:func:`~loudscape_extract.floor.floor_keep_mask`), or all with no floor."""
        if self.floor_db <= 0:
            return np.ones(levels.shape, dtype=bool)
        bins = np.arange(self.first_bin, self.first_bin + levels.shape[1])
        return floor_keep_mask(
            levels,
            frame_index=frame_index,
            bin_index=bins,
            y_min=self.y_low,
            floor_db=self.floor_db,
        )

    def rows(
        self,
        keep: np.ndarray,
        *,
        x: np.ndarray,
        levels: np.ndarray,
        levels_a: np.ndarray,
        hp: np.ndarray,
    ) -> np.ndarray:
        """The rows of the kept bins, frame-major, float32 ``[x, y, z, scalar, hp]``.

        Parameters
        ----------
        keep : np.ndarray [shape=(n_frames, n_bins_drawn), dtype=bool]
        x : np.ndarray [shape=(n_frames,)]
            x of each frame (from :attr:`x_per_kept`).
        levels : np.ndarray [shape=(n_frames, n_bins_drawn)]
            Bin levels in dB.
        levels_a, hp : np.ndarray [shape=(n_kept,)]
            A-weighted level and hp of the kept bins, in ``keep``'s order.
        """
        points = np.empty((int(np.count_nonzero(keep)), 5), dtype=np.float32)
        points[:, 0] = np.broadcast_to(x[:, None], keep.shape)[keep]
        points[:, 1] = normalize(levels[keep], self.y_low, self.y_high)
        points[:, 2] = np.broadcast_to(self.z_per_bin[None, :], keep.shape)[keep]
        span = self.scalar_high - self.scalar_low
        points[:, 3] = np.clip((levels_a.astype(np.float64) - self.scalar_low) / span, 0.0, 1.0)
        points[:, 4] = hp
        return points


def song_mapping(
    *,
    kept_times_s: np.ndarray,
    frequencies_hz: np.ndarray,
    peak_db: float,
    quietest_db: float,
    floor_db: float,
    freq_scale: str,
    half_hop_s: float,
) -> SongMapping:
    """The mapping of a cloud whose kept frames are at ``kept_times_s`` and whose drawn bins
    reach ``peak_db`` (and ``quietest_db``, used when the floor is off)."""
    first_bin = first_drawn_bin(freq_scale)
    z_per_bin, z_axis = frequency_axis(frequencies_hz, freq_scale)
    y_low = peak_db - floor_db if floor_db > 0 else quietest_db
    t_first, t_last = float(kept_times_s[0]), float(kept_times_s[-1])
    s_low, s_high = scalar_range(frequencies_hz[first_bin:], y_low, peak_db)
    # One kept frame, or one level everywhere: the axis gets a range around the single value
    # (half a hop of time, half a dB) and the points sit at its middle (docs/FORMAT.md).
    x_low, x_high = spread_range(t_first, t_last, half_hop_s)
    y_axis_low, y_axis_high = spread_range(y_low, peak_db, 0.5)
    axes = {
        "x": axis("time", "s", x_low, x_high),
        "y": level_axis(y_axis_low, y_axis_high),
        "z": z_axis,
        "scalar": scalar_axis(s_low, s_high),
        "hp": hp_axis(),
    }
    return SongMapping(
        axes=axes,
        freq_scale=freq_scale,
        floor_db=float(floor_db),
        first_bin=first_bin,
        y_low=y_low,
        y_high=peak_db,
        scalar_low=s_low,
        scalar_high=s_high,
        x_per_kept=normalize(kept_times_s, t_first, t_last),
        z_per_bin=z_per_bin[first_bin:].astype(np.float32),
    )


def song_metadata(
    features: SongSource, cloud: SongCloudFacts, *, generator: str, source_format: str = ""
) -> dict:
    """The ``comment loudscape-meta`` object for a Song-mode file (see docs/FORMAT.md).

    Parameters
    ----------
    features : SongSource
        The track's description and metrics.
    cloud : SongCloudFacts
        The cloud's description.
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
    if features.curves is not None:
        metadata["loudness"] = features.curves
    return metadata
