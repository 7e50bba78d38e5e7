"""Harmonic-percussive separation masks, identical to librosa's but fast.

librosa (``librosa.decompose.hpss``) median-filters the magnitude spectrogram along time (the
harmonic estimate) and along frequency (the percussive estimate) with
``scipy.ndimage.median_filter(..., mode="reflect")`` on the 2-D array, which takes scipy's
generic n-d rank filter (about 17 s on a 3-minute song). Here every row (or column) is padded
by half a kernel with numpy's ``"symmetric"`` mode (scipy's ``"reflect"``: ``d c b a |
a b c d | d c b a``) and filtered on the floats' bits read as unsigned integers (they sort
alike for the non-negative magnitudes, and a median is one of the window's values): by the
compiled running median of crates/median (:mod:`loudscape_extract.native`) where it was
built, else by one call to scipy's 1-D running median on the padded rows laid end to end.
The padding is exactly half a kernel, so no window reaches across rows, and every median
equals librosa's bit for bit.
"""

from __future__ import annotations

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.native import available as native_available
from loudscape_extract.native import median_columns, median_rows

__all__ = [
    "HPSS_KERNEL",
    "HPSS_MARGIN",
    "HPSS_POWER",
    "HP_EPSILON",
    "hp_ratio",
    "hpss_masks",
    "masks_from_medians",
    "median_filter_axis",
]

#: Song mode's HPSS settings (librosa's ``kernel_size``, ``power`` and ``margin``).
HPSS_KERNEL = 31
HPSS_POWER = 2.0
HPSS_MARGIN = 1.0
#: The epsilon of ``hp = |H| / (|H| + |P| + eps)``, in full-scale magnitude units (-200 dB).
HP_EPSILON = 1e-10


_UNSIGNED = {np.float32: np.uint32, np.float64: np.uint64}
_POSITIVE_INFINITY_BITS = {
    np.uint32: np.array(np.inf, np.float32).view(np.uint32)[()],
    np.uint64: np.array(np.inf, np.float64).view(np.uint64)[()],
}


def median_filter_axis(data: np.ndarray, *, size: int, axis: int) -> np.ndarray:
    """Running median along one axis with scipy's ``mode="reflect"`` edges.

    Equals ``scipy.ndimage.median_filter(data, size=shape, mode="reflect")`` where ``shape``
    is 1 everywhere except ``size`` on ``axis``.

    Parameters
    ----------
    data : np.ndarray [shape=(d, n)]
        2-D float array.
    size : int
        Odd kernel length >= 1.
    axis : int
        0 (down the columns) or 1 (along the rows); negative values count from the end.

    Returns
    -------
    filtered : np.ndarray [shape=(d, n), dtype=data.dtype]
    """
    data = np.asarray(data)
    if data.ndim != 2:
        raise ExtractError(f"median_filter_axis expects a 2-D array, got shape {data.shape}")
    if size < 1 or size % 2 == 0:
        raise ExtractError(f"median kernel size must be odd and >= 1, got {size}")
    if data.dtype not in (np.float32, np.float64):
        data = data.astype(np.float64)
    axis = axis % 2
    d = data.shape[axis]  # length filtered along
    rows = data.shape[1 - axis]
    if size == 1 or d == 0 or rows == 0:
        return data.copy()
    half = size // 2
    # Non-negative floats (no -0.0, no NaN) sort as their bits do read as unsigned integers.
    unsigned = _UNSIGNED[data.dtype.type]
    as_integers = (
        data.dtype == np.float32 and data.view(unsigned).max() <= _POSITIVE_INFINITY_BITS[unsigned]
    )
    if as_integers and native_available():
        # The compiled kernel filters down the columns as they lie, and along the rows.
        keys = _pad_symmetric(data.view(np.uint32), half, axis, np.uint32)
        if axis == 1:
            return median_rows(keys, size).view(np.float32)
        return median_columns(keys, size).view(np.float32)
    import scipy.ndimage  # only here: its import is a cost the compiled kernel saves

    # scipy's 1-D running median is about a quarter faster on integers than on floats; it
    # runs on int64 (any other integer type is cast to it first and back after), so the bits
    # go straight into an int64 padded copy and come back from scipy's int64 output.
    work = data.view(unsigned) if as_integers else data
    padded_dtype = np.int64 if as_integers else data.dtype
    # Rows (transposed when filtering down the columns), padded along their length.
    padded = _pad_symmetric(work if axis == 1 else work.T, half, 1, padded_dtype)
    flat = padded.ravel()
    if as_integers:
        # The median is one of the window's values: the same bits, back to the floats.
        filtered = scipy.ndimage.median_filter(flat, size=size, mode="reflect")
        inner = filtered.reshape(padded.shape)[:, half : half + d]
        return (inner if axis == 1 else inner.T).astype(unsigned, order="C").view(data.dtype)
    if data.dtype == np.float64:
        as_unsigned = flat.view(np.uint64)
        if as_unsigned.max() <= _POSITIVE_INFINITY_BITS[np.uint64]:
            # The same for float64, whose bits scipy takes as they are (read as int64:
            # non-negative doubles' bits are below 2**63).
            flat = scipy.ndimage.median_filter(
                as_unsigned.view(np.int64), size=size, mode="reflect"
            )
            flat = flat.view(np.float64)
        else:
            flat = scipy.ndimage.median_filter(flat, size=size, mode="reflect")
    else:
        flat = scipy.ndimage.median_filter(flat, size=size, mode="reflect")
    filtered = flat.reshape(padded.shape)[:, half : half + d]
    return np.ascontiguousarray(filtered if axis == 1 else filtered.T)


def _pad_symmetric(source: np.ndarray, half: int, axis: int, dtype) -> np.ndarray:
    """``source`` padded by ``half`` on both ends of ``axis`` with numpy's ``"symmetric"``
    mode (``d c b a | a b c d | d c b a``), as ``dtype``."""
    d = source.shape[axis]
    if d < half:
        widths = ((0, 0), (half, half)) if axis == 1 else ((half, half), (0, 0))
        return np.pad(source.astype(dtype), widths, mode="symmetric")
    # One copy: the data into the middle, then the edges mirrored from inside the array.
    shape = list(source.shape)
    shape[axis] += 2 * half
    padded = np.empty(shape, dtype=dtype)
    along = padded if axis == 1 else padded.T
    along[:, half : half + d] = source if axis == 1 else source.T
    along[:, :half] = along[:, half : 2 * half][:, ::-1]
    along[:, half + d :] = along[:, d : d + half][:, ::-1]
    return padded


def hpss_masks(
    magnitude: np.ndarray, *, kernel_size: int = 31, power: float = 2.0, margin: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Soft HPSS masks with librosa's semantics (``librosa.decompose.hpss(S, mask=True)``).

    Parameters
    ----------
    magnitude : np.ndarray [shape=(n_bins, n_frames)]
        Magnitude spectrogram (frequency down, time across).
    kernel_size : int
        Odd median kernel length, the same for both directions (librosa's default 31).
    power : float
        Soft-mask exponent, > 0 (2: Wiener-like).
    margin : float
        Separation margin >= 1; with 1 the masks sum to 1 and bins where both filtered
        spectrograms are zero get 0.5 in each.

    Returns
    -------
    mask_harmonic, mask_percussive : np.ndarray [shape=(n_bins, n_frames)]
        In [0, 1], dtype of ``magnitude`` (float32 or float64).
    """
    magnitude = np.asarray(magnitude)
    if magnitude.ndim != 2:
        raise ExtractError(f"magnitude must have shape (n_bins, n_frames), got {magnitude.shape}")
    if not power > 0:
        raise ExtractError(f"power must be > 0, got {power}")
    if margin < 1:
        raise ExtractError(f"margin must be >= 1, got {margin}")
    harmonic = median_filter_axis(magnitude, size=kernel_size, axis=1)
    percussive = median_filter_axis(magnitude, size=kernel_size, axis=0)
    return masks_from_medians(harmonic, percussive, power=power, margin=margin)


def masks_from_medians(
    harmonic: np.ndarray, percussive: np.ndarray, *, power: float = 2.0, margin: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """The soft masks of :func:`hpss_masks` from its two median-filtered spectrograms (the
    time-direction one, ``harmonic``, and the frequency-direction one, ``percussive``), for
    callers that filter a long spectrogram block by block.
    """
    if margin == 1:
        return _softmask_pair(harmonic, percussive, power=power)
    mask_harmonic = _softmask(harmonic, percussive * margin, power=power, split_zeros=False)
    mask_percussive = _softmask(percussive, harmonic * margin, power=power, split_zeros=False)
    return mask_harmonic, mask_percussive


def _ratios(x: np.ndarray, x_ref: np.ndarray, power: float):
    """``(x / z) ** power``, ``(x_ref / z) ** power`` with ``z = max(x, x_ref)`` (1 where z is
    below the dtype's tiny), and the mask of those "bad" bins."""
    dtype = x.dtype if x.dtype in (np.float32, np.float64) else np.float64
    z = np.maximum(x, x_ref).astype(dtype, copy=False)
    bad = z < np.finfo(dtype).tiny
    np.copyto(z, 1, where=bad)
    mask = np.divide(x, z, dtype=dtype)
    ref = np.divide(x_ref, z, out=z)
    if power == 2:
        mask *= mask
        ref *= ref
    else:
        np.power(mask, power, out=mask)
        np.power(ref, power, out=ref)
    return mask, ref, bad


def _softmask(x: np.ndarray, x_ref: np.ndarray, *, power: float, split_zeros: bool) -> np.ndarray:
    """``librosa.util.softmask``: ``x**p / (x**p + x_ref**p)``, computed scaled by the maximum;
    bins where both are zero get 0.5 with ``split_zeros``, else 0."""
    mask, ref, bad = _ratios(x, x_ref, power)
    ref += mask
    np.copyto(ref, 1, where=bad)
    mask /= ref
    np.copyto(mask, 0.5 if split_zeros else 0.0, where=bad)
    return mask


def _softmask_pair(harmonic: np.ndarray, percussive: np.ndarray, *, power: float):
    """Both soft masks for margin 1 (they share the scaling), split zeros as librosa does."""
    mask_h, mask_p, bad = _ratios(harmonic, percussive, power)
    total = mask_h + mask_p
    np.copyto(total, 1, where=bad)
    mask_h /= total
    mask_p /= total
    np.copyto(mask_h, 0.5, where=bad)
    np.copyto(mask_p, 0.5, where=bad)
    return mask_h, mask_p


def hp_ratio(
    magnitude: np.ndarray, mask_harmonic: np.ndarray, mask_percussive: np.ndarray
) -> np.ndarray:
    """Harmonic-percussive balance ``|H| / (|H| + |P| + eps)`` per bin (the paper's hp_ratio).

    ``H = mask_harmonic * magnitude`` and ``P = mask_percussive * magnitude``; with margin 1 the
    masks sum to 1, so this is the harmonic mask wherever the magnitude is well above
    ``eps = 1e-10`` and tends to 0 where the bin is digitally silent.

    Parameters
    ----------
    magnitude, mask_harmonic, mask_percussive : np.ndarray [shape=(n_bins, n_frames)]

    Returns
    -------
    hp : np.ndarray [shape=(n_bins, n_frames), dtype=float32]
        In [0, 1]: 1 is tonal (harmonic), 0 is percussive.
    """
    magnitude = np.asarray(magnitude, dtype=np.float32)
    harmonic = mask_harmonic * magnitude
    percussive = mask_percussive * magnitude
    denominator = harmonic + percussive
    denominator += np.float32(HP_EPSILON)
    harmonic /= denominator
    return np.clip(harmonic, 0.0, 1.0, out=harmonic).astype(np.float32, copy=False)
