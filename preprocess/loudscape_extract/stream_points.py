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

from loudscape_extract.errors import ExtractError
from loudscape_extract.hpss import HPSS_KERNEL
from loudscape_extract.song_cloud import (
    CloudDescription,
    SongMapping,
    check_song_options,
    first_drawn_bin,
    song_mapping,
)
from loudscape_extract.spectrogram import level_a_db, level_db
from loudscape_extract.stream import DEFAULT_BLOCK_FRAMES, SpectralLevels, spectral_blocks

__all__ = ["SongPlan", "StreamedCloud", "plan_song", "song_point_blocks"]


@dataclass(frozen=True)
class StreamedCloud(CloudDescription):
    """:class:`~loudscape_extract.points.SongCloud` without the points (they went into the
    body file block by block): their count."""

    point_count: int


@dataclass(frozen=True)
class SongPlan:
    """A Song-mode cloud fixed before its points (:func:`plan_song`).

    Attributes
    ----------
    mapping : SongMapping
        The final axes and where each kept bin goes.
    frames_total, frames_kept : int
    silent : np.ndarray [shape=(n_frames,), dtype=bool]
    x_per_frame : np.ndarray [shape=(n_frames,), dtype=float32]
        x of each frame (NaN for silent frames).
    a_gain_db : np.ndarray [shape=(n_bins,)]
    """

    mapping: SongMapping
    frames_total: int
    frames_kept: int
    silent: np.ndarray
    x_per_frame: np.ndarray
    a_gain_db: np.ndarray

    @property
    def axes(self) -> dict:
        return self.mapping.axes

    def cloud(self, point_count: int) -> StreamedCloud:
        """The cloud's description once its points are counted."""
        return StreamedCloud(
            point_count=int(point_count),
            axes=self.mapping.axes,
            frames_total=self.frames_total,
            frames_kept=self.frames_kept,
            peak_level_db=self.mapping.y_high,
            floor_db=self.mapping.floor_db,
            freq_scale=self.mapping.freq_scale,
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
    check_song_options(floor_db=floor_db, freq_scale=freq_scale)
    silent = levels.silent
    kept_frames = np.flatnonzero(~silent)
    if kept_frames.size == 0:
        raise ExtractError("audio is entirely silent (no frame has a non-zero sample)")
    first_bin = first_drawn_bin(freq_scale)
    mapping = song_mapping(
        kept_times_s=levels.times_s[kept_frames],
        frequencies_hz=levels.frequencies_hz,
        peak_db=levels.level_max_db[first_bin],
        quietest_db=levels.level_min_db[first_bin],
        floor_db=floor_db,
        freq_scale=freq_scale,
        half_hop_s=hop_length / sample_rate / 2,
    )
    x_per_frame = np.full(silent.shape, np.nan, dtype=np.float32)
    x_per_frame[kept_frames] = mapping.x_per_kept
    return SongPlan(
        mapping=mapping,
        frames_total=int(silent.size),
        frames_kept=int(kept_frames.size),
        silent=silent,
        x_per_frame=x_per_frame,
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
    magnitude: np.ndarray | None = None,
    hpss_frames: int | None = None,
) -> Iterator[tuple[int, np.ndarray]]:
    """:func:`song_points` block by block: STFT and HPSS of the mono mix, the plan's mapping.

    ``magnitude``: the whole track's magnitude spectrogram when the level pass kept it
    (:attr:`~loudscape_extract.stream.SpectralLevels.magnitude`); otherwise it is computed
    again block by block. ``hpss_frames``: the frames transformed and separated at a time
    (:func:`~loudscape_extract.stream.spectral_blocks`; the points do not depend on it).

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
    mapping = plan.mapping
    first_bin = mapping.first_bin
    written = 0
    for block in spectral_blocks(
        mono,
        n_fft=n_fft,
        hop_length=hop_length,
        block_frames=block_frames,
        hpss=True,
        kernel_size=kernel_size,
        magnitude=magnitude,
        hpss_frames=hpss_frames,
    ):
        kept = ~plan.silent[block.start : block.stop]
        if not kept.any():
            continue
        levels_all = level_db(block.magnitude[:, kept])
        levels = levels_all[first_bin:].T  # (n_kept, n_bins_drawn)
        keep = mapping.keep(levels, frame_index=block.start + np.flatnonzero(kept))
        if not keep.any():
            continue
        points = mapping.rows(
            keep,
            x=plan.x_per_frame[block.start : block.stop][kept],
            levels=levels,
            levels_a=level_a_db(levels_all, plan.a_gain_db)[first_bin:].T[keep],
            hp=block.hp[first_bin:, kept].T[keep],
        )
        written += points.shape[0]
        yield block.stop, points
    if written == 0:
        raise ExtractError("no bin is left above the noise floor")
