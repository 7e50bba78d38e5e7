"""The whole-track reference: per-bin and per-frame features of one track, plus its metrics,
with every per-bin array in memory at once (:func:`track_features`).

Production does not run this: ``loudscape-extract song`` and the timeline's songs go through
the streamed pipeline (:mod:`loudscape_extract.stream`, :func:`~loudscape_extract.song.
extract_song`), in memory that does not grow with the per-bin data. This module is what the
tests hold the streamed results equal to, and the notebook-sized API for short audio
(``track_features`` -> :func:`~loudscape_extract.points.song_points`). Both turn their sums
into series and metrics with :mod:`loudscape_extract.measures`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from loudscape_extract.audio import Audio, check_analysable, mix_to_mono
from loudscape_extract.curves import loudness_curves
from loudscape_extract.dynamics import (
    dc_and_highpass,
    dr_meter,
    dynamics_from_segments,
    segment_true_peak,
)
from loudscape_extract.errors import ExtractError
from loudscape_extract.hpss import HPSS_KERNEL, HPSS_MARGIN, HPSS_POWER, hp_ratio, hpss_masks
from loudscape_extract.loudness import (
    sample_peak_dbfs,
    segment_energy,
    true_peak_dbtp,
    window_maxima,
)
from loudscape_extract.measures import (
    FrameFeatures,
    TrackDescription,
    a_power_gain,
    crest_statistics,
    dynamics_series,
    level_series,
    spectral_series,
    track_metrics,
)
from loudscape_extract.spectrogram import (
    a_weighting_db,
    frame_count,
    frame_signal,
    frame_times,
    level_a_db,
    level_db,
    stft_magnitude,
)

__all__ = ["FrameFeatures", "TrackFeatures", "crest_statistics", "frame_features", "track_features"]

_CHUNK_FRAMES = 1024


@dataclass(frozen=True)
class TrackFeatures(TrackDescription):
    """Everything Song mode needs from one track (and :class:`TrackDescription`'s numbers).

    Attributes
    ----------
    frequencies_hz : np.ndarray [shape=(n_bins,)]
        Bin centre frequencies, ``k * sample_rate / n_fft``.
    magnitude : np.ndarray [shape=(n_bins, n_frames), dtype=float32]
        Mono magnitude spectrogram, full-scale sine = 1.
    level_db : np.ndarray [shape=(n_bins, n_frames), dtype=float32]
        ``20 log10(max(magnitude, 1e-10))``.
    level_a_db : np.ndarray [shape=(n_bins, n_frames), dtype=float32]
        ``level_db`` plus the A-weighting gain of the bin (clipped at -200 dB).
    hp : np.ndarray [shape=(n_bins, n_frames), dtype=float32]
        Harmonic-percussive ratio in [0, 1].
    frames : FrameFeatures
    metrics : dict
        ``integrated_lufs``, ``lra_lu``, ``sample_peak_dbfs``, ``true_peak_dbtp``, ``plr_db``,
        ``crest_median_db``, ``crest_p95_db``, ``dc_offset``, ``dr_db``, ``psr_median_db``,
        ``psr_p10_db``, ``psr_p90_db``, ``psr_spread_db``, ``crest_3s_median_db`` (float or
        None); see docs/FORMAT.md.
    """

    frequencies_hz: np.ndarray
    magnitude: np.ndarray
    level_db: np.ndarray
    level_a_db: np.ndarray
    hp: np.ndarray
    frames: FrameFeatures
    metrics: dict
    highpass_hz: float | None = None
    curves: dict | None = None


def _frame_rms_peak(mono: np.ndarray, *, n_fft: int, hop_length: int):
    frames = frame_signal(mono, n_fft=n_fft, hop_length=hop_length)
    n_frames = frames.shape[0]
    rms = np.empty(n_frames)
    peak = np.empty(n_frames)
    for start in range(0, n_frames, _CHUNK_FRAMES):
        chunk = frames[start : start + _CHUNK_FRAMES].astype(np.float64)
        rms[start : start + chunk.shape[0]] = np.sqrt(np.einsum("ij,ij->i", chunk, chunk) / n_fft)
        peak[start : start + chunk.shape[0]] = np.abs(chunk).max(axis=1)
    return rms, peak


def _silent_frames(mono: np.ndarray, *, n_fft: int, hop_length: int) -> np.ndarray:
    """Frames (centred, zero-padded, as the STFT's) whose every sample is exactly 0."""
    nonzero = np.concatenate([[0], np.cumsum(mono != 0, dtype=np.int64)])
    n_frames = frame_count(mono.shape[0], n_fft=n_fft, hop_length=hop_length)
    start = np.arange(n_frames, dtype=np.int64) * hop_length - n_fft // 2
    first = np.clip(start, 0, mono.shape[0])
    last = np.clip(start + n_fft, 0, mono.shape[0])
    return nonzero[last] == nonzero[first]


def frame_features(
    mono: np.ndarray,
    *,
    sample_rate: float,
    n_fft: int,
    hop_length: int,
    magnitude: np.ndarray,
    hp: np.ndarray,
    a_gain_db: np.ndarray,
    silent: np.ndarray | None = None,
) -> FrameFeatures:
    """Per-frame RMS, peak, crest factor, A-weighted level and mean hp.

    Parameters
    ----------
    mono : np.ndarray [shape=(n_samples,)]
        The mono mix for level, peak and crest (DC removed by :func:`track_features`).
    sample_rate : float
    n_fft, hop_length : int
    magnitude : np.ndarray [shape=(n_bins, n_frames)]
        From :func:`stft_magnitude` with the same ``n_fft`` and ``hop_length``.
    hp : np.ndarray [shape=(n_bins, n_frames)]
    a_gain_db : np.ndarray [shape=(n_bins,)]
        A-weighting gain per bin.
    silent : np.ndarray [shape=(n_frames,), dtype=bool], optional
        Which frames are digital silence in the file as decoded (after DC removal they are
        not exactly 0); default: where ``mono``'s frame is all zeros.

    Returns
    -------
    frames : FrameFeatures
    """
    rms, peak = _frame_rms_peak(mono, n_fft=n_fft, hop_length=hop_length)
    if magnitude.shape[1] != rms.shape[0] or hp.shape != magnitude.shape:
        raise ExtractError(
            f"magnitude {magnitude.shape} and hp {hp.shape} do not match {rms.shape[0]} frames"
        )
    silent = (peak == 0) if silent is None else np.asarray(silent, dtype=bool)
    rms_dbfs, crest_db = level_series(rms, peak, silent)
    loudness_a_db, hp_mean = spectral_series(
        magnitude, power_gain=a_power_gain(a_gain_db), silent=silent, hp=hp
    )
    return FrameFeatures(
        times_s=frame_times(rms.shape[0], sample_rate=sample_rate, hop_length=hop_length),
        rms_dbfs=rms_dbfs,
        peak=peak,
        crest_db=crest_db,
        loudness_a_db=loudness_a_db,
        hp_mean=hp_mean,
        silent=silent,
    )


def track_features(
    audio: Audio,
    *,
    n_fft: int = 2048,
    hop_length: int = 1024,
    kernel_size: int = HPSS_KERNEL,
    highpass_hz: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> TrackFeatures:
    """Decode-to-features: spectrogram, A-weighting, HPSS, frame series and metrics.

    Parameters
    ----------
    audio : Audio
        From :func:`decode_audio`; ``samples`` has shape (n_samples, n_channels).
    n_fft : int
        STFT frame length (even).
    hop_length : int
        STFT hop in samples.
    kernel_size : int
        HPSS median kernel (odd).
    highpass_hz : float, optional
        Also high-pass the DC-free signal at this frequency (e.g. 20 Hz) before the frame
        level, crest factors, DR, PSR and loudness. The spectrogram always sees the signal as
        decoded (its DC bin shows an offset), and so do ``sample_peak_dbfs`` and
        ``true_peak_dbtp``.
    progress : callable, optional
        Called with a short message as each stage starts.

    Returns
    -------
    features : TrackFeatures

    Raises
    ------
    ExtractError
        Audio shorter than one frame, or entirely silent.
    """
    samples = audio.samples
    if samples.ndim != 2 or samples.shape[0] == 0:
        raise ExtractError(f"audio has no samples (shape {samples.shape})", path=audio.path)
    say = progress or (lambda _message: None)
    mono = mix_to_mono(samples)
    check_analysable(
        n_samples=samples.shape[0],
        sample_rate=audio.sample_rate,
        n_fft=n_fft,
        any_sample=bool(np.any(samples)),
        mono=mono,
        path=audio.path,
    )
    say("spectrogram")
    magnitude = stft_magnitude(mono, n_fft=n_fft, hop_length=hop_length)
    frequencies = np.arange(magnitude.shape[0]) * (audio.sample_rate / n_fft)
    a_gain = a_weighting_db(frequencies)
    levels = level_db(magnitude)
    levels_a = level_a_db(levels, a_gain)
    say("harmonic-percussive separation")
    mask_harmonic, mask_percussive = hpss_masks(
        magnitude, kernel_size=kernel_size, power=HPSS_POWER, margin=HPSS_MARGIN
    )
    hp = hp_ratio(magnitude, mask_harmonic, mask_percussive)
    del mask_harmonic, mask_percussive
    say("frame features")
    clean, dc = dc_and_highpass(samples, sample_rate=audio.sample_rate, highpass_hz=highpass_hz)
    if highpass_hz is None:  # the mean of DC-free channels is the mono mix minus its mean DC
        mono_clean = mono - np.float32(dc.mean())
    else:
        mono_clean = mix_to_mono(clean)
    frames = frame_features(
        mono_clean,
        sample_rate=audio.sample_rate,
        n_fft=n_fft,
        hop_length=hop_length,
        magnitude=magnitude,
        hp=hp,
        a_gain_db=a_gain,
        silent=_silent_frames(mono, n_fft=n_fft, hop_length=hop_length),
    )
    say("dynamics and loudness (short-term loudness, PSR, DR, integrated, range, true peak)")
    energy = segment_energy(clean, audio.sample_rate)
    # short_term_dynamics' steps, keeping the segment peaks for the overs
    segment_peak, overall_peak = segment_true_peak(clean, energy[1])
    starts = energy[1][:-1].astype(np.int64)
    m = np.asarray(mono_clean[: energy[1][-1]], dtype=np.float64)
    dynamics = dynamics_from_segments(
        *energy,
        segment_peak=segment_peak,
        true_peak=overall_peak,
        mono_squares=np.add.reduceat(m * m, starts) if starts.size else np.zeros(0),
        mono_peaks=np.maximum.reduceat(np.abs(m), starts) if starts.size else np.zeros(0),
        sample_rate=audio.sample_rate,
    )
    frames = replace(frames, **dynamics_series(frames.times_s, frames.silent, dynamics, *energy))
    metrics = track_metrics(
        energy=energy[0],
        boundaries=energy[1],
        dynamics=dynamics,
        sample_peak_dbfs=sample_peak_dbfs(samples),
        true_peak_dbtp=true_peak_dbtp(samples, sample_rate=audio.sample_rate),
        crest_db=frames.crest_db,
        dc=dc,
        dr_db=dr_meter(clean, sample_rate=audio.sample_rate),
        window_maxima=window_maxima(clean, sample_rate=audio.sample_rate),
    )
    return TrackFeatures(
        path=audio.path,
        sample_rate=audio.sample_rate,
        n_channels=audio.n_channels,
        n_samples=audio.n_samples,
        n_fft=n_fft,
        hop_length=hop_length,
        frequencies_hz=frequencies,
        magnitude=magnitude,
        level_db=levels,
        level_a_db=levels_a,
        hp=hp,
        frames=frames,
        metrics=metrics,
        highpass_hz=highpass_hz,
        curves=loudness_curves(
            *energy,
            segment_peak=segment_peak,
            dynamics=dynamics,
            sample_rate=audio.sample_rate,
        ),
    )
