"""Per-bin and per-frame features of one track, plus its whole-track metrics.

This is the reusable middle of the pipeline: Song mode turns :class:`TrackFeatures` into one
point per bin; other commands (timeline, report) can use the per-frame series in
:class:`FrameFeatures` and the metrics without building points.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from loudscape_extract.audio import Audio, mix_to_mono
from loudscape_extract.errors import ExtractError
from loudscape_extract.hpss import hp_ratio, hpss_masks
from loudscape_extract.loudness import loudness_metrics
from loudscape_extract.spectrogram import (
    LEVEL_FLOOR_DB,
    a_weighting_db,
    frame_signal,
    frame_times,
    level_db,
    stft_magnitude,
)

__all__ = ["FrameFeatures", "TrackFeatures", "crest_statistics", "frame_features", "track_features"]

HPSS_KERNEL = 31
HPSS_POWER = 2.0
HPSS_MARGIN = 1.0
_CHUNK_FRAMES = 1024


@dataclass(frozen=True)
class FrameFeatures:
    """Per-frame series of the mono mix (frames as the STFT's: centred, ``n_fft`` long).

    Attributes
    ----------
    times_s : np.ndarray [shape=(n_frames,)]
        Frame centre times in seconds.
    rms_dbfs : np.ndarray [shape=(n_frames,)]
        ``20 log10(RMS)`` of the frame's samples (amplitude 1 = 0 dBFS, so a full-scale sine
        is -3.01 dBFS); ``-inf`` for silent frames.
    peak : np.ndarray [shape=(n_frames,)]
        Largest absolute sample (linear).
    crest_db : np.ndarray [shape=(n_frames,)]
        ``20 log10(peak / RMS)``; NaN for silent frames.
    loudness_a_db : np.ndarray [shape=(n_frames,)]
        A-weighted mean-square level of the frame in dBFS (same reference as ``rms_dbfs``),
        from the spectrum: ``10 log10(sum_k (m_k a_k)^2 / 3)``, where ``m_k`` is the bin
        magnitude (full-scale sine = 1) and ``a_k`` the A-weighting gain; NaN when silent.
    hp_mean : np.ndarray [shape=(n_frames,)]
        Power-weighted mean hp over the frame's bins, ``sum(hp m^2) / sum(m^2)``; NaN when
        silent.
    silent : np.ndarray [shape=(n_frames,), dtype=bool]
        True where every sample of the frame is exactly 0.
    """

    times_s: np.ndarray
    rms_dbfs: np.ndarray
    peak: np.ndarray
    crest_db: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    silent: np.ndarray


@dataclass(frozen=True)
class TrackFeatures:
    """Everything Song mode needs from one track.

    Attributes
    ----------
    path : str
        Source path as given.
    sample_rate, n_channels, n_samples : int
        Of the decoded file.
    n_fft, hop_length : int
        STFT parameters.
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
        ``crest_median_db``, ``crest_p95_db`` (float or None).
    """

    path: str
    sample_rate: int
    n_channels: int
    n_samples: int
    n_fft: int
    hop_length: int
    frequencies_hz: np.ndarray
    magnitude: np.ndarray
    level_db: np.ndarray
    level_a_db: np.ndarray
    hp: np.ndarray
    frames: FrameFeatures
    metrics: dict

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate


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


def frame_features(
    mono: np.ndarray,
    *,
    sample_rate: float,
    n_fft: int,
    hop_length: int,
    magnitude: np.ndarray,
    hp: np.ndarray,
    a_gain_db: np.ndarray,
) -> FrameFeatures:
    """Per-frame RMS, peak, crest factor, A-weighted level and mean hp.

    Parameters
    ----------
    mono : np.ndarray [shape=(n_samples,)]
        The mono mix the spectrogram came from.
    sample_rate : float
    n_fft, hop_length : int
    magnitude : np.ndarray [shape=(n_bins, n_frames)]
        From :func:`stft_magnitude` with the same ``n_fft`` and ``hop_length``.
    hp : np.ndarray [shape=(n_bins, n_frames)]
    a_gain_db : np.ndarray [shape=(n_bins,)]
        A-weighting gain per bin.

    Returns
    -------
    frames : FrameFeatures
    """
    rms, peak = _frame_rms_peak(mono, n_fft=n_fft, hop_length=hop_length)
    if magnitude.shape[1] != rms.shape[0] or hp.shape != magnitude.shape:
        raise ExtractError(
            f"magnitude {magnitude.shape} and hp {hp.shape} do not match {rms.shape[0]} frames"
        )
    silent = peak == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        rms_dbfs = 20.0 * np.log10(rms)
        crest_db = np.where(silent, np.nan, 20.0 * np.log10(peak / rms))
        power = np.square(magnitude, dtype=np.float32)
        a_power = (10.0 ** (a_gain_db / 10.0)).astype(np.float32) @ power
        loudness_a_db = np.where(silent, np.nan, 10.0 * np.log10(a_power / 3.0))
        total = np.ones(power.shape[0], dtype=np.float32) @ power
        hp_power = np.einsum("ij,ij->j", hp, power, dtype=np.float64)
        hp_mean = np.where(silent | (total == 0), np.nan, hp_power / total)
    return FrameFeatures(
        times_s=frame_times(rms.shape[0], sample_rate=sample_rate, hop_length=hop_length),
        rms_dbfs=rms_dbfs,
        peak=peak,
        crest_db=crest_db,
        loudness_a_db=loudness_a_db,
        hp_mean=hp_mean,
        silent=silent,
    )


def crest_statistics(crest_db: np.ndarray) -> dict[str, float | None]:
    """Median and 95th percentile of the frame crest factors (NaN frames ignored).

    Returns
    -------
    stats : dict
        ``crest_median_db``, ``crest_p95_db``; None when no frame has a crest factor.
    """
    valid = crest_db[np.isfinite(crest_db)]
    if valid.size == 0:
        return {"crest_median_db": None, "crest_p95_db": None}
    return {
        "crest_median_db": float(np.median(valid)),
        "crest_p95_db": float(np.percentile(valid, 95.0)),
    }


def track_features(
    audio: Audio,
    *,
    n_fft: int = 2048,
    hop_length: int = 1024,
    kernel_size: int = HPSS_KERNEL,
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
    if samples.shape[0] < n_fft:
        raise ExtractError(
            f"audio of {samples.shape[0]} samples ({audio.duration_s * 1000:.1f} ms) is shorter "
            f"than one STFT frame (n_fft={n_fft})",
            path=audio.path,
        )
    if not np.any(samples):
        raise ExtractError("audio is entirely silent (every sample is 0)", path=audio.path)
    say = progress or (lambda _message: None)
    mono = mix_to_mono(samples)
    if not np.any(mono):
        raise ExtractError("the mono mix is entirely silent (channels cancel)", path=audio.path)
    say("spectrogram")
    magnitude = stft_magnitude(mono, n_fft=n_fft, hop_length=hop_length)
    frequencies = np.arange(magnitude.shape[0]) * (audio.sample_rate / n_fft)
    a_gain = a_weighting_db(frequencies)
    levels = level_db(magnitude)
    levels_a = levels + a_gain[:, None].astype(np.float32)
    np.maximum(levels_a, np.float32(LEVEL_FLOOR_DB), out=levels_a)
    say("harmonic-percussive separation")
    mask_harmonic, mask_percussive = hpss_masks(
        magnitude, kernel_size=kernel_size, power=HPSS_POWER, margin=HPSS_MARGIN
    )
    hp = hp_ratio(magnitude, mask_harmonic, mask_percussive)
    del mask_harmonic, mask_percussive
    say("frame features")
    frames = frame_features(
        mono,
        sample_rate=audio.sample_rate,
        n_fft=n_fft,
        hop_length=hop_length,
        magnitude=magnitude,
        hp=hp,
        a_gain_db=a_gain,
    )
    say("loudness metrics (integrated, range, true peak)")
    metrics = loudness_metrics(samples, sample_rate=audio.sample_rate)
    metrics.update(crest_statistics(frames.crest_db))
    metrics = {
        key: (None if v is None or not math.isfinite(v) else v) for key, v in metrics.items()
    }
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
    )
