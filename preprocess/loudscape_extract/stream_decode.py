"""The two decoding passes of the streamed pipeline (:mod:`loudscape_extract.stream`).

1. **decode** (:func:`decode_pass`): the file block by block; keeps the decoded mono mix
   (float32, 635 MB for 60 minutes at 44.1 kHz) and each channel's sum (the DC offset), and
   the decoded blocks themselves while they total at most :data:`KEEP_DECODED_VALUES` values
   (about 12 minutes of 44.1 kHz stereo), so that a song of ordinary length is decoded once;
2. **signal** (:func:`signal_pass`): the kept blocks, or the file decoded again, block by
   block: DC removal, the
   optional high-pass and the K-weighting as FFT convolutions carrying their last ``taps - 1``
   input samples from block to block, the true-peak interpolator likewise, and per 100 ms
   segment, 3 s DR block and STFT frame the sums and peaks the metrics need.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.audio import (
    AudioInfo,
    BlockReport,
    audio_info,
    check_analysable,
    check_decoded,
    mix_rows_to_mono,
    read_blocks,
)
from loudscape_extract.dsp import fft_convolve, sos_impulse_response
from loudscape_extract.dynamics import (
    Dynamics,
    dr_block_length,
    dynamics_from_segments,
    highpass_sos,
)
from loudscape_extract.errors import ExtractError
from loudscape_extract.fft import irfft, rfft
from loudscape_extract.loudness import (
    TRUE_PEAK_OVERSAMPLING,
    WindowMaxima,
    channel_gains,
    interpolator_taps,
    k_weighting_sos,
    weighted_power,
)
from loudscape_extract.notices import ClipRuns, cancel_notice, clip_notice
from loudscape_extract.spectrogram import frame_count

__all__ = [
    "DEFAULT_BLOCK_SAMPLES",
    "KEEP_DECODED_VALUES",
    "DecodedMono",
    "SignalStats",
    "decode_pass",
    "decode_track",
    "signal_pass",
]

#: Samples decoded at a time (about 24 s at 44.1 kHz).
DEFAULT_BLOCK_SAMPLES = 1 << 20
#: The decoded blocks are kept for the signal pass up to this many samples times channels
#: (float32: 256 MiB); a longer file is decoded a second time instead.
KEEP_DECODED_VALUES = 1 << 26
_FRAME_CHUNK = 1024
_SHORT_PEAK = 1 << 15


@functools.lru_cache(maxsize=16)
def _impulse_response(flat_sos: tuple) -> np.ndarray:
    return sos_impulse_response(np.array(flat_sos).reshape(-1, 6))


@dataclass(frozen=True)
class DecodedMono:
    """What the first decoding pass keeps.

    Attributes
    ----------
    info : AudioInfo
    mono : np.ndarray [shape=(n_samples,), dtype=float32]
        The decoded mono mix (:func:`mix_to_mono` of the decoded channels).
    dc : np.ndarray [shape=(n_channels,)]
        Each channel's mean.
    sample_peak : float
        Largest absolute decoded sample.
    any_nonzero : bool
        Whether any decoded sample is non-zero.
    warning : str
        Non-empty when the file is truncated or corrupt (:attr:`Audio.warning`).
    signal : tuple of dict
        Warnings about the signal found while decoding (:func:`notices.cancel_notice`,
        :func:`notices.clip_notice`).
    blocks : tuple of (int, np.ndarray) or None
        The decoded blocks as :func:`read_blocks` gave them (start, samples), when the file is
        short enough to keep them (:data:`KEEP_DECODED_VALUES`); :func:`signal_pass` reads
        them instead of decoding again.
    block : int
        The block length they were read with.
    """

    info: AudioInfo
    mono: np.ndarray
    dc: np.ndarray
    sample_peak: float
    any_nonzero: bool
    warning: str = ""
    signal: tuple = ()
    blocks: tuple | None = field(default=None, repr=False, compare=False)
    block: int = DEFAULT_BLOCK_SAMPLES

    @property
    def n_samples(self) -> int:
        return int(self.mono.shape[0])


def decode_pass(
    info: AudioInfo,
    *,
    block: int = DEFAULT_BLOCK_SAMPLES,
    strict: bool = False,
    keep_values: int = KEEP_DECODED_VALUES,
) -> DecodedMono:
    """Decode once: the mono mix, channel means and the sample peak (see the module docs).

    A truncated or corrupt file is decoded as far as it goes, with a warning, as by
    :func:`decode_audio` (``strict``: an :class:`ExtractError`). The decoded blocks are kept
    while they total at most ``keep_values`` samples times channels.
    """
    report = BlockReport()
    capacity = max(info.n_samples, 1)
    mono = np.empty(capacity, dtype=np.float32)
    sums = np.zeros(info.n_channels)
    peak = 0.0
    any_nonzero = False
    n = 0
    channel_squares = mono_squares = 0.0
    clips = ClipRuns(info.n_channels)
    kept: list | None = [] if info.n_samples * info.n_channels <= keep_values else None
    for start, samples in read_blocks(info, block=block, report=report):
        count = samples.shape[0]
        if start + count > mono.shape[0]:  # the header understated the length
            grown = np.empty(max(2 * mono.shape[0], start + count), dtype=np.float32)
            grown[:start] = mono[:start]
            mono = grown
        # The channels as contiguous rows: each channel's sum on its own (pairwise): numpy's
        # sum over axis 0 of a narrow array casts and adds row by row, ten times slower; the
        # mono mix from the rows, the same sums as from the interleaved columns, faster.
        channels = np.ascontiguousarray(samples.T)
        sums += channels.sum(axis=1, dtype=np.float64)
        block_mono = mix_rows_to_mono(channels)
        mono[start : start + count] = block_mono
        # The mono mix's energy (for the channels-cancel notice only, compared with a
        # threshold and printed to 0.1 dB): float64 sums of squares, as the channels' below,
        # without the float64 copy that np.dot needed (a third of the decoding pass's own time).
        mono_squares += float(np.einsum("i,i->", block_mono, block_mono, dtype=np.float64))
        channel_squares += float(np.einsum("ij,ij->", samples, samples, dtype=np.float64))
        block_peak = max(float(samples.max()), -float(samples.min()))
        clips.feed(start, samples, peak=block_peak)
        peak = max(peak, block_peak)
        if kept is not None:
            kept.append((start, samples))
            if (start + count) * info.n_channels > keep_values:  # longer than the header said
                kept = None
        any_nonzero = any_nonzero or block_peak > 0
        n = start + count
    warning = check_decoded(info, decoded=n, report=report, strict=strict)
    signal = [
        cancel_notice(mono_squares, channel_squares / info.n_channels)
        if info.n_channels > 1
        else None,
        clip_notice(clips.runs, clips.samples, clips.first_s(info.sample_rate)),
    ]
    return DecodedMono(
        info=info,
        mono=mono[:n],
        dc=sums / n,
        sample_peak=peak,
        any_nonzero=any_nonzero,
        warning=warning,
        signal=tuple(item for item in signal if item),
        blocks=None if kept is None else tuple(kept),
        block=block,
    )


def _reduce_into(out, values, start, boundaries, ufunc) -> None:
    """Combine per-sample ``values`` (absolute samples ``[start, start + n)``, last axis) into
    ``out[..., i]``, the interval ``[boundaries[i], boundaries[i + 1])``, with ``ufunc``."""
    end = min(start + values.shape[-1], int(boundaries[-1]))
    if end <= start:
        return
    first = int(np.searchsorted(boundaries, start, side="right")) - 1
    last = int(np.searchsorted(boundaries, end, side="left"))
    cuts = np.maximum(boundaries[first:last], start) - start
    part = ufunc.reduceat(values[..., : end - start], cuts.astype(np.int64), axis=-1)
    out[..., first:last] = ufunc(out[..., first:last], part)


class _StreamFir:
    """Causal FIR filter from rest along the last axis, fed consecutive blocks."""

    def __init__(self, taps: np.ndarray, rows: int, dtype) -> None:
        self.taps = taps
        self.dtype = dtype
        self.carry = np.zeros((rows, taps.shape[0] - 1), dtype=dtype)

    def __call__(self, block: np.ndarray) -> np.ndarray:
        keep = self.carry.shape[1]
        x = np.concatenate([self.carry, block.astype(self.dtype, copy=False)], axis=1)
        y = fft_convolve(x, self.taps, dtype=self.dtype)[:, keep:]
        if keep:
            self.carry = x[:, x.shape[1] - keep :].copy()
        return y


def _phase_outputs(x: np.ndarray, phases: list[np.ndarray], count: int):
    """The causal convolutions of ``x`` with each of ``phases`` (equal lengths ``m``) at
    outputs ``m - 1 .. m - 2 + count`` (the ones whose window lies inside ``x``), by
    overlap-save, one forward transform of each segment shared by all filters, float32.

    Yields ``(phase index, first, y)`` with ``y`` of shape (rows, length) the outputs
    ``first .. first + length - 1`` of that phase, batch after batch, so the caller reduces
    them while they are in the cache instead of keeping whole-block outputs. The phases are
    short (25 taps), so the segments are short too (4,096 samples, transformed 128 at a
    time): transforms that fit the cache cost well under half as much per sample as the
    65,536-sample ones of :func:`fft_convolve`."""
    rows, n = x.shape
    m = phases[0].shape[0]
    size = 1 << max(12, math.ceil(math.log2(4 * m)))
    step = size - m + 1
    n_blocks = -(-count // step)
    spectra = [rfft(np.asarray(h, dtype=np.float32), size) for h in phases]
    padded = np.zeros((rows, n_blocks * step + m - 1), dtype=np.float32)
    padded[:, : min(n, padded.shape[1])] = x[:, : padded.shape[1]]
    batch = max(1, (1 << 19) // size)
    item = padded.itemsize
    for first in range(0, n_blocks, batch):
        blocks = min(batch, n_blocks - first)
        # (rows, blocks, size) windows of padded, step apart (a view, no gather)
        segments = np.lib.stride_tricks.as_strided(
            padded[:, first * step :],
            shape=(rows, blocks, size),
            strides=(padded.strides[0], step * item, item),
            writeable=False,
        )
        spectrum = rfft(segments, axis=-1)
        begin = first * step
        length = min(blocks * step, count - begin)
        for index, h_spectrum in enumerate(spectra):
            y = irfft(spectrum * h_spectrum, size, axis=-1)[:, :, m - 1 :]
            yield index, begin, y.reshape(rows, -1)[:, :length]


class _StreamTruePeak:
    """The 4x-oversampled absolute maximum over channels around each sample, as
    :func:`segment_true_peak` computes it (the same interpolator in float32: FFT convolutions,
    or shifted sums for short blocks), fed consecutive blocks;
    only positions whose interpolation window lies inside the signal are produced.

    With ``offsets`` it also gives the peak of ``signal + offsets`` (the decoded signal, when
    the fed one is its DC-free version) from the same interpolation: the interpolator is
    linear, so each phase's output moves by ``offset * sum(phase taps)`` wherever its window
    lies inside the signal (near the start, by the partial sum over the samples already
    there). One oversampled pass serves both peaks."""

    def __init__(
        self,
        rows: int,
        oversampling: int = TRUE_PEAK_OVERSAMPLING,
        offsets=None,
        *,
        offset_maximum_only: bool = False,
    ) -> None:
        # offset_maximum_only: :meth:`feed` gives the offset signal's peak over the whole block
        # (shape (1,)) instead of at each position, from each phase's extremes.
        self.offset_maximum_only = offset_maximum_only
        self.taps = interpolator_taps(oversampling).astype(np.float32)
        self.factor = oversampling
        self.per_phase = -(-self.taps.shape[0] // oversampling)
        self.half = (self.per_phase - 1) // 2
        padded = np.zeros(self.per_phase * oversampling)
        padded[: self.taps.shape[0]] = self.taps
        self.phases = [padded[p::oversampling] for p in range(oversampling)]
        # A phase whose taps are all zero but one (to rounding: the windowed sinc's zeros fall
        # on phase 0, whose other taps are below 1e-16) is a scaled copy of the input:
        # (tap index, gain), computed directly instead of by a convolution.
        self.copies = {}
        for phase, h in enumerate(self.phases):
            main = int(np.argmax(np.abs(h)))
            if np.abs(np.delete(h, main)).sum() <= 1e-12 * abs(h[main]):
                self.copies[phase] = (main, np.float32(h[main]))
        self.convolved = [p for p in range(oversampling) if p not in self.copies]
        self.buffer = np.zeros((rows, self.half), dtype=np.float32)
        self.buffer_start = -self.half
        self.offsets = None if offsets is None else np.asarray(offsets, np.float32)[:, None]

    def _offset_response(self, phase: int, count: int) -> np.ndarray:
        """``sum_k h_p[k]`` over the window samples inside the signal, per output (1, count)."""
        h = self.taps[phase :: self.factor].astype(np.float32)
        p = self.per_phase
        # output j reads samples j - half .. (relative to buffer_start); tap k reads x[j+p-1-k]
        j = np.arange(count)
        first_inside = -self.buffer_start  # x index of sample 0
        k_max = np.minimum(p - 1, j + p - 1 - first_inside)
        partial = np.concatenate([[0.0], np.cumsum(h, dtype=np.float64)]).astype(np.float32)
        return partial[np.clip(k_max + 1, 0, h.shape[0])][None, :]

    def feed(self, block: np.ndarray) -> tuple[int, np.ndarray, np.ndarray | None]:
        """``(s0, peak, offset_peak)``: the interpolated peak of samples ``s0 .. s0 +
        len(peak) - 1``, and that of the signal plus the offsets (None without them; with
        ``offset_maximum_only`` its largest value alone, shape (1,), or (0,) when no position
        was produced).

        The block's maximum of ``|y + c|`` over a phase's outputs ``y`` with a constant ``c``
        per channel is ``max(|max(y) + c|, |min(y) + c|)``, bit for bit: float rounding is
        monotone, so the extremes of ``y + c`` are those of ``y`` plus ``c``, rounded the same.
        """
        x = np.concatenate([self.buffer, block.astype(np.float32, copy=False)], axis=1)
        p = self.per_phase
        s0 = self.buffer_start + self.half
        count = x.shape[1] - (p - 1)
        peak = np.zeros(max(count, 0), dtype=np.float32)
        offset_peak = None if self.offsets is None else np.zeros_like(peak)
        if offset_peak is not None and self.offset_maximum_only:
            offset_peak = np.zeros(1 if count > 0 else 0, dtype=np.float32)
        if count > 0:
            if count < _SHORT_PEAK:
                # Short blocks (short songs): the phases as shifted sums, cheaper than FFTs.
                def outputs():
                    for phase in range(self.factor):
                        y = np.zeros((x.shape[0], count), dtype=np.float32)
                        for k, tap in enumerate(self.taps[phase :: self.factor]):
                            y += tap * x[:, p - 1 - k : p - 1 - k + count]
                        yield phase, y

                produced = ((phase, 0, y) for phase, y in outputs())
            else:

                def outputs():
                    for phase, (index, gain) in self.copies.items():
                        yield phase, 0, gain * x[:, p - 1 - index : p - 1 - index + count]
                    phases = [self.phases[phase] for phase in self.convolved]
                    for index, first, y in _phase_outputs(x, phases, count):
                        yield self.convolved[index], first, y

                produced = outputs()
            shifts = {}
            for phase, first, y in produced:
                span = slice(first, first + y.shape[1])
                np.maximum(peak[span], np.abs(y).max(axis=0), out=peak[span])
                if offset_peak is not None:
                    if phase not in shifts:
                        # Only the outputs before sample 0's window is whole (the first block's
                        # first few) have shifts of their own; the last column is everyone's.
                        head = min(count, max(0, -self.buffer_start))
                        shifts[phase] = self.offsets * self._offset_response(phase, head + 1)
                    shift = shifts[phase]
                    lo, hi = span.start, min(span.stop, shift.shape[1] - 1)
                    if self.offset_maximum_only:
                        best = offset_peak[0]
                        if hi > lo:  # the first outputs, with shifts of their own
                            head = np.abs(y[:, : hi - lo] + shift[:, lo:hi]).max()
                            best = max(best, head)
                        rest = y[:, max(hi - lo, 0) :]
                        if rest.shape[1]:
                            last = shift[:, -1]
                            top = np.abs(rest.max(axis=1) + last).max()
                            bottom = np.abs(rest.min(axis=1) + last).max()
                            best = max(best, top, bottom)
                        offset_peak[0] = best
                        continue
                    shifted = y + shift[:, -1:]
                    if hi > lo:
                        shifted[:, : hi - lo] = y[:, : hi - lo] + shift[:, lo:hi]
                    np.abs(shifted, out=shifted)
                    np.maximum(offset_peak[span], shifted.max(axis=0), out=offset_peak[span])
            self.buffer = x[:, count:].copy()
            self.buffer_start += count
        else:
            self.buffer = x
        return s0, peak, offset_peak


class _StreamFrames:
    """RMS and peak of the centred, zero-padded frames of a mono signal fed in blocks (what
    ``features._frame_rms_peak`` gives for the whole signal)."""

    def __init__(self, n_samples: int, *, n_fft: int, hop_length: int) -> None:
        self.n_fft, self.hop = n_fft, hop_length
        self.pad = n_fft // 2
        self.n_frames = frame_count(n_samples, n_fft=n_fft, hop_length=hop_length)
        self.rms = np.empty(self.n_frames)
        self.peak = np.empty(self.n_frames)
        self.buffer = np.zeros(self.pad, dtype=np.float32)
        self.buffer_start = -self.pad
        self.next = 0

    def feed(self, block: np.ndarray) -> None:
        self.buffer = np.concatenate([self.buffer, block.astype(np.float32, copy=False)])
        self._emit()

    def finish(self) -> None:
        self.buffer = np.concatenate([self.buffer, np.zeros(self.pad, dtype=np.float32)])
        self._emit()
        if self.next != self.n_frames:
            raise ExtractError(f"framing ended at frame {self.next} of {self.n_frames}")

    def _emit(self) -> None:
        length = self.buffer.shape[0]
        offset = self.next * self.hop - self.pad - self.buffer_start
        available = (length - self.n_fft - offset) // self.hop + 1 if length >= offset else 0
        count = min(max(available, 0), self.n_frames - self.next)
        if count > 0:
            frames = sliding_window_view(self.buffer[offset:], self.n_fft)[:: self.hop][:count]
            for first in range(0, count, _FRAME_CHUNK):
                chunk = frames[first : first + _FRAME_CHUNK].astype(np.float64)
                at = self.next + first
                stop = at + chunk.shape[0]
                self.rms[at:stop] = np.sqrt(np.einsum("ij,ij->i", chunk, chunk) / self.n_fft)
                self.peak[at:stop] = np.abs(chunk).max(axis=1)
            self.next += count
        drop = self.next * self.hop - self.pad - self.buffer_start
        if drop > 0:
            self.buffer = self.buffer[drop:].copy()
            self.buffer_start += drop


@dataclass(frozen=True)
class SignalStats:
    """What the second decoding pass measures (see :func:`signal_pass`)."""

    frame_rms: np.ndarray
    frame_peak: np.ndarray
    energy: np.ndarray
    boundaries: np.ndarray
    segment_peak: np.ndarray
    true_peak_clean: float
    mono_squares: np.ndarray
    mono_peaks: np.ndarray
    dr_squares: np.ndarray
    dr_peaks: np.ndarray
    dr_lengths: np.ndarray
    true_peak_decoded: float
    window_maxima: dict = field(default_factory=dict)

    def dynamics(self, sample_rate: float) -> Dynamics:
        """Short-term loudness, PSR and 3 s crest every 100 ms from these sums
        (:func:`~loudscape_extract.dynamics.dynamics_from_segments`)."""
        return dynamics_from_segments(
            self.energy,
            self.boundaries,
            segment_peak=self.segment_peak,
            true_peak=self.true_peak_clean,
            mono_squares=self.mono_squares,
            mono_peaks=self.mono_peaks,
            sample_rate=sample_rate,
        )


def signal_pass(
    decoded: DecodedMono,
    *,
    n_fft: int,
    hop_length: int,
    highpass_hz: float | None = None,
    block: int = DEFAULT_BLOCK_SAMPLES,
) -> SignalStats:
    """Decode again (or read the blocks the decoding pass kept) and measure, per block, what
    the loudness and dynamics metrics need.

    The signal is the DC-free (and optionally high-passed) channels, as in
    :func:`track_features`; the true peak of the decoded signal is measured too.
    """
    info = decoded.info
    rate = info.sample_rate
    n = decoded.n_samples
    nc = info.n_channels
    dc_rows = decoded.dc.astype(np.float32)[:, None]
    highpass = None
    if highpass_hz is not None:
        sos = highpass_sos(highpass_hz, sample_rate=rate)
        highpass = _StreamFir(_impulse_response(tuple(sos.ravel())), nc, np.float32)
    gains = channel_gains(nc)
    used = np.flatnonzero(gains)
    k_sos = k_weighting_sos(sample_rate=rate)
    k_weighting = _StreamFir(_impulse_response(tuple(k_sos.ravel())), used.shape[0], np.float32)
    n_segments = int(math.floor(n / (0.1 * rate) + 1e-9))
    boundaries = np.round(np.arange(n_segments + 1) * 0.1 * rate).astype(np.int64)
    boundaries = np.minimum(boundaries, n)
    energy = np.zeros((used.shape[0], n_segments))
    segment_peak = np.zeros(n_segments, dtype=np.float32)
    mono_squares = np.zeros(n_segments)
    mono_peaks = np.zeros(n_segments)
    dr_block = dr_block_length(rate)
    dr_bounds = np.append(np.arange(0, n, dr_block), n).astype(np.int64)
    dr_squares = np.zeros((nc, dr_bounds.shape[0] - 1))
    dr_peaks = np.zeros((nc, dr_bounds.shape[0] - 1))
    # Without the high-pass the decoded signal is the DC-free one plus the channel means: one
    # oversampled pass gives both true peaks. With it they differ by more; two passes.
    peak_clean = _StreamTruePeak(
        nc, offsets=None if highpass is not None else decoded.dc, offset_maximum_only=True
    )
    peak_decoded = _StreamTruePeak(nc) if highpass is not None else None
    frames = _StreamFrames(n, n_fft=n_fft, hop_length=hop_length)
    maxima = WindowMaxima(sample_rate=rate)
    overall_clean = 0.0
    overall_decoded = decoded.sample_peak
    seen = 0
    if decoded.blocks is not None and decoded.block == block:
        source = iter(decoded.blocks)
    else:
        source = read_blocks(info, block=block)
    for start, samples in source:
        if start + samples.shape[0] > n:
            raise ExtractError("the file changed while it was read (more samples)", path=info.path)
        # The channels as rows (contiguous): every per-channel pass below reads them so, and
        # numpy's arithmetic on the decoder's (samples, channels) layout is slow.
        channels = np.ascontiguousarray(samples.T)
        clean = channels - dc_rows
        if highpass is not None:
            clean = highpass(clean)
        mono_clean = mix_rows_to_mono(clean)
        filtered = k_weighting(clean[used])
        for row in range(used.shape[0]):
            squared = np.square(filtered[row], dtype=np.float64)
            _reduce_into(energy[row], squared, start, boundaries, np.add)
        maxima.feed(weighted_power(filtered, gains[used]))
        sample_abs = np.abs(clean).max(axis=0)
        _reduce_into(segment_peak, sample_abs, start, boundaries, np.maximum)
        overall_clean = max(overall_clean, float(sample_abs.max()))
        s0, interpolated, decoded_peak = peak_clean.feed(clean)
        if interpolated.size:
            _reduce_into(segment_peak, interpolated, s0, boundaries, np.maximum)
            overall_clean = max(overall_clean, float(interpolated.max()))
        if peak_decoded is not None:
            _, decoded_peak, _ = peak_decoded.feed(channels)
        if decoded_peak is not None and decoded_peak.size:
            overall_decoded = max(overall_decoded, float(decoded_peak.max()))
        # Squares in float64 straight from the float32 samples (no float64 copy first); the
        # peaks in float32 (absolute values and maxima are exact; the sums hold float64).
        _reduce_into(
            mono_squares, np.square(mono_clean, dtype=np.float64), start, boundaries, np.add
        )
        _reduce_into(mono_peaks, np.abs(mono_clean), start, boundaries, np.maximum)
        _reduce_into(dr_squares, np.square(clean, dtype=np.float64), start, dr_bounds, np.add)
        _reduce_into(dr_peaks, np.abs(clean), start, dr_bounds, np.maximum)
        frames.feed(mono_clean)
        seen = start + samples.shape[0]
    if seen != n:
        raise ExtractError("the file changed while it was read (fewer samples)", path=info.path)
    frames.finish()
    total_energy = np.zeros(n_segments)
    for row, channel in enumerate(used):
        total_energy += gains[channel] * energy[row]
    return SignalStats(
        frame_rms=frames.rms,
        frame_peak=frames.peak,
        energy=total_energy,
        boundaries=boundaries,
        segment_peak=segment_peak,
        true_peak_clean=overall_clean,
        mono_squares=mono_squares,
        mono_peaks=mono_peaks,
        dr_squares=dr_squares.T.copy(),
        dr_peaks=dr_peaks.T.copy(),
        dr_lengths=np.diff(dr_bounds),
        true_peak_decoded=overall_decoded,
        window_maxima=maxima.result(),
    )


def decode_track(
    path: str,
    *,
    n_fft: int = 2048,
    block_samples: int = DEFAULT_BLOCK_SAMPLES,
    strict: bool = False,
) -> DecodedMono:
    """:func:`decode_pass` of ``path``, refusing audio that yields no frame or no sound.

    Raises
    ------
    ExtractError
        As :func:`decode_audio`; audio shorter than one STFT frame, or entirely silent.
    """
    decoded = decode_pass(audio_info(path), block=block_samples, strict=strict)
    check_analysable(
        n_samples=decoded.n_samples,
        sample_rate=decoded.info.sample_rate,
        n_fft=n_fft,
        any_sample=decoded.any_nonzero,
        mono=decoded.mono,
        path=path,
    )
    return decoded
