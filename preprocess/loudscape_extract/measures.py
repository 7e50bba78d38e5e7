"""Per-frame series and whole-track metrics of one track, one copy for the streamed pipeline
(:mod:`loudscape_extract.stream`, production) and the whole-track reference
(:mod:`loudscape_extract.features`): each computes its sums and spectra its own way (block by
block, or all at once) and turns them into the same series and metrics here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from loudscape_extract.dynamics import Dynamics, frame_windows, song_dynamics_metrics
from loudscape_extract.loudness import loudness_from_energy, momentary_per_frame

#: The maxima of :func:`~loudscape_extract.loudness.window_maxima`, in the metrics' order.
WINDOW_MAXIMA_KEYS = (
    "max_momentary_lufs",
    "max_momentary_s",
    "max_short_term_lufs",
    "max_short_term_s",
)

__all__ = [
    "FrameFeatures",
    "TrackDescription",
    "WINDOW_MAXIMA_KEYS",
    "a_power_gain",
    "crest_statistics",
    "dynamics_series",
    "level_series",
    "spectral_series",
    "track_metrics",
]


@dataclass(frozen=True)
class TrackDescription:
    """What any analysed track says of itself: the file's and the STFT's numbers.

    Attributes
    ----------
    path : str
        Source path as given.
    sample_rate, n_channels, n_samples : int
        Of the decoded file.
    n_fft, hop_length : int
        STFT parameters.
    """

    path: str
    sample_rate: int
    n_channels: int
    n_samples: int
    n_fft: int
    hop_length: int

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate


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


def level_series(
    rms: np.ndarray, peak: np.ndarray, silent: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``rms_dbfs`` and ``crest_db`` of :class:`FrameFeatures` from each frame's RMS and peak."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rms_dbfs = np.where(silent, -np.inf, 20.0 * np.log10(rms))
        crest_db = np.where(silent, np.nan, 20.0 * np.log10(peak / rms))
    return rms_dbfs, crest_db


def a_power_gain(a_gain_db: np.ndarray) -> np.ndarray:
    """Each bin's A-weighting as a float32 power gain."""
    return (10.0 ** (a_gain_db / 10.0)).astype(np.float32)


def spectral_series(
    magnitude: np.ndarray,
    *,
    power_gain: np.ndarray,
    silent: np.ndarray,
    hp: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """``loudness_a_db`` and ``hp_mean`` (None without ``hp``) of :class:`FrameFeatures` for
    the frames of ``magnitude`` (bins x frames); ``power_gain`` from :func:`a_power_gain`."""
    hp_mean = None
    with np.errstate(divide="ignore", invalid="ignore"):
        power = np.square(magnitude, dtype=np.float32)
        a_power = power_gain @ power
        loudness_a_db = np.where(silent, np.nan, 10.0 * np.log10(a_power / 1.5))
        if hp is not None:
            total = np.ones(power.shape[0], dtype=np.float32) @ power
            hp_power = np.einsum("ij,ij->j", hp, power, dtype=np.float64)
            hp_mean = np.where(silent | (total == 0), np.nan, hp_power / total)
    return loudness_a_db, hp_mean


def dynamics_series(
    times_s: np.ndarray,
    silent: np.ndarray,
    dynamics: Dynamics,
    energy: np.ndarray,
    boundaries: np.ndarray,
) -> dict[str, np.ndarray]:
    """The per-frame ``psr_db``, ``crest_3s_db``, ``short_term_lufs`` and ``momentary_lufs``
    of :class:`FrameFeatures` (NaN for silent frames)."""
    window = frame_windows(times_s, dynamics)
    has_windows = dynamics.start_s.shape[0] > 0

    def per_frame(series):
        values = series[window] if has_windows else np.full(window.shape, np.nan)
        return np.where(silent, np.nan, values)

    return {
        "psr_db": per_frame(dynamics.psr_db),
        "crest_3s_db": per_frame(dynamics.crest_3s_db),
        "short_term_lufs": per_frame(dynamics.short_term_lufs),
        "momentary_lufs": np.where(
            silent, np.nan, momentary_per_frame(times_s, energy, boundaries)
        ),
    }


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


def track_metrics(
    *,
    energy: np.ndarray,
    boundaries: np.ndarray,
    dynamics: Dynamics,
    sample_peak_dbfs: float | None,
    true_peak_dbtp: float | None,
    crest_db: np.ndarray,
    dc: np.ndarray,
    dr_db: float | None,
    window_maxima: dict | None = None,
) -> dict:
    """The whole-track metrics (:attr:`TrackFeatures.metrics`), in the file's key order.

    Loudness, LRA and PLR of the DC-free (and high-passed) signal from its 100 ms segment
    energies, and its maximum momentary and short-term loudness at any window position with
    their times (``window_maxima``, :func:`~loudscape_extract.loudness.window_maxima`'s keys;
    None without it); the peaks of the file as decoded, as any meter reads them. Values that
    are not finite become None.
    """
    integrated, lra = loudness_from_energy(energy, boundaries)
    clean_peak = 20.0 * math.log10(dynamics.true_peak) if dynamics.true_peak > 0 else None
    metrics = {
        "integrated_lufs": integrated,
        "lra_lu": lra,
        "sample_peak_dbfs": sample_peak_dbfs,
        "true_peak_dbtp": true_peak_dbtp,
        "plr_db": None if integrated is None or clean_peak is None else clean_peak - integrated,
    }
    maxima = window_maxima or {}
    for key in WINDOW_MAXIMA_KEYS:
        metrics[key] = maxima.get(key)
    metrics.update(crest_statistics(crest_db))
    metrics["dc_offset"] = float(np.max(np.abs(dc)))
    metrics["dr_db"] = dr_db
    metrics.update(song_dynamics_metrics(dynamics))
    return {key: (None if v is None or not math.isfinite(v) else v) for key, v in metrics.items()}
