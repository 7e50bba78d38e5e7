"""Per-bin and per-frame features of one track, plus its whole-track metrics.

This is the reusable middle of the pipeline: Song mode turns :class:`TrackFeatures` into one
point per bin; other commands (timeline, report) can use the per-frame series in
:class:`FrameFeatures` and the metrics without building points.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from loudscape_extract.audio import Audio, mix_to_mono
from loudscape_extract.curves import loudness_curves
from loudscape_extract.dynamics import (
    dc_and_highpass,
    dr_meter,
    dynamics_from_segments,
    frame_windows,
    segment_true_peak,
    song_dynamics_metrics,
)
from loudscape_extract.errors import ExtractError
from loudscape_extract.hpss import hp_ratio, hpss_masks
from loudscape_extract.loudness import (
    loudness_from_energy,
    momentary_per_frame,
    sample_peak_dbfs,
    segment_energy,
    true_peak_dbtp,
)
from loudscape_extract.spectrogram import (
    LEVEL_FLOOR_DB,
    a_weighting_db,
    frame_count,
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
        ``20 log10(RMS)`` of the frame's samples of the DC-free mono mix (amplitude 1 = 0 dBFS,
        so a full-scale sine is -3.01 dBFS); ``-inf`` for silent frames.
    peak : np.ndarray [shape=(n_frames,)]
        Largest absolute sample (linear).
    crest_db : np.ndarray [shape=(n_frames,)]
        ``20 log10(peak / RMS)``; NaN for silent frames.
    loudness_a_db : np.ndarray [shape=(n_frames,)]
        A-weighted level of the frame in dB re a full-scale sine (Song mode's scalar
        reference: a full-scale 1 kHz sine reads 0 dB in both), from the spectrum:
        ``10 log10(sum_k (m_k a_k)^2 / 1.5)``, where ``m_k`` is the bin magnitude (full-scale
        sine = 1), ``a_k`` the A-weighting gain and 1.5 the Hann window's power sum of one
        sine over its bins; NaN when silent.
    hp_mean : np.ndarray [shape=(n_frames,)]
        Power-weighted mean hp over the frame's bins, ``sum(hp m^2) / sum(m^2)``; NaN when
        silent.
    silent : np.ndarray [shape=(n_frames,), dtype=bool]
        True where every sample of the frame is exactly 0.
    psr_db, crest_3s_db, short_term_lufs : np.ndarray [shape=(n_frames,)]
        PSR, 3 s crest factor and short-term loudness of the 3 s window centred on the frame
        (:mod:`loudscape_extract.dynamics`); NaN where not measurable. Empty arrays when
        built by :func:`frame_features` alone.
    momentary_lufs : np.ndarray [shape=(n_frames,)]
        BS.1770 momentary loudness of the 400 ms block centred on the frame
        (:func:`~loudscape_extract.loudness.momentary_per_frame`); NaN where not measurable.
    """

    times_s: np.ndarray
    rms_dbfs: np.ndarray
    peak: np.ndarray
    crest_db: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    silent: np.ndarray
    psr_db: np.ndarray = field(default_factory=lambda: np.zeros(0))
    crest_3s_db: np.ndarray = field(default_factory=lambda: np.zeros(0))
    short_term_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    momentary_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0))


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
        ``crest_median_db``, ``crest_p95_db``, ``dc_offset``, ``dr_db``, ``psr_median_db``,
        ``psr_p10_db``, ``psr_p90_db``, ``psr_spread_db``, ``crest_3s_median_db`` (float or
        None); see docs/FORMAT.md.
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
    highpass_hz: float | None = None
    curves: dict | None = None

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
    with np.errstate(divide="ignore", invalid="ignore"):
        rms_dbfs = np.where(silent, -np.inf, 20.0 * np.log10(rms))
        crest_db = np.where(silent, np.nan, 20.0 * np.log10(peak / rms))
        power = np.square(magnitude, dtype=np.float32)
        a_power = (10.0 ** (a_gain_db / 10.0)).astype(np.float32) @ power
        loudness_a_db = np.where(silent, np.nan, 10.0 * np.log10(a_power / 1.5))
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
    window = frame_windows(frames.times_s, dynamics)
    has_windows = dynamics.start_s.shape[0] > 0
    per_frame = lambda series: series[window] if has_windows else np.full(window.shape, np.nan)  # noqa: E731
    frames = replace(
        frames,
        psr_db=np.where(frames.silent, np.nan, per_frame(dynamics.psr_db)),
        crest_3s_db=np.where(frames.silent, np.nan, per_frame(dynamics.crest_3s_db)),
        short_term_lufs=np.where(frames.silent, np.nan, per_frame(dynamics.short_term_lufs)),
        momentary_lufs=np.where(
            frames.silent, np.nan, momentary_per_frame(frames.times_s, *energy)
        ),
    )
    # Loudness, LRA and PLR of the DC-free (and high-passed) signal; the peaks of the file as
    # decoded, as any meter reads them.
    integrated, lra = loudness_from_energy(*energy)
    clean_peak = 20.0 * math.log10(dynamics.true_peak) if dynamics.true_peak > 0 else None
    metrics = {
        "integrated_lufs": integrated,
        "lra_lu": lra,
        "sample_peak_dbfs": sample_peak_dbfs(samples),
        "true_peak_dbtp": true_peak_dbtp(samples, sample_rate=audio.sample_rate),
        "plr_db": None if integrated is None or clean_peak is None else clean_peak - integrated,
    }
    metrics.update(crest_statistics(frames.crest_db))
    metrics["dc_offset"] = float(np.max(np.abs(dc)))
    metrics["dr_db"] = dr_meter(clean, sample_rate=audio.sample_rate)
    metrics.update(song_dynamics_metrics(dynamics))
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
        highpass_hz=highpass_hz,
        curves=loudness_curves(
            *energy,
            segment_peak=segment_peak,
            dynamics=dynamics,
            sample_rate=audio.sample_rate,
        ),
    )
