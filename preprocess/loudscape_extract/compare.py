"""Compare releases of one song as a mastering engineer does: aligned, matched in loudness.

:func:`compare_versions` takes 2 to 8 decoded versions, the first the reference, and gives for
each its offset against the first (:mod:`loudscape_extract.align`), the gain that matches its
integrated loudness to the quietest version's (or to a normalization preset's level), its
loudness and dynamics metrics, its short-term loudness curve on the first version's clock, and
its long-term average spectrum in 1/3-octave bands at matched loudness with the difference to
the first version: what is left once loudness is matched (dynamics and tonal balance).
docs/COMPARE.md ("Many versions") says how and where it fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from loudscape_extract.align import Alignment, align
from loudscape_extract.audio import Audio, mix_to_mono
from loudscape_extract.dynamics import (
    dc_and_highpass,
    dr_meter,
    short_term_dynamics,
    song_dynamics_metrics,
)
from loudscape_extract.errors import ExtractError
from loudscape_extract.loudness import (
    loudness_from_energy,
    segment_energy_and_maxima,
    true_peak_dbtp,
)
from loudscape_extract.normalization import PRESETS, preset_gain, streaming_gains

__all__ = [
    "MAX_VERSIONS",
    "METRIC_KEYS",
    "THIRD_OCTAVE_HZ",
    "Version",
    "compare_versions",
    "third_octave_spectrum",
    "version_metrics",
]

MAX_VERSIONS = 8
#: The metrics of the comparison table, in its order.
METRIC_KEYS = (
    "integrated_lufs",
    "lra_lu",
    "true_peak_dbtp",
    "max_momentary_lufs",
    "max_short_term_lufs",
    "plr_db",
    "psr_median_db",
    "dr_db",
)
#: ISO 266 preferred 1/3-octave centre frequencies, 25 Hz to 16 kHz.
THIRD_OCTAVE_HZ = (
    25, 31.5, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500, 630, 800, 1000, 1250,
    1600, 2000, 2500, 3150, 4000, 5000, 6300, 8000, 10000, 12500, 16000,
)  # fmt: skip


#: Segments of the long-term spectrum's Welch average computed at a time.
_WELCH_RUN = 256


@dataclass(frozen=True)
class Version:
    """One release in a comparison.

    Attributes
    ----------
    path : str
    metrics : dict
        :data:`METRIC_KEYS` and ``streaming`` (each service's gain, dB).
    alignment : Alignment
        Against the first version (the first's own is offset 0, confidence 1).
    match_gain_db : float or None
        The gain that brings its integrated loudness to the matching level.
    short_term_times_s : np.ndarray
        The short-term curve's times on the *first* version's clock, through the time map
        (NaN where the version's music is not in the first).
    short_term_lufs : np.ndarray
    spectrum_db : np.ndarray [shape=(len(THIRD_OCTAVE_HZ),)]
        Band levels at matched loudness, dB (relative to full scale).
    spectrum_difference_db : np.ndarray
        ``spectrum_db`` minus the first version's, per band.
    warnings : tuple of str
        The decoder's warning (a truncated or corrupt file: the numbers are of the part that
        decoded), in the JSON and the CSV, since a reader of those sees no stderr.
    """

    path: str
    metrics: dict
    alignment: Alignment
    match_gain_db: float | None
    short_term_times_s: np.ndarray
    short_term_lufs: np.ndarray
    spectrum_db: np.ndarray
    spectrum_difference_db: np.ndarray
    warnings: tuple[str, ...] = ()

    def to_json(self) -> dict:
        def clean(v):
            return None if v is None or not math.isfinite(v) else round(float(v), 3)

        return {
            "path": self.path,
            "offset_s": (
                round(self.alignment.offset_s, 6) + 0.0 if self.alignment.alignable else None
            ),
            "alignment": self.alignment.to_json(),
            "match_gain_db": clean(self.match_gain_db),
            "metrics": {k: clean(self.metrics.get(k)) for k in METRIC_KEYS},
            "streaming": {k: clean(v) for k, v in self.metrics.get("streaming", {}).items()},
            "spectrum_difference_db": {
                str(f): clean(d)
                for f, d in zip(THIRD_OCTAVE_HZ, self.spectrum_difference_db, strict=True)
            },
            "warnings": list(self.warnings),
        }


def version_metrics(audio: Audio) -> tuple[dict, np.ndarray, np.ndarray]:
    """The comparison's metrics of one version, with its short-term curve (times, LUFS).

    The same functions and the same DC removal as the extractor's song metrics, without the
    spectrogram: integrated loudness, LRA, true peak, max momentary and short-term loudness
    at any window position, PLR, PSR median, DR, and each streaming service's gain.
    """
    samples = audio.samples
    rate = audio.sample_rate
    clean, dc = dc_and_highpass(samples, sample_rate=rate, highpass_hz=None)
    mono_clean = mix_to_mono(samples) - np.float32(dc.mean())
    energy, maxima = segment_energy_and_maxima(clean, sample_rate=rate)
    dynamics = short_term_dynamics(clean, mono_clean, sample_rate=rate, energy=energy)
    integrated, lra = loudness_from_energy(*energy)
    clean_peak = 20.0 * math.log10(dynamics.true_peak) if dynamics.true_peak > 0 else None
    metrics = {
        "integrated_lufs": integrated,
        "lra_lu": lra,
        "true_peak_dbtp": true_peak_dbtp(samples, sample_rate=rate),
        "plr_db": None if integrated is None or clean_peak is None else clean_peak - integrated,
        "dr_db": dr_meter(clean, sample_rate=rate),
    }
    metrics["max_momentary_lufs"] = maxima.get("max_momentary_lufs")
    metrics["max_short_term_lufs"] = maxima.get("max_short_term_lufs")
    metrics["psr_median_db"] = song_dynamics_metrics(dynamics)["psr_median_db"]
    metrics = {
        k: (None if v is None or not math.isfinite(v) else float(v)) for k, v in metrics.items()
    }
    metrics["streaming"] = streaming_gains(metrics)
    times = np.asarray(dynamics.start_s, dtype=np.float64) + 3.0  # a window's end: when heard
    return metrics, times, np.asarray(dynamics.short_term_lufs, dtype=np.float64)


def third_octave_spectrum(audio: Audio, gain_db: float = 0.0) -> np.ndarray:
    """The long-term average spectrum in 1/3-octave bands, dB, after ``gain_db``.

    Welch's average of the mono mix's power spectrum (Hann, 8192-sample segments at 44.1/48
    kHz, half overlap), summed over each band's edges (centre x 2^(+-1/6)). A band above
    Nyquist or without a bin is NaN.
    """
    mono = mix_to_mono(audio.samples)
    rate = audio.sample_rate
    nperseg = min(len(mono), 1 << int(round(math.log2(rate * 0.17))))
    # Welch's average taken over runs of _WELCH_RUN segments (half overlap, as welch steps)
    # and weighted by their counts: welch holds every segment and its spectrum at once,
    # 2 GB for a 20-minute song; a run holds a few megabytes.
    step = nperseg - nperseg // 2
    n_segments = (len(mono) - nperseg) // step + 1
    # Imported here: scipy.signal costs every extractor command 0.6-0.8 s of start-up.
    from scipy.signal import welch

    psd, freqs = 0.0, None
    for first in range(0, n_segments, _WELCH_RUN):
        count = min(_WELCH_RUN, n_segments - first)
        part = mono[first * step : first * step + (count - 1) * step + nperseg]
        freqs, run = welch(part.astype(np.float64), fs=rate, nperseg=nperseg, scaling="spectrum")
        psd = psd + run * (count / n_segments)
    out = np.full(len(THIRD_OCTAVE_HZ), np.nan)
    for i, centre in enumerate(THIRD_OCTAVE_HZ):
        lo, hi = centre * 2 ** (-1 / 6), centre * 2 ** (1 / 6)
        band = (freqs >= lo) & (freqs < hi)
        if hi <= rate / 2 and band.any():
            power = float(psd[band].sum())
            out[i] = 10.0 * math.log10(power) + gain_db if power > 0 else -np.inf
    return out


def compare_versions(
    audios: list[Audio], *, match: str = "quietest", progress=None
) -> list[Version]:
    """Align every version to the first and match their loudness.

    Parameters
    ----------
    audios : list of Audio
        2 to :data:`MAX_VERSIONS` versions; the first is the reference.
    match : str
        ``"quietest"`` (each version to the quietest one's integrated loudness, so nothing is
        turned up) or a normalization preset's key (each to that service's level with its rules,
        docs/DYNAMICS.md).
    progress : callable, optional
        Called with a short message before each version's work.

    Raises
    ------
    ExtractError
        Fewer than 2 or more than 8 versions, or an unknown ``match``.
    """
    if not 2 <= len(audios) <= MAX_VERSIONS:
        raise ExtractError(f"compare takes 2 to {MAX_VERSIONS} versions, got {len(audios)}")
    if match != "quietest" and match not in PRESETS:
        raise ExtractError(
            f"--match {match!r} is not one of: quietest, {', '.join(sorted(PRESETS))}"
        )
    say = progress or (lambda _message: None)
    measured = []
    for audio in audios:
        say(f"measuring {audio.path}")
        measured.append(version_metrics(audio))
    levels = [m[0]["integrated_lufs"] for m in measured]
    known = [v for v in levels if v is not None]
    gains: list[float | None] = []
    for metrics, _, _ in measured:
        if metrics["integrated_lufs"] is None:
            gains.append(None)
        elif match == "quietest":
            gains.append(min(known) - metrics["integrated_lufs"])
        else:
            gains.append(preset_gain(match, metrics))
    first = audios[0]
    out: list[Version] = []
    reference_spectrum = None
    for i, (audio, (metrics, times, short_term), gain) in enumerate(
        zip(audios, measured, gains, strict=True)
    ):
        if i == 0:
            alignment = Alignment(alignable=True, offset_s=0.0, confidence=1.0)
        else:
            say(f"aligning {audio.path} to {first.path}")
            alignment = align(first.samples, audio.samples, first.sample_rate, audio.sample_rate)
        spectrum = third_octave_spectrum(audio, gain or 0.0)
        if reference_spectrum is None:
            reference_spectrum = spectrum
        out.append(
            Version(
                path=audio.path,
                metrics=metrics,
                alignment=alignment,
                match_gain_db=gain,
                short_term_times_s=alignment.a_time(times),
                short_term_lufs=short_term,
                spectrum_db=spectrum,
                spectrum_difference_db=spectrum - reference_spectrum,
                warnings=(audio.warning,) if audio.warning else (),
            )
        )
    return out
