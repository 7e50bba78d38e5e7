"""Song mode's whole-track reference: :func:`song_points` places every point of a track at
once from :class:`~loudscape_extract.features.TrackFeatures` (every per-bin array in memory).

Production runs the streamed pipeline instead (:func:`~loudscape_extract.song.extract_song`:
:mod:`loudscape_extract.stream_points` block by block); both take their rules from
:mod:`loudscape_extract.song_cloud`, and the tests hold the streamed files equal to this
reference bit for bit. Song mode's constants and :func:`song_metadata` are importable from here
too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.features import TrackFeatures
from loudscape_extract.song_cloud import (
    AUDIBLE_HZ,
    DEFAULT_FLOOR_DB,
    FREQ_SCALES,
    MAX_FLOOR_DB,
    SCALAR_MAX_DB,
    SCALAR_MIN_DB,
    CloudDescription,
    check_song_options,
    first_drawn_bin,
    scalar_range,
    song_mapping,
    song_metadata,
)

__all__ = [
    "DEFAULT_FLOOR_DB",
    "MAX_FLOOR_DB",
    "FREQ_SCALES",
    "AUDIBLE_HZ",
    "SCALAR_MAX_DB",
    "SCALAR_MIN_DB",
    "SongCloud",
    "scalar_range",
    "song_metadata",
    "song_points",
]


@dataclass(frozen=True)
class SongCloud(CloudDescription):
    """Song-mode points and what is needed to describe them (:class:`CloudDescription`).

    Attributes
    ----------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
        Columns x (time), y (level), z (frequency), scalar (A-weighted level), hp; frame-major
        order (all points of the first kept frame by ascending frequency, then the next frame).
    """

    points: np.ndarray

    @property
    def point_count(self) -> int:
        return int(self.points.shape[0])


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
    check_song_options(floor_db=floor_db, freq_scale=freq_scale)
    kept_frames = np.flatnonzero(~features.frames.silent)
    if kept_frames.size == 0:
        raise ExtractError("audio is entirely silent (no frame has a non-zero sample)")
    first_bin = first_drawn_bin(freq_scale)
    levels = features.level_db[first_bin:, kept_frames].T  # (n_kept, n_bins_drawn)
    mapping = song_mapping(
        kept_times_s=features.frames.times_s[kept_frames],
        frequencies_hz=features.frequencies_hz,
        peak_db=float(levels.max()),
        quietest_db=float(levels.min()),
        floor_db=floor_db,
        freq_scale=freq_scale,
        half_hop_s=features.hop_length / features.sample_rate / 2,
    )
    keep = mapping.keep(levels, frame_index=kept_frames)
    if not keep.any():
        raise ExtractError("no bin is left above the noise floor")
    points = mapping.rows(
        keep,
        x=mapping.x_per_kept,
        levels=levels,
        levels_a=features.level_a_db[first_bin:, kept_frames].T[keep],
        hp=features.hp[first_bin:, kept_frames].T[keep],
    )
    return SongCloud(
        points=points,
        axes=mapping.axes,
        frames_total=int(features.frames.silent.size),
        frames_kept=int(kept_frames.size),
        peak_level_db=mapping.y_high,
        floor_db=mapping.floor_db,
        freq_scale=freq_scale,
    )
