"""Small signal-processing helpers on numpy and scipy's pocketfft (`fft.py`).

``scipy.signal`` is not used: importing it costs about a second here, a fifth of the time
budget for a whole song. What Song mode needs from it is small: a Hann window, a
Kaiser-windowed low-pass, a biquad cascade (applied as an FFT convolution with its impulse
response, which for the K-weighting filter decays below 1e-13 within about 0.2 s) and a
polyphase upsampler.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from loudscape_extract.fft import irfft, rfft

__all__ = [
    "fft_convolve",
    "hann_window",
    "kaiser_lowpass",
    "sos_filter",
    "sos_impulse_response",
    "upsample_polyphase",
]


def hann_window(n: int) -> np.ndarray:
    """Periodic Hann window (``scipy.signal.get_window("hann", n)``).

    Returns
    -------
    window : np.ndarray [shape=(n,), dtype=float64]
    """
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def kaiser_lowpass(numtaps: int, cutoff: float, *, beta: float) -> np.ndarray:
    """Windowed-sinc low-pass, unity gain at DC (``scipy.signal.firwin(numtaps, cutoff,
    window=("kaiser", beta))``).

    Parameters
    ----------
    numtaps : int
        Odd filter length.
    cutoff : float
        Cut-off as a fraction of the Nyquist frequency, in (0, 1).
    beta : float
        Kaiser window shape.

    Returns
    -------
    taps : np.ndarray [shape=(numtaps,)]
    """
    n = np.arange(numtaps) - (numtaps - 1) / 2.0
    taps = cutoff * np.sinc(cutoff * n) * np.kaiser(numtaps, beta)
    return taps / taps.sum()


def sos_impulse_response(sos: np.ndarray, *, tolerance: float = 1e-14, max_length: int = 1 << 20):
    """Impulse response of a cascade of biquads, cut where it has decayed below ``tolerance``
    times its peak for good (checked over a run of 1024 samples).

    Parameters
    ----------
    sos : np.ndarray [shape=(n_sections, 6)]
        ``b0 b1 b2 a0 a1 a2`` per section, ``a0 = 1``, all poles inside the unit circle.

    Returns
    -------
    h : np.ndarray [shape=(n,)]
    """
    block = 4096
    h = np.zeros(block)
    h[0] = 1.0
    length = block
    while True:
        y = h.copy()
        for b0, b1, b2, _a0, a1, a2 in np.asarray(sos, dtype=np.float64):
            y = _biquad(y, b0, b1, b2, a1, a2)
        peak = np.abs(y).max()
        tail = np.flatnonzero(np.abs(y) > tolerance * peak)
        end = int(tail[-1]) + 1 if tail.size else 1
        if end + 1024 <= length or length >= max_length:
            return y[:end]
        length *= 2
        h = np.zeros(length)
        h[0] = 1.0


def _biquad(x: np.ndarray, b0: float, b1: float, b2: float, a1: float, a2: float) -> np.ndarray:
    """Direct-form filtering of a short array (used only for impulse responses)."""
    y = np.empty_like(x)
    x1 = x2 = y1 = y2 = 0.0
    for i, value in enumerate(x.tolist()):
        out = b0 * value + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2
        y[i] = out
        x2, x1, y2, y1 = x1, value, y1, out
    return y


def fft_convolve(x: np.ndarray, h: np.ndarray, *, dtype=np.float64) -> np.ndarray:
    """Causal linear convolution ``y[n] = sum_k h[k] x[n - k]`` along the last axis, first
    ``n`` samples (what ``scipy.signal.lfilter(h, 1, x)`` gives), by overlap-save.

    Parameters
    ----------
    x : np.ndarray [shape=(..., n)]
    h : np.ndarray [shape=(m,)]
    dtype : {np.float64, np.float32}
        Working precision (float32 halves the time; relative error about 1e-7).

    Returns
    -------
    y : np.ndarray [shape=(..., n), dtype=dtype]
    """
    x = np.asarray(x)
    lead, n = x.shape[:-1], x.shape[-1]
    x = x.reshape(-1, n)
    m = h.shape[0]
    size = 1 << max(16, math.ceil(math.log2(4 * m)))
    step = size - m + 1
    n_blocks = -(-n // step)
    spectrum = rfft(np.asarray(h, dtype=dtype), size)
    padded = np.zeros((x.shape[0], m - 1 + n_blocks * step + size), dtype=dtype)
    padded[:, m - 1 : m - 1 + n] = x
    y = np.empty((x.shape[0], n_blocks * step), dtype=dtype)
    batch = 8
    item = padded.itemsize
    for first in range(0, n_blocks, batch):
        count = min(batch, n_blocks - first)
        # (rows, count, size) windows of padded, step apart: a view (the transform reads it
        # in place; gathering a copy first cost as much as the transforms)
        segments = np.lib.stride_tricks.as_strided(
            padded[:, first * step :],
            shape=(x.shape[0], count, size),
            strides=(padded.strides[0], step * item, item),
            writeable=False,
        )
        spectra = rfft(segments, axis=-1)
        spectra *= spectrum
        out = irfft(spectra, size, axis=-1)
        y[:, first * step : (first + count) * step] = out[:, :, m - 1 :].reshape(x.shape[0], -1)
    return y[:, :n].reshape(*lead, n)


def sos_filter(sos: np.ndarray, x: np.ndarray, *, dtype=np.float64) -> np.ndarray:
    """Filter with a stable biquad cascade from rest along the last axis
    (``scipy.signal.sosfilt(sos, x)`` to about 1e-12 relative in float64).

    Parameters
    ----------
    sos : np.ndarray [shape=(n_sections, 6)]
    x : np.ndarray [shape=(..., n)]
    dtype : {np.float64, np.float32}
        Working precision.

    Returns
    -------
    y : np.ndarray [shape=(..., n), dtype=dtype]
    """
    return fft_convolve(x, _cached_impulse_response(tuple(np.asarray(sos).ravel())), dtype=dtype)


@functools.lru_cache(maxsize=8)
def _cached_impulse_response(flat_sos: tuple) -> np.ndarray:
    return sos_impulse_response(np.array(flat_sos).reshape(-1, 6))


def upsample_polyphase(x: np.ndarray, taps: np.ndarray, *, factor: int) -> np.ndarray:
    """Interpolate by ``factor``: insert zeros, filter with ``taps`` (``len(taps)`` a multiple
    of ``factor`` plus one or not), keeping only outputs whose window lies inside ``x``.

    Output ``j * factor + p`` is ``sum_k taps[p + k * factor] * x[j + K - 1 - k]`` with ``K``
    the taps per phase, i.e. the full upsampled signal of ``scipy.signal.upfirdn(taps, x,
    factor)`` from index ``(K - 1) * factor`` on.

    Parameters
    ----------
    x : np.ndarray [shape=(..., n)]
    taps : np.ndarray [shape=(m,)]
    factor : int

    Returns
    -------
    y : np.ndarray [shape=(..., (n - K + 1) * factor)]
    """
    per_phase = -(-taps.shape[0] // factor)
    padded_taps = np.zeros(per_phase * factor, dtype=x.dtype)
    padded_taps[: taps.shape[0]] = taps
    # phases[p, k] = taps[p + k * factor]; reversed in k to correlate with a forward window.
    phases = padded_taps.reshape(per_phase, factor).T[:, ::-1]
    windows = np.lib.stride_tricks.sliding_window_view(x, per_phase, axis=-1)
    out = windows @ phases.T  # (..., n - K + 1, factor)
    return out.reshape(*out.shape[:-2], -1)
