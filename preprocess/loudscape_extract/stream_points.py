"""Song mode's points produced block by block from a :class:`StreamedTrack` (the writer
appends each block as it comes: :func:`loudscape_extract.ply.write_ply_blocks`)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from loudscape_extract.contract import spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.floor import floor_keep_mask
from loudscape_extract.format import axis, frequency_axis, hp_axis, level_axis, scalar_axis
from loudscape_extract.points import FREQ_SCALES, MAX_FLOOR_DB, _normalize, scalar_range
from loudscape_extract.spectrogram import LEVEL_FLOOR_DB, level_db
from loudscape_extract.stream import StreamedTrack, spectral_blocks

__all__ = ["StreamedCloud", "level_a_db", "song_point_blocks"]


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


def song_point_blocks(
    track: StreamedTrack, *, floor_db: float, freq_scale: str = "linear"
) -> tuple[StreamedCloud, Callable[[], Iterator[np.ndarray]]]:
    """:func:`song_points` block by block: the cloud's description now, the points on demand.

    Counting the points above the floor needs the track's peak level, known only after
    :func:`stream_track`; so this runs one STFT pass to count them (the header must state the
    count), and the returned callable runs the STFT and HPSS again to produce them.

    Returns
    -------
    cloud : StreamedCloud
    blocks : callable
        Returns an iterator of float32 arrays of shape (n, 5), in :func:`song_points`' order,
        whose lengths sum to ``cloud.point_count``.
    """
    if freq_scale not in FREQ_SCALES:
        raise ExtractError(f"freq_scale must be one of {FREQ_SCALES}, got {freq_scale!r}")
    if not 0 <= floor_db <= MAX_FLOOR_DB:  # NaN fails too
        raise ExtractError(f"floor_db must be from 0 to {MAX_FLOOR_DB:g} dB, got {floor_db}")
    silent = track.frames.silent
    kept_frames = np.flatnonzero(~silent)
    if kept_frames.size == 0:
        raise ExtractError("audio is entirely silent (no frame has a non-zero sample)")
    first_bin = 0 if freq_scale == "linear" else 1
    z_per_bin, z_axis = frequency_axis(track.frequencies_hz, freq_scale)
    z_per_bin = z_per_bin[first_bin:].astype(np.float32)
    n_bins = z_per_bin.shape[0]
    peak = track.level_max_db[first_bin]
    options = dict(n_fft=track.n_fft, hop_length=track.hop_length, block_frames=track.block_frames)
    bin_index = np.arange(first_bin, first_bin + n_bins)

    def keep_mask(levels: np.ndarray, block_start: int, kept: np.ndarray) -> np.ndarray:
        # levels: (n_kept, n_bins_drawn) of the block's kept frames (the rule of points.py)
        if floor_db <= 0:
            return np.ones(levels.shape, dtype=bool)
        frame_index = block_start + np.flatnonzero(kept)
        return floor_keep_mask(
            levels, frame_index=frame_index, bin_index=bin_index, y_min=y_low, floor_db=floor_db
        )

    if floor_db > 0:
        y_low = peak - floor_db
        n_points = 0
        for block in spectral_blocks(track.mono, **options):
            kept = ~silent[block.start : block.stop]
            levels = level_db(block.magnitude[first_bin:, kept]).T
            n_points += int(np.count_nonzero(keep_mask(levels, block.start, kept)))
    else:
        y_low = track.level_min_db[first_bin]
        n_points = int(kept_frames.size) * n_bins
    if n_points == 0:
        raise ExtractError("no bin is left above the noise floor")
    times = track.frames.times_s[kept_frames]
    t_first, t_last = float(times[0]), float(times[-1])
    x_per_kept = np.full(silent.shape, np.nan, dtype=np.float32)
    x_per_kept[kept_frames] = _normalize(times, t_first, t_last)
    s_low, s_high = scalar_range(track.frequencies_hz[first_bin:], y_low, peak)
    a_gain = track.a_gain_db

    def blocks() -> Iterator[np.ndarray]:
        written = 0
        for block in spectral_blocks(
            track.mono, **options, hpss=True, kernel_size=track.kernel_size
        ):
            kept = ~silent[block.start : block.stop]
            if not kept.any():
                continue
            levels_all = level_db(block.magnitude[:, kept])
            levels = levels_all[first_bin:].T  # (n_kept, n_bins_drawn)
            keep = keep_mask(levels, block.start, kept)
            count = int(np.count_nonzero(keep))
            if count == 0:
                continue
            points = np.empty((count, 5), dtype=np.float32)
            x = x_per_kept[block.start : block.stop][kept]
            points[:, 0] = np.broadcast_to(x[:, None], keep.shape)[keep]
            points[:, 1] = _normalize(levels[keep], y_low, peak)
            points[:, 2] = np.broadcast_to(z_per_bin[None, :], keep.shape)[keep]
            levels_a = level_a_db(levels_all, a_gain)[first_bin:].T[keep]
            scalar = (levels_a.astype(np.float64) - s_low) / (s_high - s_low)
            points[:, 3] = np.clip(scalar, 0.0, 1.0)
            points[:, 4] = block.hp[first_bin:, kept].T[keep]
            written += count
            yield points
        if written != n_points:
            raise ExtractError(f"counted {n_points} points but produced {written}")

    # One kept frame, or one level everywhere: the axis gets a range around the single value
    # (half a hop of time, half a dB) and the points sit at its middle (docs/FORMAT.md).
    x_low, x_high = spread_range(t_first, t_last, track.hop_length / track.sample_rate / 2)
    y_axis_low, y_axis_high = spread_range(y_low, peak, 0.5)
    axes = {
        "x": axis("time", "s", x_low, x_high),
        "y": level_axis(y_axis_low, y_axis_high),
        "z": z_axis,
        "scalar": scalar_axis(s_low, s_high),
        "hp": hp_axis(),
    }
    cloud = StreamedCloud(
        point_count=n_points,
        axes=axes,
        frames_total=int(silent.size),
        frames_kept=int(kept_frames.size),
        peak_level_db=peak,
        floor_db=float(floor_db),
        freq_scale=freq_scale,
    )
    return cloud, blocks
