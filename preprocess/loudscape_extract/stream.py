"""Bounded-memory extraction: the Song pipeline streamed through a track in blocks.

:func:`track_features` holds every per-bin array of a track at once (about 8 GB for 60
minutes). This module computes the same features and metrics with memory that does not grow
with the per-bin data:

1. **decode** and 2. **signal** (:mod:`loudscape_extract.stream_decode`): the mono mix kept
   from a first decode; the sums and peaks the loudness and dynamics metrics need from a
   second;
3. **spectral passes** over blocks of STFT frames of the mono mix. HPSS's harmonic median runs
   along time, so each block is filtered with half a kernel of neighbouring frames on each
   side (real frames inside the track, the same symmetric padding as the unblocked filter at
   its ends): every median sees the same values as the unblocked one, and the spectral
   results are equal bit for bit.

Every whole-track metric is computed from the per-segment and per-block sums, so it is exact
up to float rounding (sums in a different order, FFT convolutions of different lengths).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.curves import loudness_curves
from loudscape_extract.dsp import hann_window
from loudscape_extract.dynamics import dr_from_blocks
from loudscape_extract.errors import ExtractError
from loudscape_extract.fft import rfft
from loudscape_extract.hpss import (
    HPSS_KERNEL,
    HPSS_MARGIN,
    HPSS_POWER,
    hp_ratio,
    masks_from_medians,
    median_filter_axis,
)
from loudscape_extract.measures import (
    FrameFeatures,
    TrackDescription,
    a_power_gain,
    dynamics_series,
    level_series,
    spectral_series,
    track_metrics,
)
from loudscape_extract.spectrogram import a_weighting_db, frame_count, frame_times, level_db
from loudscape_extract.stream_decode import (
    DEFAULT_BLOCK_SAMPLES,
    DecodedMono,
    SignalStats,
    decode_track,
    signal_pass,
)

__all__ = [
    "DEFAULT_BLOCK_FRAMES",
    "KEEP_MAGNITUDE_VALUES",
    "SIGNAL_MESSAGE",
    "SpectralBlock",
    "SpectralLevels",
    "StreamedTrack",
    "finish_track",
    "level_range",
    "spectral_blocks",
    "spectral_level_pass",
    "stream_track",
]

#: STFT frames per spectral block (about 48 s at 44.1 kHz with hop 1024).
DEFAULT_BLOCK_FRAMES = 2048
#: The level pass keeps the whole magnitude spectrogram for Song mode's points pass up to this
#: many values (float32: 256 MiB, about 27 minutes at 44.1 kHz with n_fft 2048, hop 1024);
#: a longer track's points pass computes its STFT again.
KEEP_MAGNITUDE_VALUES = 1 << 26
#: The progress message said before :func:`signal_pass`.
SIGNAL_MESSAGE = (
    "dynamics and loudness (short-term loudness, PSR, DR, integrated, range, true peak)"
)
_FFT_CHUNK_FRAMES = 512


def _frames_of(mono: np.ndarray, first: int, stop: int, *, n_fft: int, hop_length: int):
    """Centred frames ``first .. stop - 1`` of ``mono`` (zero-padded at the track's ends)."""
    pad = n_fft // 2
    begin = first * hop_length - pad
    end = (stop - 1) * hop_length - pad + n_fft
    local = np.zeros(end - begin, dtype=np.float32)
    lo, hi = max(begin, 0), min(end, mono.shape[0])
    if hi > lo:
        local[lo - begin : hi - begin] = mono[lo:hi]
    return sliding_window_view(local, n_fft)[::hop_length][: stop - first]


def _magnitude(frames: np.ndarray, window_scaled: np.ndarray) -> np.ndarray:
    """:func:`stft_magnitude` of already cut frames, computed the same way frame by frame."""
    n_frames = frames.shape[0]
    magnitude = np.empty((frames.shape[1] // 2 + 1, n_frames), dtype=np.float32)
    for start in range(0, n_frames, _FFT_CHUNK_FRAMES):
        stop = min(start + _FFT_CHUNK_FRAMES, n_frames)
        spectrum = rfft(frames[start:stop] * window_scaled, axis=1)
        magnitude[:, start:stop] = np.abs(spectrum).T
    magnitude[0] *= np.float32(0.5)
    magnitude[-1] *= np.float32(0.5)
    return magnitude


@dataclass(frozen=True)
class SpectralBlock:
    """Frames ``start .. stop - 1``: their magnitude, the decoded mono mix's frame peaks, and
    (when asked for) their hp ratio."""

    start: int
    stop: int
    magnitude: np.ndarray
    decoded_peak: np.ndarray
    hp: np.ndarray | None


def spectral_blocks(
    mono: np.ndarray,
    *,
    n_fft: int,
    hop_length: int,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
    hpss: bool = False,
    kernel_size: int = HPSS_KERNEL,
    magnitude: np.ndarray | None = None,
    hpss_frames: int | None = None,
) -> Iterator[SpectralBlock]:
    """The mono mix's spectrogram block by block (see the module docs for HPSS's overlap).

    ``magnitude``, the whole track's magnitude spectrogram when a pass before kept it
    (:attr:`SpectralLevels.magnitude`), is sliced instead of computing the STFT again (the
    same values: each frame's transform does not depend on the frames beside it).

    ``hpss_frames`` (default ``block_frames``; rounded down to a multiple of it, never
    fewer): the frames transformed and median-filtered at a time, the blocks yielded (the
    same as without it) being cut from them. Each span filters
    half a kernel of neighbouring frames on each side as well, so small yielded blocks (Song
    mode's points pass: 256 frames, about 12 % more harmonic medians) cost less over wider
    spans; the values do not depend on either size.

    Yields
    ------
    block : SpectralBlock
        ``magnitude`` and ``hp`` of shape (1 + n_fft // 2, stop - start), equal to the
        columns of :func:`stft_magnitude` and of ``hp_ratio(hpss_masks(...))`` on the whole.
    """
    if block_frames < 1:
        raise ExtractError(f"block_frames must be >= 1, got {block_frames}")
    span_frames = block_frames * max(1, (hpss_frames or block_frames) // block_frames)
    n_frames = frame_count(mono.shape[0], n_fft=n_fft, hop_length=hop_length)
    window = hann_window(n_fft).astype(np.float32)
    window_scaled = window * np.float32(2.0 / window.sum())
    context = kernel_size // 2 if hpss else 0
    whole = magnitude
    for start in range(0, n_frames, span_frames):
        stop = min(start + span_frames, n_frames)
        first, last = max(0, start - context), min(n_frames, stop + context)
        frames = _frames_of(mono, first, last, n_fft=n_fft, hop_length=hop_length)
        if whole is not None:
            extended = whole[:, first:last]
        else:
            extended = _magnitude(frames, window_scaled)
        inner = slice(start - first, stop - first)
        magnitude = np.ascontiguousarray(extended[:, inner])
        decoded_peak = np.abs(frames[inner]).max(axis=1).astype(np.float64)
        hp = None
        if hpss:
            harmonic = median_filter_axis(extended, size=kernel_size, axis=1)[:, inner]
            percussive = median_filter_axis(magnitude, size=kernel_size, axis=0)
            mask_h, mask_p = masks_from_medians(
                np.ascontiguousarray(harmonic), percussive, power=HPSS_POWER, margin=HPSS_MARGIN
            )
            hp = hp_ratio(magnitude, mask_h, mask_p)
        if stop - start <= block_frames:
            yield SpectralBlock(start, stop, magnitude, decoded_peak, hp)
            continue
        for at in range(start, stop, block_frames):
            part = slice(at - start, min(at + block_frames, stop) - start)
            yield SpectralBlock(
                at,
                at + part.stop - part.start,
                np.ascontiguousarray(magnitude[:, part]),
                decoded_peak[part],
                None if hp is None else np.ascontiguousarray(hp[:, part]),
            )


def level_range(magnitude: np.ndarray) -> dict[int, tuple[float, float]]:
    """The loudest and quietest :func:`level_db` of ``magnitude`` (bins x frames), keyed by
    the first bin counted (0: all, 1: without the 0 Hz bin).

    The level is monotone in the magnitude, so only the magnitudes within a millionth of the
    extremes are taken to dB (the margin covers a logarithm rounded differently from one
    value to the next); the result is that of ``level_db`` of the whole, bit for bit, at a
    fraction of its cost.
    """
    if magnitude.shape[0] < 2:
        levels = level_db(magnitude)
        return {0: (float(levels.max()), float(levels.min()))}
    rest = magnitude[1:]
    high, low = rest.max(), rest.min()
    loudest = float(level_db(rest[rest >= high * np.float32(1 - 1e-6)]).max())
    quietest = float(level_db(rest[rest <= low * np.float32(1 + 1e-6)]).min())
    row = level_db(magnitude[0])
    return {
        0: (max(loudest, float(row.max())), min(quietest, float(row.min()))),
        1: (loudest, quietest),
    }


@dataclass(frozen=True)
class StreamedTrack(TrackDescription):
    """:class:`TrackFeatures` without the per-bin arrays: what a streamed pass keeps.

    Attributes
    ----------
    path : str
    sample_rate, n_channels, n_samples, n_fft, hop_length : int
    source_format : str
        ``FORMAT/SUBTYPE`` of the file.
    mono : np.ndarray [shape=(n_samples,), dtype=float32]
        The decoded mono mix (the spectral passes read it again).
    frequencies_hz, a_gain_db : np.ndarray [shape=(n_bins,)]
    frames : FrameFeatures
        ``hp_mean`` is NaN unless the track was streamed with ``frame_hp=True``.
    metrics : dict
        As :attr:`TrackFeatures.metrics`.
    level_max_db, level_min_db : dict
        Loudest and quietest bin level over the non-silent frames, keyed by the first drawn
        bin (0: all bins, 1: without the 0 Hz bin).
    highpass_hz : float or None
    kernel_size, block_frames : int
    warning : str
        Non-empty when the file is truncated or corrupt: how much was decoded, and why.
    curves : dict or None
        The loudness curves (:func:`loudness_curves`).
    signal : tuple of dict
        Warnings about the signal found while decoding (:attr:`DecodedMono.signal`).
    """

    source_format: str
    mono: np.ndarray
    frequencies_hz: np.ndarray
    a_gain_db: np.ndarray
    frames: FrameFeatures
    metrics: dict
    level_max_db: dict
    level_min_db: dict
    highpass_hz: float | None
    kernel_size: int
    block_frames: int
    warning: str = ""
    curves: dict | None = None
    signal: tuple = ()


@dataclass(frozen=True)
class SpectralLevels:
    """What the spectrogram level pass (:func:`spectral_level_pass`) finds, per frame and
    over the track: enough to fix a Song-mode cloud's axes before any point is made.

    Attributes
    ----------
    frequencies_hz, a_gain_db : np.ndarray [shape=(n_bins,)]
    times_s : np.ndarray [shape=(n_frames,)]
    silent : np.ndarray [shape=(n_frames,), dtype=bool]
        Frames whose every decoded sample is 0.
    loudness_a_db, hp_mean : np.ndarray [shape=(n_frames,)]
        As :class:`FrameFeatures`' (``hp_mean`` NaN unless the pass ran HPSS).
    level_max_db, level_min_db : dict
        Loudest and quietest bin level over the non-silent frames, keyed by the first drawn
        bin (0: all bins, 1: without the 0 Hz bin).
    magnitude : np.ndarray [shape=(n_bins, n_frames), dtype=float32] or None
        The magnitude spectrogram, when the pass was asked to keep it and it is at most
        :data:`KEEP_MAGNITUDE_VALUES` values (Song mode's points pass reads it).
    """

    frequencies_hz: np.ndarray
    a_gain_db: np.ndarray
    times_s: np.ndarray
    silent: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    level_max_db: dict
    level_min_db: dict
    magnitude: np.ndarray | None = field(default=None, repr=False, compare=False)


def stream_track(
    path: str,
    *,
    n_fft: int = 2048,
    hop_length: int = 1024,
    highpass_hz: float | None = None,
    frame_hp: bool = True,
    kernel_size: int = HPSS_KERNEL,
    block_samples: int = DEFAULT_BLOCK_SAMPLES,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
    strict: bool = False,
    progress: Callable[[str], None] | None = None,
    after_levels: Callable[[DecodedMono, SpectralLevels], None] | None = None,
) -> StreamedTrack:
    """:func:`track_features` in bounded memory: per-frame series, metrics and level range.

    The passes in order: :func:`~loudscape_extract.stream_decode.decode_track`,
    :func:`spectral_level_pass`, ``after_levels`` (Song mode makes its points there, the axes
    being fixed by the level pass), :func:`~loudscape_extract.stream_decode.signal_pass`, then
    :func:`finish_track`.

    Parameters
    ----------
    path : str
        Audio file.
    n_fft, hop_length, kernel_size, highpass_hz
        As :func:`track_features`.
    frame_hp : bool
        Compute the per-frame hp mean (runs HPSS; the timeline needs it, Song mode does not).
    block_samples, block_frames : int
        Block sizes of the decoding and spectral passes (results do not depend on them).
    strict : bool
        Refuse a truncated or corrupt file; otherwise it is used as far as it decodes and
        ``track.warning`` says how far.
    progress : callable, optional
    after_levels : callable, optional
        Called with the decoded track and the level pass's results before the signal pass
        (with the magnitude spectrogram kept, :attr:`SpectralLevels.magnitude`, for a track
        short enough).

    Raises
    ------
    ExtractError
        As :func:`decode_audio` and :func:`track_features`.
    """
    say = progress or (lambda _message: None)
    decoded = decode_track(path, n_fft=n_fft, block_samples=block_samples, strict=strict)
    say("spectrogram" + (" and harmonic-percussive separation" if frame_hp else ""))
    levels = spectral_level_pass(
        decoded,
        n_fft=n_fft,
        hop_length=hop_length,
        block_frames=block_frames,
        hpss=frame_hp,
        kernel_size=kernel_size,
        keep_magnitude=after_levels is not None,
    )
    if after_levels is not None:
        after_levels(decoded, levels)
        levels = replace(levels, magnitude=None)
    say(SIGNAL_MESSAGE)
    stats = signal_pass(
        decoded, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, block=block_samples
    )
    say("frame features")
    return finish_track(
        decoded,
        levels,
        stats,
        n_fft=n_fft,
        hop_length=hop_length,
        highpass_hz=highpass_hz,
        kernel_size=kernel_size,
        block_frames=block_frames,
    )


def spectral_level_pass(
    decoded: DecodedMono,
    *,
    n_fft: int,
    hop_length: int,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
    hpss: bool = False,
    kernel_size: int = HPSS_KERNEL,
    keep_magnitude: bool = False,
) -> SpectralLevels:
    """One pass over the mono mix's spectrogram: silent frames, A-weighted frame level, the
    level range (and with ``hpss`` the per-frame hp mean; with ``keep_magnitude`` the whole
    magnitude spectrogram, up to :data:`KEEP_MAGNITUDE_VALUES` values)."""
    rate = decoded.info.sample_rate
    frequencies = np.arange(n_fft // 2 + 1) * (rate / n_fft)
    a_gain = a_weighting_db(frequencies)
    power_gain = a_power_gain(a_gain)
    n_frames = frame_count(decoded.n_samples, n_fft=n_fft, hop_length=hop_length)
    silent = np.zeros(n_frames, dtype=bool)
    loudness_a = np.empty(n_frames)
    hp_mean = np.full(n_frames, np.nan)
    level_max = {0: -math.inf, 1: -math.inf}
    level_min = {0: math.inf, 1: math.inf}
    n_bins = frequencies.shape[0]
    kept_magnitude = None
    if keep_magnitude and n_bins * n_frames <= KEEP_MAGNITUDE_VALUES:
        kept_magnitude = np.empty((n_bins, n_frames), dtype=np.float32)
    for block in spectral_blocks(
        decoded.mono,
        n_fft=n_fft,
        hop_length=hop_length,
        block_frames=block_frames,
        hpss=hpss,
        kernel_size=kernel_size,
    ):
        span = slice(block.start, block.stop)
        if kept_magnitude is not None:
            kept_magnitude[:, span] = block.magnitude
        block_silent = block.decoded_peak == 0
        silent[span] = block_silent
        loudness_a[span], block_hp = spectral_series(
            block.magnitude, power_gain=power_gain, silent=block_silent, hp=block.hp
        )
        if block_hp is not None:
            hp_mean[span] = block_hp
        kept = ~block_silent
        if kept.any():
            magnitude = block.magnitude if kept.all() else block.magnitude[:, kept]
            for first_bin, (loudest, quietest) in level_range(magnitude).items():
                level_max[first_bin] = max(level_max[first_bin], loudest)
                level_min[first_bin] = min(level_min[first_bin], quietest)
    return SpectralLevels(
        frequencies_hz=frequencies,
        a_gain_db=a_gain,
        times_s=frame_times(n_frames, sample_rate=rate, hop_length=hop_length),
        silent=silent,
        loudness_a_db=loudness_a,
        hp_mean=hp_mean,
        level_max_db=level_max,
        level_min_db=level_min,
        magnitude=kept_magnitude,
    )


def finish_track(
    decoded: DecodedMono,
    levels: SpectralLevels,
    stats: SignalStats,
    *,
    n_fft: int,
    hop_length: int,
    highpass_hz: float | None,
    kernel_size: int = HPSS_KERNEL,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
) -> StreamedTrack:
    """The per-frame series and whole-track metrics from the passes' results."""
    info = decoded.info
    rate = info.sample_rate
    silent = levels.silent
    n_frames = silent.shape[0]
    if stats.frame_rms.shape[0] != n_frames:
        raise ExtractError(
            f"the signal pass framed {stats.frame_rms.shape[0]} frames, the spectrogram {n_frames}",
            path=info.path,
        )
    rms_dbfs, crest_db = level_series(stats.frame_rms, stats.frame_peak, silent)
    dynamics = stats.dynamics(rate)
    frames = FrameFeatures(
        times_s=levels.times_s,
        rms_dbfs=rms_dbfs,
        peak=stats.frame_peak,
        crest_db=crest_db,
        loudness_a_db=levels.loudness_a_db,
        hp_mean=levels.hp_mean,
        silent=silent,
        **dynamics_series(levels.times_s, silent, dynamics, stats.energy, stats.boundaries),
    )
    sample_peak = decoded.sample_peak
    true_peak = max(stats.true_peak_decoded, sample_peak)
    metrics = track_metrics(
        energy=stats.energy,
        boundaries=stats.boundaries,
        dynamics=dynamics,
        sample_peak_dbfs=20.0 * math.log10(sample_peak) if sample_peak > 0 else None,
        true_peak_dbtp=20.0 * math.log10(true_peak) if true_peak > 0 else None,
        crest_db=crest_db,
        dc=decoded.dc,
        dr_db=dr_from_blocks(stats.dr_squares, stats.dr_peaks, stats.dr_lengths),
        window_maxima=stats.window_maxima,
    )
    return StreamedTrack(
        path=info.path,
        sample_rate=rate,
        n_channels=info.n_channels,
        n_samples=decoded.n_samples,
        n_fft=n_fft,
        hop_length=hop_length,
        source_format=f"{info.format}/{info.subtype}",
        mono=decoded.mono,
        frequencies_hz=levels.frequencies_hz,
        a_gain_db=levels.a_gain_db,
        frames=frames,
        metrics=metrics,
        level_max_db=levels.level_max_db,
        level_min_db=levels.level_min_db,
        highpass_hz=highpass_hz,
        kernel_size=kernel_size,
        block_frames=block_frames,
        warning=decoded.warning,
        signal=decoded.signal,
        curves=loudness_curves(
            stats.energy,
            stats.boundaries,
            segment_peak=stats.segment_peak,
            dynamics=dynamics,
            sample_rate=rate,
        ),
    )
