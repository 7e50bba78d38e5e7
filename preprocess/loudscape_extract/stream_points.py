"""Song mode's points produced block by block from the spectrogram level pass's results.

The cloud's axes depend only on what :func:`~loudscape_extract.stream.spectral_level_pass`
finds (the kept frames' times, the peak bin level and the floor), so :func:`plan_song` fixes
them before any point is made; :func:`song_point_blocks` then runs the STFT and HPSS again and
yields each block's points in the file's order (song.py appends them to the body file).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.features import HPSS_KERNEL
from loudscape_extract.floor import floor_keep_mask
from loudscape_extract.format import axis, frequency_axis, hp_axis, level_axis, scalar_axis
from loudscape_extract.points import FREQ_SCALES, MAX_FLOOR_DB, _normalize, scalar_range
from loudscape_extract.spectrogram import LEVEL_FLOOR_DB, level_db
from loudscape_extract.stream import DEFAULT_BLOCK_FRAMES, SpectralLevels, spectral_blocks

__all__ = ["SongPlan", "StreamedCloud", "level_a_db", "plan_song", "song_point_blocks"]


def level_a_db(magnitude_levels: np.ndarray, a_gain_db: np.ndarray) -> np.ndarray:
    """``level + A-gain`` per bin, clipped at the level floor (as :func:`track_features`)."""
    levels_a = magnitude_levels + a_gain_db[:, None].astype(np.float32)
    np.maximum(levels_a, np.float32(LEVEL_FLOOR_DB), out=levels_a)
    return levels_a


@dataclass(frozen=True)
class StreamedCloud:
    """:class:`SongCloud` without the points (they are produced block by block)."""

    point_count: int
    axes: dict
    frames_total: int
    frames_kept: int
    peak_level_db: float
    floor_db: float
    freq_scale: str


@dataclass(frozen=True)
class SongPlan:
    """A Song-mode cloud fixed before its points: its axes and the rules that place a point.

    Attributes
    ----------
    axes : dict
        The ``axes`` metadata object (docs/FORMAT.md), final: the points never leave it.
    frames_total, frames_kept : int
    peak_level_db, floor_db : float
    freq_scale : str
    first_bin : int
        0, or 1 when the 0 Hz bin is not drawn (log frequency).
    y_low, scalar_low, scalar_high : float
        The level mapped to y = -1, and the scalar's dB range.
    x_per_frame : np.ndarray [shape=(n_frames,), dtype=float32]
        x of each frame (NaN for silent frames).
    z_per_bin : np.ndarray [shape=(n_bins_drawn,), dtype=float32]
    silent : np.ndarray [shape=(n_frames,), dtype=bool]
    a_gain_db : np.ndarray [shape=(n_bins,)]
    """

    axes: dict
    frames_total: int
    frames_kept: int
    peak_level_db: float
    floor_db: float
    freq_scale: str
    first_bin: int
    y_low: float
    scalar_low: float
    scalar_high: float
    x_per_frame: np.ndarray
    z_per_bin: np.ndarray
    silent: np.ndarray
    a_gain_db: np.ndarray

    def cloud(self, point_count: int) -> StreamedCloud:
        """The cloud's description once its points are counted."""
        return StreamedCloud(
            point_count=int(point_count),
            axes=self.axes,
            frames_total=self.frames_total,
            frames_kept=self.frames_kept,
            peak_level_db=self.peak_level_db,
            floor_db=self.floor_db,
            freq_scale=self.freq_scale,
        )


def plan_song(
    levels: SpectralLevels,
    *,
    sample_rate: int,
    hop_length: int,
    floor_db: float,
    freq_scale: str = "linear",
) -> SongPlan:
    """:func:`song_points`' axes and mapping from the level pass alone (no point made yet).

    Raises
    ------
    ExtractError
        A bad ``floor_db`` or ``freq_scale``, or no frame that is not silent.
    """
    if freq_scale not in FREQ_SCALES:
        raise ExtractError(f"freq_scale must be one of {FREQ_SCALES}, got {freq_scale!r}")
    if not 0 <= floor_db <= MAX_FLOOR_DB:  # NaN fails too
        raise ExtractError(f"floor_db must be from 0 to {MAX_FLOOR_DB:g} dB, got {floor_db}")
    silent = levels.silent
    kept_frames = np.flatnonzero(~silent)
    if kept_frames.size == 0:
        raise ExtractError("audio is entirely silent (no frame has a non-zero sample)")
    first_bin = 0 if freq_scale == "linear" else 1
    z_per_bin, z_axis = frequency_axis(levels.frequencies_hz, freq_scale)
    peak = levels.level_max_db[first_bin]
    y_low = peak - floor_db if floor_db > 0 else levels.level_min_db[first_bin]
    times = levels.times_s[kept_frames]
    t_first, t_last = float(times[0]), float(times[-1])
    x_per_frame = np.full(silent.shape, np.nan, dtype=np.float32)
    x_per_frame[kept_frames] = _normalize(times, t_first, t_last)
    s_low, s_high = scalar_range(levels.frequencies_hz[first_bin:], y_low, peak)
    # One kept frame, or one level everywhere: the axis gets a range around the single value
    # (half a hop of time, half a dB) and the points sit at its middle (docs/FORMAT.md).
    x_low, x_high = spread_range(t_first, t_last, hop_length / sample_rate / 2)
    y_axis_low, y_axis_high = spread_range(y_low, peak, 0.5)
    axes = {
        "x": axis("time", "s", x_low, x_high),
        "y": level_axis(y_axis_low, y_axis_high),
        "z": z_axis,
        "scalar": scalar_axis(s_low, s_high),
        "hp": hp_axis(),
    }
    return SongPlan(
        axes=axes,
        frames_total=int(silent.size),
        frames_kept=int(kept_frames.size),
        peak_level_db=peak,
        floor_db=float(floor_db),
        freq_scale=freq_scale,
        first_bin=first_bin,
        y_low=y_low,
        scalar_low=s_low,
        scalar_high=s_high,
        x_per_frame=x_per_frame,
        z_per_bin=z_per_bin[first_bin:].astype(np.float32),
        silent=silent,
        a_gain_db=levels.a_gain_db,
    )


def song_point_blocks(
    mono: np.ndarray,
    plan: SongPlan,
    *,
    n_fft: int,
    hop_length: int,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
    kernel_size: int = HPSS_KERNEL,
) -> Iterator[tuple[int, np.ndarray]]:
    """:func:`song_points` block by block: STFT and HPSS of the mono mix, the plan's mapping.

    Yields
    ------
    frames_done : int
        Frames of the track covered so far.
    points : np.ndarray [shape=(n, 5), dtype=float32]
        The next rows of the cloud, in :func:`song_points`' order (n > 0).

    Raises
    ------
    ExtractError
        No bin is left above the noise floor (after the last block).
    """
    first_bin = plan.first_bin
    n_bins = plan.z_per_bin.shape[0]
    bin_index = np.arange(first_bin, first_bin + n_bins)
    peak, y_low, floor_db = plan.peak_level_db, plan.y_low, plan.floor_db
    s_low, s_high = plan.scalar_low, plan.scalar_high
    written = 0
    for block in spectral_blocks(
        mono,
        n_fft=n_fft,
        hop_length=hop_length,
        block_frames=block_frames,
        hpss=True,
        kernel_size=kernel_size,
    ):
        kept = ~plan.silent[block.start : block.stop]
        if not kept.any():
            continue
        levels_all = level_db(block.magnitude[:, kept])
        levels = levels_all[first_bin:].T  # (n_kept, n_bins_drawn)
        if floor_db > 0:  # the rule of points.py
            keep = floor_keep_mask(
                levels,
                frame_index=block.start + np.flatnonzero(kept),
                bin_index=bin_index,
                y_min=y_low,
                floor_db=floor_db,
            )
        else:
            keep = np.ones(levels.shape, dtype=bool)
        count = int(np.count_nonzero(keep))
        if count == 0:
            continue
        points = np.empty((count, 5), dtype=np.float32)
        x = plan.x_per_frame[block.start : block.stop][kept]
        points[:, 0] = np.broadcast_to(x[:, None], keep.shape)[keep]
        points[:, 1] = _normalize(levels[keep], y_low, peak)
        points[:, 2] = np.broadcast_to(plan.z_per_bin[None, :], keep.shape)[keep]
        levels_a = level_a_db(levels_all, plan.a_gain_db)[first_bin:].T[keep]
        scalar = (levels_a.astype(np.float64) - s_low) / (s_high - s_low)
        points[:, 3] = np.clip(scalar, 0.0, 1.0)
        points[:, 4] = block.hp[first_bin:, kept].T[keep]
        written += count
        yield block.stop, points
    if written == 0:
        raise ExtractError("no bin is left above the noise floor")
