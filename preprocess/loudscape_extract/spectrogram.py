"""Short-time Fourier transform, per-bin levels and A-weighting."""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.dsp import hann_window
from loudscape_extract.errors import ExtractError
from loudscape_extract.fft import rfft

__all__ = [
    "LEVEL_FLOOR_DB",
    "a_weighting_db",
    "frame_count",
    "frame_signal",
    "frame_times",
    "level_a_db",
    "level_db",
    "stft_magnitude",
]

#: Levels are computed as ``20 log10(max(magnitude, 1e-10))``: nothing is below -200 dB.
LEVEL_FLOOR_DB = -200.0
_MAGNITUDE_FLOOR = 10.0 ** (LEVEL_FLOOR_DB / 20.0)
_CHUNK_FRAMES = 512


def _check_framing(n_samples: int, n_fft: int, hop_length: int) -> None:
    if n_fft < 4 or n_fft % 2:
        raise ExtractError(f"n_fft must be an even integer >= 4, got {n_fft}")
    if not 1 <= hop_length <= n_fft:
        raise ExtractError(f"hop_length must be in [1, n_fft={n_fft}], got {hop_length}")
    if n_samples < n_fft:
        raise ExtractError(
            f"audio of {n_samples} samples is shorter than one STFT frame (n_fft={n_fft})"
        )


def frame_count(n_samples: int, *, n_fft: int, hop_length: int) -> int:
    """Number of centred frames: ``1 + n_samples // hop_length`` (librosa's ``center=True``)."""
    return 1 + (n_samples + 2 * (n_fft // 2) - n_fft) // hop_length


def frame_times(n_frames: int, *, sample_rate: float, hop_length: int) -> np.ndarray:
    """Centre time of each frame in seconds.

    Returns
    -------
    times : np.ndarray [shape=(n_frames,), dtype=float64]
        ``t * hop_length / sample_rate``.
    """
    return np.arange(n_frames, dtype=np.float64) * hop_length / float(sample_rate)


def frame_signal(y: np.ndarray, *, n_fft: int, hop_length: int) -> np.ndarray:
    """Centred frames of a mono signal, zero-padded by ``n_fft // 2`` at both ends.

    Parameters
    ----------
    y : np.ndarray [shape=(n_samples,)]
    n_fft : int
        Frame length in samples (even).
    hop_length : int
        Frame step in samples.

    Returns
    -------
    frames : np.ndarray [shape=(n_frames, n_fft)]
        A read-only strided view (no copy); frame ``t`` is centred on sample ``t * hop_length``.
    """
    y = np.asarray(y)
    if y.ndim != 1:
        raise ExtractError(f"expected a mono signal of shape (n_samples,), got {y.shape}")
    _check_framing(y.shape[0], n_fft, hop_length)
    padded = np.pad(y, n_fft // 2, mode="constant")
    return sliding_window_view(padded, n_fft)[::hop_length]


def stft_magnitude(y: np.ndarray, *, n_fft: int = 2048, hop_length: int = 1024) -> np.ndarray:
    """Magnitude STFT with a periodic Hann window, scaled so a full-scale sine reads 1.

    Frames are centred (librosa's ``center=True`` with zero padding), so bins 1 to
    ``n_fft / 2 - 1`` equal ``np.abs(librosa.stft(y, n_fft=n_fft, hop_length=hop_length)) /
    (window.sum() / 2)`` and bins 0 and ``n_fft / 2`` half of that.

    Parameters
    ----------
    y : np.ndarray [shape=(n_samples,)]
        Mono signal, n_samples >= n_fft.
    n_fft : int
    hop_length : int

    Returns
    -------
    magnitude : np.ndarray [shape=(1 + n_fft // 2, n_frames), dtype=float32]
        A sine of amplitude 1 whose frequency is a bin centre gives 1.0 (0 dB) in that bin; a
        constant (DC) of amplitude A gives A in bin 0, and likewise the Nyquist bin (they are
        scaled by ``1 / sum(window)``, the other bins by ``2 / sum(window)``).
    """
    frames = frame_signal(np.asarray(y, dtype=np.float32), n_fft=n_fft, hop_length=hop_length)
    window = hann_window(n_fft).astype(np.float32)
    window_scaled = window * np.float32(2.0 / window.sum())
    n_frames = frames.shape[0]
    magnitude = np.empty((n_fft // 2 + 1, n_frames), dtype=np.float32)
    for start in range(0, n_frames, _CHUNK_FRAMES):
        stop = min(start + _CHUNK_FRAMES, n_frames)
        spectrum = rfft(frames[start:stop] * window_scaled, axis=1)
        magnitude[:, start:stop] = np.abs(spectrum).T
    # DC and Nyquist have no negative-frequency twin: the one-sided factor 2 does not apply,
    # so a constant of amplitude A reads A in bin 0 (not 2 A, 6.02 dB too high).
    magnitude[0] *= np.float32(0.5)
    magnitude[-1] *= np.float32(0.5)
    return magnitude


def level_db(magnitude: np.ndarray) -> np.ndarray:
    """Log amplitude: ``20 log10(max(magnitude, 1e-10))`` in dB (so never below -200 dB).

    Parameters
    ----------
    magnitude : np.ndarray [shape=(...)]

    Returns
    -------
    level : np.ndarray [shape=(...), dtype=float32]
    """
    magnitude = np.asarray(magnitude, dtype=np.float32)
    out = np.maximum(magnitude, np.float32(_MAGNITUDE_FLOOR))
    np.log10(out, out=out)
    out *= np.float32(20.0)
    return out


def level_a_db(levels: np.ndarray, a_gain_db: np.ndarray) -> np.ndarray:
    """A-weighted bin levels: ``levels`` (bins x frames, dB, float32) plus each bin's
    A-weighting gain, clipped at :data:`LEVEL_FLOOR_DB`."""
    levels_a = levels + a_gain_db[:, None].astype(np.float32)
    np.maximum(levels_a, np.float32(LEVEL_FLOOR_DB), out=levels_a)
    return levels_a


def a_weighting_db(frequencies: np.ndarray, *, min_db: float = LEVEL_FLOOR_DB) -> np.ndarray:
    """A-weighting gain in dB (IEC 61672-1:2013, analogue formula, normalised to 0 dB at 1 kHz).

    Parameters
    ----------
    frequencies : np.ndarray [shape=(n,)]
        Frequencies in Hz, >= 0.
    min_db : float
        Gains below this are clipped to it (0 Hz has -inf gain).

    Returns
    -------
    gain : np.ndarray [shape=(n,), dtype=float64]
        About -19.1 dB at 100 Hz, 0.0 dB at 1 kHz, +1.3 dB at 2.5 kHz.
    """
    f = np.asarray(frequencies, dtype=np.float64)
    if np.any(f < 0) or not np.all(np.isfinite(f)):
        raise ExtractError(f"frequencies must be finite and >= 0, got min {np.min(f)}")
    # The standard's +2.00 dB constant leaves a few thousandths of a dB at 1 kHz; make it 0.
    gain = _a_weighting_raw_db(f) - _a_weighting_raw_db(np.array([1000.0]))[0]
    return np.maximum(gain, min_db)


def _a_weighting_raw_db(f: np.ndarray) -> np.ndarray:
    f2 = f * f
    c1, c2, c3, c4 = 20.598997**2, 107.65265**2, 737.86223**2, 12194.217**2
    with np.errstate(divide="ignore"):
        response = c4 * f2 * f2 / ((f2 + c1) * np.sqrt((f2 + c2) * (f2 + c3)) * (f2 + c4))
        return 20.0 * np.log10(response) + 2.0
