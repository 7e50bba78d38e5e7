"""Dynamics of a track at musical time scales: DC removal, short-term PSR and crest, TT DR.

The frame crest factor of one STFT frame (46 ms) measures waveform shape, not how hard a master
was compressed. These measures look at 3 s, the scale of a phrase:

- **PSR** (peak to short-term loudness ratio): true peak of a 3 s window minus its BS.1770
  short-term loudness (the term proposed to the AES for this use);
- **3 s crest factor**: sample peak over RMS of the DC-free mono mix in a 3 s window;
- **DR**: the TT Dynamic Range meter's value (3 s blocks per channel, RMS of the loudest 20 %
  of blocks against the second-highest block peak; RMS with the meter's +3.01 dB so a sine
  reads 0 dB).

Everything is computed on a 100 ms segment grid (BS.1770's): per segment the K-weighted energy,
the true peak, the sample peak and the sum of squares; windows are 30 consecutive segments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.dsp import sos_filter
from loudscape_extract.errors import ExtractError
from loudscape_extract.fft import irfft, rfft
from loudscape_extract.loudness import (
    ABSOLUTE_GATE_LUFS,
    TRUE_PEAK_OVERSAMPLING,
    interpolator_taps,
    segment_energy,
    valid_interpolated_samples,
)

__all__ = [
    "DC_WARN_THRESHOLD",
    "HIGHPASS_HZ",
    "SHORT_TERM_SEGMENTS",
    "Dynamics",
    "dc_and_highpass",
    "dc_message",
    "dc_warning",
    "dr_block_length",
    "dr_from_blocks",
    "dr_meter",
    "dynamics_from_segments",
    "frame_windows",
    "highpass_sos",
    "segment_true_peak",
    "short_term_dynamics",
    "song_dynamics_metrics",
]

#: A channel mean above this (about -40 dBFS) is reported as a large DC offset.
DC_WARN_THRESHOLD = 0.01
#: Cut-off of the optional infrasound high-pass.
HIGHPASS_HZ = 20.0
#: 3 s windows of 100 ms segments.
SHORT_TERM_SEGMENTS = 30
_DR_BLOCK_S = 3.0
_DR_LOUDEST = 0.2


def dc_message(offset: float) -> str:
    """The one-line warning for a large DC offset, without the file name."""
    return (
        f"DC offset {offset:.3f} of full scale "
        f"({20.0 * math.log10(offset):.1f} dBFS) removed before level, crest, PSR and DR"
    )


def dc_warning(path: str, offset: float) -> str:
    """The one-line warning for a large DC offset."""
    return f"{path}: {dc_message(offset)}"


def highpass_sos(cutoff_hz: float, *, sample_rate: float) -> np.ndarray:
    """Second-order Butterworth high-pass (bilinear transform, pre-warped), one biquad.

    Returns
    -------
    sos : np.ndarray [shape=(1, 6)]
    """
    if not 0 < cutoff_hz < sample_rate / 2:
        raise ExtractError(
            f"high-pass cut-off must be in (0, {sample_rate / 2}) Hz, got {cutoff_hz}"
        )
    k = math.tan(math.pi * cutoff_hz / sample_rate)
    q = 1.0 / math.sqrt(2.0)
    a0 = 1.0 + k / q + k * k
    b = [1.0 / a0, -2.0 / a0, 1.0 / a0]
    a = [1.0, 2.0 * (k * k - 1.0) / a0, (1.0 - k / q + k * k) / a0]
    return np.array([b + a], dtype=np.float64)


def dc_and_highpass(
    samples: np.ndarray, *, sample_rate: float, highpass_hz: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Remove each channel's mean (DC offset), then optionally high-pass at ``highpass_hz``.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels)]
    sample_rate : float
    highpass_hz : float, optional
        Cut-off of a 2nd-order Butterworth high-pass (e.g. :data:`HIGHPASS_HZ`); None: none.

    Returns
    -------
    clean : np.ndarray [shape=(n_samples, n_channels), dtype=float32]
    dc_offset : np.ndarray [shape=(n_channels,)]
        The mean removed from each channel (full scale 1).
    """
    x = np.asarray(samples, dtype=np.float32)
    dc = x.mean(axis=0, dtype=np.float64)
    clean = x - dc.astype(np.float32)[None, :]
    if highpass_hz is not None:
        sos = highpass_sos(highpass_hz, sample_rate=sample_rate)
        clean = np.ascontiguousarray(sos_filter(sos, clean.T, dtype=np.float32).T)
    return clean, dc


def segment_true_peak(
    samples: np.ndarray, boundaries: np.ndarray, *, oversampling: int = TRUE_PEAK_OVERSAMPLING
) -> np.ndarray:
    """Largest absolute value of the 4x-oversampled signal in each segment, over channels.

    Interpolated values are used only where the interpolator's window lies inside the signal
    (as libebur128 does: no overshoot invented at an abrupt end); every segment's sample peak is
    a lower bound.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels)]
    boundaries : np.ndarray [shape=(n_segments + 1,)]
        Segment boundaries in samples, ascending, from 0.

    Returns
    -------
    peak : np.ndarray [shape=(n_segments,)]
        Linear.
    overall : float
        The largest over the whole signal (the partial last segment included): the true peak.
    """
    n_samples, n_channels = samples.shape
    if n_samples == 0:
        return np.zeros(0), 0.0
    taps = interpolator_taps(oversampling)
    per_phase = -(-taps.shape[0] // oversampling)
    half = (per_phase - 1) // 2
    valid = valid_interpolated_samples(n_samples, oversampling=oversampling)
    end = int(boundaries[-1])
    per_sample = np.abs(samples).max(axis=1).astype(np.float32)
    # x[w .. w + per_phase - 1] is the window centred on sample w: `half` zeros in front.
    padded = np.zeros((n_channels, half + n_samples + per_phase), dtype=np.float32)
    padded[:, half : half + n_samples] = samples.T
    peak = _interpolated_peak(padded, taps, oversampling, valid)
    np.maximum(per_sample[:valid], peak, out=per_sample[:valid])
    per_segment = np.maximum.reduceat(per_sample[:end], boundaries[:-1].astype(np.int64))
    return per_segment, float(per_sample.max())


def _interpolated_peak(
    padded: np.ndarray, taps: np.ndarray, factor: int, count: int, *, size: int = 1 << 15
) -> np.ndarray:
    """Largest absolute interpolated value around each of the first ``count`` samples, over
    the rows and the ``factor`` phases: overlap-save FFT convolution with each phase of the
    polyphase filter, one forward transform per block shared by all phases.

    ``padded[:, w : w + per_phase]`` is the window centred on sample ``w``.
    """
    per_phase = -(-taps.shape[0] // factor)
    flat = np.zeros(per_phase * factor)
    flat[: taps.shape[0]] = taps
    # Phase p, as a causal filter: h_p[k] = taps[p + k * factor].
    spectra = rfft(flat.reshape(per_phase, factor).T, size, axis=-1)
    spectra = spectra.astype(np.complex64)
    step = size - per_phase + 1
    n = padded.shape[-1]
    out = np.zeros(count, dtype=np.float32)
    block = np.zeros((padded.shape[0], size), dtype=np.float32)
    for first in range(0, count, step):
        # Output k of the block's convolution is sample first + k - (per_phase - 1).
        stop = min(first + size, n)
        block[:] = 0.0
        block[:, : stop - first] = padded[:, first:stop]
        spectrum = rfft(block, axis=-1)
        m = min(step, count - first)
        best = out[first : first + m]
        for phase in range(factor):
            y = irfft(spectrum * spectra[phase], size, axis=-1)
            np.maximum(best, np.abs(y[:, per_phase - 1 : per_phase - 1 + m]).max(axis=0), out=best)
    return out


def dr_meter(samples: np.ndarray, *, sample_rate: float) -> float | None:
    """The TT Dynamic Range meter's DR value (unrounded), mean over channels.

    Per channel: 3 s blocks (the last, partial one included), block RMS ``sqrt(2 mean(x^2))``
    and block peak ``max |x|``; ``DR = 20 log10(P2 / sqrt(mean of the top 20 % block RMS^2))``
    with ``P2`` the second-highest block peak (the highest when there is one block).

    Returns
    -------
    dr_db : float or None
        None for silence.
    """
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    block = dr_block_length(sample_rate)
    n_samples = x.shape[0]
    starts = np.arange(0, n_samples, block)
    if starts.size == 0:
        return None
    lengths = np.minimum(starts + block, n_samples) - starts
    squares = np.add.reduceat(x * x, starts, axis=0)
    peaks = np.maximum.reduceat(np.abs(x), starts, axis=0)
    return dr_from_blocks(squares, peaks, lengths)


def dr_block_length(sample_rate: float) -> int:
    """Samples in one of the DR meter's 3 s blocks."""
    return int(round(_DR_BLOCK_S * sample_rate))


def dr_from_blocks(squares: np.ndarray, peaks: np.ndarray, lengths: np.ndarray) -> float | None:
    """:func:`dr_meter` from per-block sums, for callers that stream the signal.

    Parameters
    ----------
    squares, peaks : np.ndarray [shape=(n_blocks, n_channels)]
        Sum of squares (float64) and largest absolute sample of each 3 s block and channel.
    lengths : np.ndarray [shape=(n_blocks,)]
        Samples in each block (the last may be short).
    """
    n_blocks = squares.shape[0]
    if n_blocks == 0:
        return None
    rms = np.sqrt(2.0 * squares / lengths[:, None])
    loudest = max(1, int(math.floor(n_blocks * _DR_LOUDEST)))
    values = []
    for channel in range(squares.shape[1]):
        top = np.sort(rms[:, channel])[-loudest:]
        level = math.sqrt(float(np.mean(top**2)))
        ordered = np.sort(peaks[:, channel])
        second = float(ordered[-2] if n_blocks > 1 else ordered[-1])
        if level > 0 and second > 0:
            values.append(20.0 * math.log10(second / level))
    return float(np.mean(values)) if values else None


@dataclass(frozen=True)
class Dynamics:
    """Per 3 s window (30 segments of 100 ms, step 100 ms) of one track.

    Attributes
    ----------
    start_s : np.ndarray [shape=(n_windows,)]
        Window start times (window ``i`` covers segments ``i .. i + 29``).
    short_term_lufs : np.ndarray [shape=(n_windows,)]
        BS.1770 short-term loudness (``-inf`` in digital silence).
    psr_db : np.ndarray [shape=(n_windows,)]
        Window true peak (dBTP) minus short-term loudness; NaN below the -70 LUFS gate.
    crest_3s_db : np.ndarray [shape=(n_windows,)]
        ``20 log10(peak / RMS)`` of the mono mix over the window; NaN in silence.
    true_peak : float
        Linear true peak of the whole (DC-free) track.
    segment_s : float
        Segment length (0.1 s).
    """

    start_s: np.ndarray
    short_term_lufs: np.ndarray
    psr_db: np.ndarray
    crest_3s_db: np.ndarray
    true_peak: float = 0.0
    segment_s: float = 0.1


def _windows(values: np.ndarray, n: int, reduce) -> np.ndarray:
    if values.shape[0] < n:
        return reduce(values[None, :], axis=-1)
    return reduce(sliding_window_view(values, n), axis=-1)


def short_term_dynamics(
    samples: np.ndarray,
    mono: np.ndarray,
    *,
    sample_rate: float,
    energy: tuple[np.ndarray, np.ndarray] | None = None,
) -> Dynamics:
    """Short-term loudness, PSR and 3 s crest factor every 100 ms.

    A track shorter than 3 s has one window, the whole track.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels)]
        DC-free channels (loudness and true peak).
    mono : np.ndarray [shape=(n_samples,)]
        Their mono mix (crest factor).
    sample_rate : float
    energy : tuple, optional
        ``segment_energy(samples, sample_rate)`` when the caller has it already.

    Returns
    -------
    dynamics : Dynamics
    """
    energy, boundaries = energy if energy is not None else segment_energy(samples, sample_rate)
    segment_peak, overall = segment_true_peak(samples, boundaries)
    m = np.asarray(mono[: boundaries[-1]], dtype=np.float64)
    starts = boundaries[:-1].astype(np.int64)
    if starts.size:
        mono_squares = np.add.reduceat(m * m, starts)
        mono_peaks = np.maximum.reduceat(np.abs(m), starts)
    else:
        mono_squares = mono_peaks = np.zeros(0)
    return dynamics_from_segments(
        energy,
        boundaries,
        segment_peak=segment_peak,
        true_peak=overall,
        mono_squares=mono_squares,
        mono_peaks=mono_peaks,
        sample_rate=sample_rate,
    )


def dynamics_from_segments(
    energy: np.ndarray,
    boundaries: np.ndarray,
    *,
    segment_peak: np.ndarray,
    true_peak: float,
    mono_squares: np.ndarray,
    mono_peaks: np.ndarray,
    sample_rate: float,
) -> Dynamics:
    """:func:`short_term_dynamics` from per-segment sums, for callers that stream the signal.

    Parameters
    ----------
    energy, boundaries : np.ndarray
        :func:`segment_energy`'s output.
    segment_peak : np.ndarray [shape=(n_segments,)]
        True peak of each segment (:func:`segment_true_peak`).
    true_peak : float
        True peak of the whole track.
    mono_squares, mono_peaks : np.ndarray [shape=(n_segments,)]
        Sum of squares (float64) and largest absolute sample of the mono mix per segment.
    sample_rate : float

    Returns
    -------
    dynamics : Dynamics
    """
    n_segments = energy.shape[0]
    if n_segments == 0:
        empty = np.zeros(0)
        return Dynamics(empty, empty, empty, empty, true_peak=true_peak)
    n = min(SHORT_TERM_SEGMENTS, n_segments)
    lengths = _windows(np.diff(boundaries).astype(np.float64), n, np.sum)
    with np.errstate(divide="ignore", invalid="ignore"):
        loudness = -0.691 + 10.0 * np.log10(_windows(energy, n, np.sum) / lengths)
        window_peak = _windows(segment_peak, n, np.max)
        peak_db = 20.0 * np.log10(window_peak)
        psr = np.where(loudness > ABSOLUTE_GATE_LUFS, peak_db - loudness, np.nan)
        squares = _windows(mono_squares, n, np.sum)
        peaks = _windows(mono_peaks, n, np.max)
        rms = np.sqrt(squares / lengths)
        crest = np.where(peaks > 0, 20.0 * np.log10(peaks / rms), np.nan)
    start_s = boundaries[: loudness.shape[0]] / float(sample_rate)
    return Dynamics(
        start_s=start_s,
        short_term_lufs=loudness,
        psr_db=psr,
        crest_3s_db=crest,
        true_peak=true_peak,
    )


def frame_windows(times_s: np.ndarray, dynamics: Dynamics) -> np.ndarray:
    """Index of the 3 s window centred (as near as the track allows) on each time.

    Returns
    -------
    index : np.ndarray [shape=(n_times,), dtype=int64]
    """
    n_windows = dynamics.start_s.shape[0]
    if n_windows == 0:
        return np.zeros(times_s.shape, dtype=np.int64)
    half = SHORT_TERM_SEGMENTS * dynamics.segment_s / 2.0
    index = np.round((np.asarray(times_s) - half) / dynamics.segment_s).astype(np.int64)
    return np.clip(index, 0, n_windows - 1)


def _gated(dynamics: Dynamics) -> np.ndarray:
    """Windows above -70 LUFS and within 20 LU of their power mean (EBU Tech 3342's gates)."""
    loudness = dynamics.short_term_lufs
    above = np.isfinite(loudness) & (loudness > ABSOLUTE_GATE_LUFS)
    if not above.any():
        return above
    mean = 10.0 * np.log10(np.mean(10.0 ** (loudness[above] / 10.0)))
    return above & (loudness > mean - 20.0)


def song_dynamics_metrics(dynamics: Dynamics) -> dict[str, float | None]:
    """Per-song summaries of the 3 s series over the windows that LRA counts.

    Returns
    -------
    metrics : dict
        ``psr_median_db``, ``psr_p10_db``, ``psr_p90_db``, ``psr_spread_db`` (p90 - p10),
        ``crest_3s_median_db``; None when no window passes the gates.
    """
    gated = _gated(dynamics)
    psr = dynamics.psr_db[gated]
    psr = psr[np.isfinite(psr)]
    crest = dynamics.crest_3s_db[gated]
    crest = crest[np.isfinite(crest)]
    out: dict[str, float | None] = {
        "psr_median_db": None,
        "psr_p10_db": None,
        "psr_p90_db": None,
        "psr_spread_db": None,
        "crest_3s_median_db": float(np.median(crest)) if crest.size else None,
    }
    if psr.size:
        p10, p50, p90 = (float(v) for v in np.percentile(psr, [10.0, 50.0, 90.0]))
        out.update(psr_median_db=p50, psr_p10_db=p10, psr_p90_db=p90, psr_spread_db=p90 - p10)
    return out
