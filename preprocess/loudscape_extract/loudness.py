"""Whole-track loudness metrics: BS.1770-4 integrated loudness, EBU Tech 3342 loudness range,
the maximum momentary and short-term loudness at any window position (EBU Tech 3341), sample
peak and 4x-oversampled true peak (BS.1770-4 Annex 2).

All functions take the original channels at the original sample rate.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.dsp import kaiser_lowpass, sos_filter, upsample_polyphase
from loudscape_extract.errors import ExtractError

__all__ = [
    "ABSOLUTE_GATE_LUFS",
    "MOMENTARY_S",
    "SHORT_TERM_S",
    "TRUE_PEAK_OVERSAMPLING",
    "WindowMaxima",
    "block_loudness",
    "channel_gains",
    "integrated_loudness",
    "k_weighting_sos",
    "loudness_from_energy",
    "loudness_metrics",
    "loudness_range",
    "momentary_per_frame",
    "interpolator_taps",
    "sample_peak_dbfs",
    "segment_energy",
    "segment_energy_and_maxima",
    "short_term_loudness",
    "valid_interpolated_samples",
    "true_peak_dbtp",
    "weighted_power",
    "window_maxima",
]

ABSOLUTE_GATE_LUFS = -70.0
TRUE_PEAK_OVERSAMPLING = 4
#: Window lengths of momentary and short-term loudness, seconds (BS.1770-4, EBU Tech 3341).
MOMENTARY_S = 0.4
SHORT_TERM_S = 3.0
#: Samples of K-weighted power fed to WindowMaxima at a time by the whole-track functions.
_MAXIMA_BLOCK = 1 << 21
_SEGMENT_S = 0.1  # blocks are whole numbers of 100 ms segments (75 % overlap, 10 Hz rate)
_TRUE_PEAK_TAPS_PER_PHASE = 24
_TRUE_PEAK_BLOCK = 2048
_TRUE_PEAK_BATCH = 256


def _as_channels(samples: np.ndarray) -> np.ndarray:
    samples = np.asarray(samples)
    if samples.ndim == 1:
        samples = samples[:, None]
    if samples.ndim != 2 or samples.shape[1] == 0:
        raise ExtractError(f"samples must have shape (n_samples, n_channels), got {samples.shape}")
    return samples


def _check_rate(sample_rate: float) -> None:
    if not sample_rate >= 8000:
        raise ExtractError(f"sample_rate must be >= 8000 Hz for K-weighting, got {sample_rate}")


def k_weighting_sos(*, sample_rate: float) -> np.ndarray:
    """The BS.1770-4 K-weighting filter (shelf + high-pass) at any sample rate.

    The two biquads are derived from their analogue prototypes (the parameters libebur128 and
    pyloudnorm's "DeMan" filter use), which reproduce the coefficients BS.1770-4 tabulates for
    48 kHz to better than 1e-8.

    Parameters
    ----------
    sample_rate : float
        In Hz, >= 8000.

    Returns
    -------
    sos : np.ndarray [shape=(2, 6)]
        Second-order sections for ``scipy.signal.sosfilt``.
    """
    _check_rate(sample_rate)
    # Stage 1: high shelf, +4 dB above ~1.5 kHz (head acoustics).
    f0, gain_db, q = 1681.974450955533, 3.999843853973347, 0.7071752369554196
    k = math.tan(math.pi * f0 / sample_rate)
    vh = 10.0 ** (gain_db / 20.0)
    vb = vh**0.4996667741545416
    a0 = 1.0 + k / q + k * k
    shelf = [
        (vh + vb * k / q + k * k) / a0,
        2.0 * (k * k - vh) / a0,
        (vh - vb * k / q + k * k) / a0,
        1.0,
        2.0 * (k * k - 1.0) / a0,
        (1.0 - k / q + k * k) / a0,
    ]
    # Stage 2: RLB high-pass at ~38 Hz.
    f0, q = 38.13547087602444, 0.5003270373238773
    k = math.tan(math.pi * f0 / sample_rate)
    a0 = 1.0 + k / q + k * k
    highpass = [1.0, -2.0, 1.0, 1.0, 2.0 * (k * k - 1.0) / a0, (1.0 - k / q + k * k) / a0]
    return np.array([shelf, highpass], dtype=np.float64)


def channel_gains(n_channels: int) -> np.ndarray:
    """BS.1770-4 channel weights G_i.

    1.0 for every channel, except: 5 channels (L, R, C, Ls, Rs) weight the surrounds 1.41;
    6 channels are taken as 5.1 in WAV order (L, R, C, LFE, Ls, Rs): LFE 0, surrounds 1.41.

    Returns
    -------
    gains : np.ndarray [shape=(n_channels,)]
    """
    gains = np.ones(n_channels)
    if n_channels == 5:
        gains[3:5] = 1.41
    elif n_channels == 6:
        gains[3] = 0.0
        gains[4:6] = 1.41
    return gains


def segment_energy(samples: np.ndarray, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Channel-weighted sum of squared K-weighted samples per complete 100 ms segment.

    Returns ``(energy [n_segments], boundaries [n_segments + 1])`` with boundaries in samples.
    """
    samples = _as_channels(samples)
    boundaries = _segment_boundaries(samples.shape[0], sample_rate)
    if boundaries.shape[0] == 1:
        return np.zeros(0), boundaries
    return _segment_sums(*_k_weighted(samples, sample_rate), boundaries), boundaries


def _segment_boundaries(n_samples: int, sample_rate: float) -> np.ndarray:
    """The sample boundaries of the complete 100 ms segments (one more than segments)."""
    n_segments = int(math.floor(n_samples / (_SEGMENT_S * sample_rate) + 1e-9))
    boundaries = np.round(np.arange(n_segments + 1) * _SEGMENT_S * sample_rate).astype(np.int64)
    return np.minimum(boundaries, n_samples)


def _k_weighted(samples: np.ndarray, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """The K-weighted channels that have a weight (``[n_used, n_samples]``, float32: relative
    error ~1e-7 of the signal, far below any gate) and those channels' weights."""
    gains = channel_gains(samples.shape[1])
    used = np.flatnonzero(gains)
    sos = k_weighting_sos(sample_rate=sample_rate)
    return sos_filter(sos, samples[:, used].T, dtype=np.float32), gains[used]


def _segment_sums(filtered: np.ndarray, gains: np.ndarray, boundaries: np.ndarray) -> np.ndarray:
    """Channel-weighted sums of squares of ``filtered`` per segment between ``boundaries``."""
    energy = np.zeros(boundaries.shape[0] - 1)
    if energy.shape[0] == 0:
        return energy
    for row, gain in enumerate(gains):
        squared = np.square(filtered[row, : boundaries[-1]], dtype=np.float64)
        energy += gain * np.add.reduceat(squared, boundaries[:-1])
    return energy


def _blocks(energy: np.ndarray, boundaries: np.ndarray, n_segments: int) -> np.ndarray:
    """Loudness (LUFS) of every block of ``n_segments`` consecutive segments (step: one)."""
    if energy.shape[0] < n_segments:
        return np.empty(0)
    sums = sliding_window_view(energy, n_segments).sum(axis=-1)
    lengths = boundaries[n_segments:] - boundaries[:-n_segments]
    with np.errstate(divide="ignore"):
        return -0.691 + 10.0 * np.log10(sums / lengths)


def block_loudness(samples: np.ndarray, *, sample_rate: float) -> np.ndarray:
    """Momentary loudness of the 400 ms gating blocks (75 % overlap) of BS.1770-4.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]
    sample_rate : float

    Returns
    -------
    loudness : np.ndarray [shape=(n_blocks,)]
        LUFS of each complete block (``-inf`` for digital silence).
    """
    energy, boundaries = segment_energy(samples, sample_rate)
    return _blocks(energy, boundaries, 4)


def short_term_loudness(samples: np.ndarray, *, sample_rate: float) -> np.ndarray:
    """Short-term loudness (3 s blocks) every 100 ms, as EBU Tech 3342 uses.

    Returns
    -------
    loudness : np.ndarray [shape=(n_blocks,)]
        LUFS of each complete 3 s block.
    """
    energy, boundaries = segment_energy(samples, sample_rate)
    return _blocks(energy, boundaries, 30)


def _gated_integrated(energy: np.ndarray, boundaries: np.ndarray) -> float | None:
    if energy.shape[0] < 4:
        return None
    sums = sliding_window_view(energy, 4).sum(axis=-1)
    mean_squares = sums / (boundaries[4:] - boundaries[:-4])
    with np.errstate(divide="ignore"):
        loudness = -0.691 + 10.0 * np.log10(mean_squares)
    above_absolute = loudness > ABSOLUTE_GATE_LUFS
    if not above_absolute.any():
        return None
    relative_gate = -0.691 + 10.0 * np.log10(mean_squares[above_absolute].mean()) - 10.0
    gated = above_absolute & (loudness > relative_gate)
    return float(-0.691 + 10.0 * np.log10(mean_squares[gated].mean()))


def integrated_loudness(samples: np.ndarray, *, sample_rate: float) -> float | None:
    """Integrated loudness, ITU-R BS.1770-4 (K-weighting, 400 ms blocks, -70 LUFS absolute
    and -10 LU relative gates).

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]
        Full scale is amplitude 1.
    sample_rate : float

    Returns
    -------
    lufs : float or None
        None when there is no complete 400 ms block or every block is below -70 LUFS.
    """
    energy, boundaries = segment_energy(samples, sample_rate)
    return _gated_integrated(energy, boundaries)


def _range_from_short_term(short_term: np.ndarray) -> float | None:
    above_absolute = short_term[short_term > ABSOLUTE_GATE_LUFS]
    if above_absolute.size == 0:
        return None
    integrated = 10.0 * np.log10(np.mean(10.0 ** (above_absolute / 10.0)))
    gated = above_absolute[above_absolute > integrated - 20.0]
    low, high = np.percentile(gated, [10.0, 95.0])
    return float(high - low)


def loudness_range(samples: np.ndarray, *, sample_rate: float) -> float | None:
    """Loudness range LRA, EBU Tech 3342: short-term loudness (3 s blocks at 10 Hz), gated at
    -70 LUFS absolute and 20 LU below their power mean, spread from the 10th to the 95th
    percentile.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]
    sample_rate : float

    Returns
    -------
    lra : float or None
        In LU; None when the audio is shorter than 3 s or every block is below -70 LUFS.
    """
    return _range_from_short_term(short_term_loudness(samples, sample_rate=sample_rate))


def sample_peak_dbfs(samples: np.ndarray) -> float | None:
    """Largest absolute sample value in dBFS (``20 log10 max|x|``); None for digital silence."""
    peak = float(np.max(np.abs(samples))) if np.size(samples) else 0.0
    return 20.0 * math.log10(peak) if peak > 0 else None


def interpolator_taps(oversampling: int) -> np.ndarray:
    """The true-peak interpolator: ``oversampling * 24 + 1`` taps, gain ``oversampling``."""
    numtaps = oversampling * _TRUE_PEAK_TAPS_PER_PHASE + 1
    return kaiser_lowpass(numtaps, 1.0 / oversampling, beta=8.0) * oversampling


_interpolator = interpolator_taps


def valid_interpolated_samples(n_samples: int, *, oversampling: int) -> int:
    """How many leading samples have interpolated values whose window lies inside the signal.

    The interpolator needs ``half`` samples after the one it interpolates around; past the
    last of them, zero padding would invent a step to zero and an overshoot at an abrupt end.
    libebur128 never evaluates those positions (its filter is not flushed), and neither do we.
    """
    per_phase = -(-(oversampling * _TRUE_PEAK_TAPS_PER_PHASE + 1) // oversampling)
    half = (per_phase - 1) // 2
    return max(0, n_samples - (per_phase - 1 - half))


def true_peak_dbtp(
    samples: np.ndarray, *, sample_rate: float, oversampling: int = TRUE_PEAK_OVERSAMPLING
) -> float | None:
    """True peak in dBTP: the largest absolute value of the signal oversampled 4x
    (BS.1770-4 Annex 2), over every channel.

    The interpolator is a 97-tap Kaiser-windowed (beta 8) low-pass at the original Nyquist
    frequency, 24 taps per phase (Annex 2's example filter has 12), flat within 0.01 dB up to
    0.8 of Nyquist. Floating point needs no 12 dB headroom attenuation. To save time the
    signal is cut into blocks, and a block is interpolated only if its largest sample (and its
    neighbours') times the interpolator's largest per-phase absolute gain could still beat the
    largest value found so far; skipped blocks cannot hold the maximum, so the result is exact.
    Near the end only positions whose interpolation window lies inside the signal count (see
    :func:`valid_interpolated_samples`, libebur128's behaviour), and the true peak is never
    below the sample peak, so a file that stops abruptly at full scale reads 0.0 dBTP.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]
    sample_rate : float
        In Hz; the interpolator is relative to the sample rate, so this is only checked.
    oversampling : int
        Oversampling factor (4).

    Returns
    -------
    dbtp : float or None
        None for digital silence.
    """
    samples = _as_channels(samples)
    _check_rate(sample_rate)
    if oversampling < 1:
        raise ExtractError(f"oversampling must be >= 1, got {oversampling}")
    taps = interpolator_taps(oversampling).astype(np.float32)
    bound_gain = max(float(np.abs(taps[p::oversampling]).sum()) for p in range(oversampling))
    half = _TRUE_PEAK_TAPS_PER_PHASE // 2
    margin = _TRUE_PEAK_TAPS_PER_PHASE
    block = _TRUE_PEAK_BLOCK
    n_samples = samples.shape[0]
    n_blocks = -(-n_samples // block)
    first = (margin - half) * oversampling
    valid = valid_interpolated_samples(n_samples, oversampling=oversampling)
    best = 0.0
    for channel in range(samples.shape[1]):
        x = np.zeros(n_blocks * block + 2 * margin, dtype=np.float32)
        x[margin : margin + n_samples] = samples[:, channel]
        block_max = np.abs(x[margin : margin + n_blocks * block]).reshape(n_blocks, block)
        block_max = block_max.max(axis=1)
        bound = block_max.copy()
        bound[1:] = np.maximum(bound[1:], block_max[:-1])
        bound[:-1] = np.maximum(bound[:-1], block_max[1:])
        bound *= bound_gain
        order = np.argsort(-bound, kind="stable")
        position = 0
        while position < n_blocks and bound[order[position]] >= best:
            batch = order[position : position + _TRUE_PEAK_BATCH]
            batch = batch[bound[batch] >= best]
            position += _TRUE_PEAK_BATCH
            starts = batch[:, None] * block + np.arange(block + 2 * margin)[None, :]
            upsampled = upsample_polyphase(x[starts], taps, factor=oversampling)
            upsampled = np.abs(upsampled[:, first : first + block * oversampling])
            # Sample s of a block is valid while s + block start < `valid` (no invented end).
            sample = (
                batch[:, None] * block + np.arange(block * oversampling)[None, :] // oversampling
            )
            upsampled[sample >= valid] = 0.0
            best = max(best, float(upsampled.max()))
    best = max(best, float(np.abs(samples).max()) if n_samples else 0.0)
    return 20.0 * math.log10(best) if best > 0 else None


def weighted_power(filtered: np.ndarray, gains: np.ndarray) -> np.ndarray:
    """Channel-weighted sum of squares per sample, ``sum_i G_i y_i[n]^2`` (float64).

    Parameters
    ----------
    filtered : np.ndarray [shape=(n_used, n_samples)]
        K-weighted channels with a non-zero weight, in the order of ``gains``.
    gains : np.ndarray [shape=(n_used,)]

    Returns
    -------
    power : np.ndarray [shape=(n_samples,)]
    """
    power = np.zeros(filtered.shape[-1])
    for row, gain in enumerate(gains):
        power += gain * np.square(filtered[row], dtype=np.float64)
    return power


class WindowMaxima:
    """The loudest momentary (400 ms) and short-term (3 s) window at any sample position.

    A meter that reads the windows every 100 ms misses a short burst's maximum by up to
    0.5 LU (EBU Tech 3341 case 13: a 400 ms tone after ``i * 20`` ms of silence); here every
    window of ``round(0.4 fs)`` (and ``round(3 fs)``) consecutive samples counts, one sample
    apart, from a running sum of :func:`weighted_power`. Fed block by block (any block
    sizes), it keeps only the last window's samples; the result does not depend on the blocks.

    Parameters
    ----------
    sample_rate : float

    Examples
    --------
    >>> import numpy as np
    >>> rate = 8000
    >>> power = np.zeros(rate * 4)
    >>> power[12345 : 12345 + 3200] = 1e-3  # 400 ms at -30.7 LUFS, off the 100 ms grid
    >>> maxima = WindowMaxima(sample_rate=rate)
    >>> for block in np.array_split(power, 7):
    ...     maxima.feed(block)
    >>> result = maxima.result()
    >>> round(result["max_momentary_lufs"], 3), result["max_momentary_s"]
    (-30.691, 1.943)
    """

    def __init__(self, *, sample_rate: float) -> None:
        _check_rate(sample_rate)
        self.sample_rate = float(sample_rate)
        self.lengths = (
            int(round(MOMENTARY_S * sample_rate)),
            int(round(SHORT_TERM_S * sample_rate)),
        )
        self._tail = np.zeros(0)
        self._tail_start = 0
        self._best = [-math.inf, -math.inf]
        self._best_start = [-1, -1]

    def feed(self, power: np.ndarray) -> None:
        """Add the next samples of :func:`weighted_power` (shape ``(n,)``)."""
        x = np.concatenate([self._tail, np.asarray(power, dtype=np.float64)])
        offset = self._tail_start
        # Cumulative sums start afresh in every block: their rounding stays that of one window.
        cumulative = np.concatenate([[0.0], np.cumsum(x)])
        for which, length in enumerate(self.lengths):
            if x.shape[0] < length:
                continue
            sums = cumulative[length:] - cumulative[:-length]
            first = int(np.argmax(sums))
            if sums[first] > self._best[which]:
                self._best[which] = float(sums[first])
                self._best_start[which] = offset + first
        keep = min(x.shape[0], max(self.lengths) - 1)
        self._tail = x[x.shape[0] - keep :].copy()
        self._tail_start = offset + x.shape[0] - keep

    def result(self) -> dict[str, float | None]:
        """``max_momentary_lufs``, ``max_momentary_s``, ``max_short_term_lufs``,
        ``max_short_term_s``: the largest loudness and the time an EBU Mode meter shows it
        (the end of the window, seconds from the start; the first such window where several
        are equal). None where the signal is shorter than the window or the window is silent."""
        out: dict[str, float | None] = {}
        for which, name in enumerate(("momentary", "short_term")):
            best, length = self._best[which], self.lengths[which]
            lufs = -0.691 + 10.0 * math.log10(best / length) if best > 0 else None
            end = (self._best_start[which] + length) / self.sample_rate
            out[f"max_{name}_lufs"] = lufs
            out[f"max_{name}_s"] = round(end, 3) if lufs is not None else None
        return out


def window_maxima(samples: np.ndarray, *, sample_rate: float) -> dict[str, float | None]:
    """Maximum momentary and short-term loudness at any window position (see
    :class:`WindowMaxima`), with the times an EBU Mode meter shows them.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]
    sample_rate : float

    Returns
    -------
    maxima : dict
        ``max_momentary_lufs``, ``max_momentary_s``, ``max_short_term_lufs``,
        ``max_short_term_s`` (None where not measurable).
    """
    samples = _as_channels(samples)
    _check_rate(sample_rate)
    return _maxima(*_k_weighted(samples, sample_rate), sample_rate)


def _maxima(filtered: np.ndarray, gains: np.ndarray, sample_rate: float) -> dict:
    """:class:`WindowMaxima` of K-weighted channels, fed :data:`_MAXIMA_BLOCK` samples at a
    time: its running sums then take a few blocks' memory, not eight bytes a sample three
    times over (a 20-minute track's whole-track sums took 1.2 GB)."""
    maxima = WindowMaxima(sample_rate=sample_rate)
    for start in range(0, filtered.shape[-1], _MAXIMA_BLOCK):
        maxima.feed(weighted_power(filtered[:, start : start + _MAXIMA_BLOCK], gains))
    return maxima.result()


def segment_energy_and_maxima(
    samples: np.ndarray, *, sample_rate: float
) -> tuple[tuple[np.ndarray, np.ndarray], dict[str, float | None]]:
    """:func:`segment_energy` and :func:`window_maxima` of the same samples from one
    K-weighting pass (the filter is most of either's cost): ``((energy, boundaries),
    maxima)``, each equal to what those functions give.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(4 * 8000) / 8000
    >>> tone = 0.1 * np.sin(2 * np.pi * 1000 * t)
    >>> (energy, boundaries), maxima = segment_energy_and_maxima(tone, sample_rate=8000)
    >>> np.array_equal(energy, segment_energy(tone, 8000)[0])
    True
    >>> maxima == window_maxima(tone, sample_rate=8000)
    True
    """
    samples = _as_channels(samples)
    _check_rate(sample_rate)
    boundaries = _segment_boundaries(samples.shape[0], sample_rate)
    filtered, gains = _k_weighted(samples, sample_rate)
    energy = _segment_sums(filtered, gains, boundaries)
    return (energy, boundaries), _maxima(filtered, gains, sample_rate)


def momentary_per_frame(
    times_s: np.ndarray, energy: np.ndarray, boundaries: np.ndarray
) -> np.ndarray:
    """BS.1770 momentary loudness (400 ms, four 100 ms segments) centred on each time.

    The block whose centre is nearest ``t`` starts at segment ``round((t - 0.2 s) / 0.1 s)``,
    clamped to the track, so its centre is within 50 ms of ``t`` (away from the ends); it is
    the value libebur128 reports as momentary loudness once the block's last segment is fed.

    Parameters
    ----------
    times_s : np.ndarray [shape=(n_times,)]
    energy, boundaries : np.ndarray
        :func:`segment_energy`'s output.

    Returns
    -------
    loudness : np.ndarray [shape=(n_times,)]
        LUFS; NaN when the track is shorter than one block or the block is digital silence.
    """
    blocks = _blocks(np.asarray(energy), np.asarray(boundaries), 4)
    times_s = np.asarray(times_s, dtype=np.float64)
    if blocks.shape[0] == 0:
        return np.full(times_s.shape, np.nan)
    index = np.clip(np.round((times_s - 0.2) / _SEGMENT_S).astype(np.int64), 0, blocks.shape[0] - 1)
    values = blocks[index]
    return np.where(np.isfinite(values), values, np.nan)


def loudness_from_energy(
    energy: np.ndarray, boundaries: np.ndarray
) -> tuple[float | None, float | None]:
    """Integrated loudness and LRA from :func:`segment_energy`'s output (one K-weighting)."""
    return _gated_integrated(energy, boundaries), _range_from_short_term(
        _blocks(energy, boundaries, 30)
    )


def loudness_metrics(samples: np.ndarray, *, sample_rate: float) -> dict[str, float | None]:
    """Integrated loudness, loudness range, sample peak, true peak and PLR of a track.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels)]
        Original channels.
    sample_rate : float

    Returns
    -------
    metrics : dict
        ``integrated_lufs``, ``lra_lu``, ``sample_peak_dbfs``, ``true_peak_dbtp``, ``plr_db``
        (true peak minus integrated loudness) and :func:`window_maxima`'s four; None where not
        measurable.
    """
    samples = _as_channels(samples)
    _check_rate(sample_rate)
    energy, boundaries = segment_energy(samples, sample_rate)
    integrated = _gated_integrated(energy, boundaries)
    lra = _range_from_short_term(_blocks(energy, boundaries, 30))
    true_peak = true_peak_dbtp(samples, sample_rate=sample_rate)
    plr = None if integrated is None or true_peak is None else true_peak - integrated
    return {
        "integrated_lufs": integrated,
        "lra_lu": lra,
        "sample_peak_dbfs": sample_peak_dbfs(samples),
        "true_peak_dbtp": true_peak,
        "plr_db": plr,
        **window_maxima(samples, sample_rate=sample_rate),
    }
