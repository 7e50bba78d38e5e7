"""Align two releases of one song in time: a global offset, a time map across edits, a confidence.

Releases of one song differ in ways that keep its music: a remaster starts 0.2-2 s later, is
louder through a limiter, has another EQ or fade, or a cut or a longer intro. The alignment
works in three steps (docs/COMPARE.md, "Alignment"):

1. **Onset envelopes.** Each version is mixed to mono, resampled to 12 kHz and turned into a
   spectral-flux envelope at 100 Hz over 40 log-spaced bands (the positive change of each
   band's log energy). Flux ignores gain, a limiter's slow gain changes and a static EQ, which
   change the level of a band but not when its notes start.
2. **Segments.** Windows of A's envelope (6 s long, every 2 s) are cross-correlated with B's
   whole envelope. A window that finds one clear peak (normalized correlation at least
   :data:`MATCH_CORRELATION`) gives a local offset. Consecutive windows whose offsets agree
   within 30 ms form a segment of constant offset; a cut in B starts a new segment with another
   offset, and the part of A that B lacks matches nothing. The time map is the list of segments.
3. **Sample accuracy.** Each segment's offset is refined on the signals themselves (mono, the
   file's own rate) by generalized cross-correlation with phase transform (GCC-PHAT) over the
   segment's loudest 3 s, within +-20 ms of the envelope's offset, with a parabolic fit of the
   peak. PHAT whitens the spectra, so the EQ and the level of either version do not move it.

Two unrelated songs give windows whose peaks scatter: when less than :data:`MIN_MATCHED` of
A's windows fall into segments, the pair is reported as not alignable and nothing is shifted.

Offsets are in seconds, positive when B's music comes later than A's (B = A delayed):
``t_b = t_a + offset_s``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.fft import irfft, rfft

#: The envelope's rate in Hz (10 ms steps).
ENVELOPE_RATE = 100
_N_BANDS = 40
#: A window's length and step in seconds.
WINDOW_S = 6.0
STEP_S = 2.0
#: A window matches where its normalized cross-correlation peak reaches this.
MATCH_CORRELATION = 0.5
#: Windows whose offsets agree within this many seconds belong to one segment.
SEGMENT_TOLERANCE_S = 0.03
#: The least share of A's windows that must fall into segments for the pair to be alignable.
MIN_MATCHED = 0.4
#: The refinement's search range around the envelope's offset, in seconds.
REFINE_RANGE_S = 0.02
REFINE_EXCERPT_S = 3.0
#: Candidate peaks kept per window, and the dynamic programme's costs.
_CANDIDATES = 4
_CHANGE_COST = 1.0
_NONE_COST = 0.15
#: The signals' phase-transform correlation peak must stand this many standard deviations
#: above the correlation around it for a segment to count as the same recording.
MIN_PHAT_Z = 10.0
_VERIFY_RANGE_S = 0.3
#: Without the signals' confirmation, a segment counts where its envelopes correlate this well.
SAME_MUSIC_CORRELATION = 0.85


@dataclass(frozen=True)
class Segment:
    """A stretch of A whose music B has at a constant offset.

    Attributes
    ----------
    start_s, end_s : float
        The stretch in A's time, seconds.
    offset_s : float
        ``t_b - t_a`` for every moment of the stretch.
    correlation : float
        The median normalized correlation of its windows, 0-1.
    """

    start_s: float
    end_s: float
    offset_s: float
    correlation: float


@dataclass(frozen=True)
class Alignment:
    """How B's time maps onto A's.

    Attributes
    ----------
    alignable : bool
        False for two pieces of music that do not share their content; then ``offset_s`` is 0
        and ``segments`` is empty, and nothing should be shifted.
    offset_s : float
        The offset of the longest segment: the one to use where a single number is wanted.
    confidence : float
        0-1: the share of A's windows that fall into segments times their median correlation.
    segments : tuple of Segment
        The time map, in A's order.
    reason : str
        Why the pair is not alignable (empty when it is).
    """

    alignable: bool
    offset_s: float
    confidence: float
    segments: tuple[Segment, ...] = field(default_factory=tuple)
    reason: str = ""

    def b_time(self, t_a: float) -> float:
        """B's time of the music that plays at ``t_a`` in A (the nearest segment's offset)."""
        if not self.segments:
            return float(t_a)
        best = min(
            self.segments,
            key=lambda s: (
                0.0
                if s.start_s <= t_a <= s.end_s
                else min(abs(t_a - s.start_s), abs(t_a - s.end_s))
            ),
        )
        return float(t_a + best.offset_s)

    def a_time(self, t_b: np.ndarray) -> np.ndarray:
        """A's time of the music at B's times ``t_b`` by the time map; NaN where B's music is
        not in A (a longer intro, an added part), and ``t_b`` itself where nothing aligns."""
        t_b = np.asarray(t_b, dtype=np.float64)
        if not self.alignable:
            return t_b.copy()
        if not self.segments:
            return t_b - self.offset_s
        out = np.full(t_b.shape, np.nan)
        for s in self.segments:
            inside = (t_b >= s.start_s + s.offset_s) & (t_b <= s.end_s + s.offset_s)
            out[inside & np.isnan(out)] = t_b[inside & np.isnan(out)] - s.offset_s
        return out

    def to_json(self) -> dict:
        return {
            "alignable": self.alignable,
            "offset_s": round(self.offset_s, 6) + 0.0,
            "confidence": round(self.confidence, 3),
            "segments": [
                {
                    "start_s": round(s.start_s, 3),
                    "end_s": round(s.end_s, 3),
                    "offset_s": round(s.offset_s, 6) + 0.0,
                    "correlation": round(s.correlation, 3),
                }
                for s in self.segments
            ],
            **({"reason": self.reason} if self.reason else {}),
        }


def _mono(samples: np.ndarray) -> np.ndarray:
    """The channels' mean as float32 (summed channel by channel: numpy's mean over a short
    last axis is slow on long signals)."""
    x = np.asarray(samples)
    if x.ndim == 1:
        return x.astype(np.float32, copy=False)
    out = x[:, 0].astype(np.float32)
    for c in range(1, x.shape[1]):
        out += x[:, c]
    if x.shape[1] > 1:
        out *= np.float32(1.0 / x.shape[1])
    return out


def onset_envelope(samples: np.ndarray, sample_rate: int) -> np.ndarray:
    """The spectral-flux envelope at :data:`ENVELOPE_RATE` Hz, zero mean and unit variance.

    Frames of about 21 ms (a power of two at the file's own rate) start every 10 ms (rounded
    to the sample), so no resampling is needed; their power spectra are summed into 40
    log-spaced bands between 60 Hz and 5.5 kHz.
    """
    x = _mono(samples)
    # Bands stop at 5.5 kHz: average groups of samples down to 16-24 kHz first (a boxcar's
    # aliasing is far below the flux's changes), a quarter of the FFT work at 44.1 kHz.
    step = max(1, int(sample_rate) // 16_000)
    if step > 1:
        n = len(x) // step
        summed = x[0 : n * step : step].copy()
        for k in range(1, step):
            summed += x[k : n * step : step]
        x = summed * np.float32(1.0 / step)
    rate = int(sample_rate) / step
    n_fft = 1 << int(np.ceil(np.log2(rate * 0.021)))
    n_frames = int(max(0, (len(x) - n_fft) * ENVELOPE_RATE // rate + 1))
    if n_frames < 2:
        return np.zeros(max(n_frames, 1))
    freqs = np.fft.rfftfreq(n_fft, 1.0 / rate)
    edges = np.geomspace(60.0, 5_500.0, _N_BANDS + 1)
    band_of = np.searchsorted(edges, freqs) - 1
    to_bands = np.zeros((len(freqs), _N_BANDS), dtype=np.float32)
    keep = (band_of >= 0) & (band_of < _N_BANDS)
    to_bands[np.flatnonzero(keep), band_of[keep]] = 1.0
    window = np.hanning(n_fft).astype(np.float32)
    starts = np.round(np.arange(n_frames) * (rate / ENVELOPE_RATE)).astype(np.int64)
    bands = np.empty((n_frames, _N_BANDS), dtype=np.float32)
    chunk = 2048
    offsets = np.arange(n_fft)
    for lo in range(0, n_frames, chunk):
        frames = x[starts[lo : lo + chunk, None] + offsets] * window
        spectrum = rfft(frames, axis=1)
        power = spectrum.real**2 + spectrum.imag**2
        bands[lo : lo + chunk] = power @ to_bands
    floor = 1e-10 * max(float(bands.max()), 1e-20)
    log_bands = np.log10(bands.astype(np.float64) + floor)
    flux = np.maximum(np.diff(log_bands, axis=0, prepend=log_bands[:1]), 0.0).sum(axis=1)
    flux -= flux.mean()
    spread = flux.std()
    return flux / spread if spread > 0 else flux


class _Correlator:
    """Normalized cross-correlation of windows of ``n`` values at every lag over ``other``.

    ``other``'s spectrum and running sums depend on ``other`` alone: computed once here, not
    once a window (a long song has hundreds of windows, each searched over the whole of B).
    """

    def __init__(self, other: np.ndarray, n: int) -> None:
        m = len(other)
        self.n = n
        self.size = 1 << int(np.ceil(np.log2(n + m)))
        self.spectrum = rfft(other, self.size)
        self.lags = np.arange(0, m - n + 1)
        sums = np.concatenate(([0.0], np.cumsum(other)))
        sq = np.concatenate(([0.0], np.cumsum(other * other)))
        seg_sum = sums[self.lags + n] - sums[self.lags]
        seg_sq = sq[self.lags + n] - sq[self.lags]
        self.seg_std = np.sqrt(np.maximum(seg_sq - seg_sum * seg_sum / n, 1e-12))

    def __call__(self, window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns ``(lags, rho)``: ``rho[i]`` is the Pearson correlation of ``window`` with
        ``other[lags[i]: lags[i] + n]`` over the part that overlaps ``other``."""
        lags = self.lags
        if len(lags) == 0:
            return lags, np.zeros(0)
        w = window - window.mean()
        raw = irfft(self.spectrum * np.conj(rfft(w, self.size)), self.size)
        rho = raw[lags] / (self.seg_std * np.linalg.norm(w) + 1e-12)
        return lags, rho


def _peaks(rho: np.ndarray, k: int, min_gap: int) -> list[int]:
    """The ``k`` highest local maxima of ``rho``, at least ``min_gap`` apart."""
    top = min(50 * k, len(rho))
    best = np.argpartition(rho, len(rho) - top)[len(rho) - top :]
    order = best[np.argsort(rho[best])[::-1]]
    chosen: list[int] = []
    for i in order:
        if all(abs(int(i) - j) >= min_gap for j in chosen):
            chosen.append(int(i))
            if len(chosen) == k:
                break
    return chosen


def _window_candidates(env_a: np.ndarray, env_b: np.ndarray) -> list[tuple[float, list]]:
    """For each window of A: (its start s, [(offset s, correlation), ...] best first)."""
    n = int(WINDOW_S * ENVELOPE_RATE)
    step = int(STEP_S * ENVELOPE_RATE)
    if len(env_a) < n or len(env_b) < n:
        n = min(len(env_a), len(env_b))
        step = max(n // 2, 1)
    out = []
    # Pad B by a window on each side so A's windows can fall before B's start (B = A cut at
    # the start) or after its end; padding is zeros (the envelope's mean).
    padded = np.concatenate((np.zeros(n), env_b, np.zeros(n)))
    correlate = _Correlator(padded, n)
    for start in range(0, max(len(env_a) - n, 0) + 1, step):
        window = env_a[start : start + n]
        if window.std() < 1e-6:
            out.append((start / ENVELOPE_RATE, []))
            continue
        lags, rho = correlate(window)
        candidates = []
        for best in _peaks(rho, _CANDIDATES, min_gap=5):
            # Sub-frame lag: a parabola through the peak and its neighbours.
            frac = 0.0
            if 0 < best < len(rho) - 1:
                y0, y1, y2 = rho[best - 1], rho[best], rho[best + 1]
                denom = y0 - 2 * y1 + y2
                if denom < 0:
                    frac = float(np.clip(0.5 * (y0 - y2) / denom, -0.5, 0.5))
            lag_frames = lags[best] + frac - n
            candidates.append(((lag_frames - start) / ENVELOPE_RATE, float(rho[best])))
        out.append((start / ENVELOPE_RATE, candidates))
    return out


def _best_path(windows: list[tuple[float, list]]) -> list[tuple[float, float, float]]:
    """One offset (or none) per window, by dynamic programming over the candidates.

    A window scores its candidate's correlation (none scores :data:`MATCH_CORRELATION`); a change
    of offset between neighbours costs :data:`_CHANGE_COST`, so the music's repeats (a chorus
    that matches the next chorus as well) do not pull single windows away from their neighbours,
    while a real cut, which every window after it agrees on, still changes the offset.
    Returns (start s, offset s, correlation) for the windows that matched.
    """
    if not windows:
        return []
    states = [[(None, MATCH_CORRELATION)] + list(c) for _, c in windows]
    score = [s[1] for s in states[0]]
    back: list[list[int]] = []
    for t in range(1, len(states)):
        prev, cur = states[t - 1], states[t]
        new_score, pointers = [], []
        for off, rho in cur:
            best, arg = -np.inf, 0
            for j, (poff, _) in enumerate(prev):
                if off is None or poff is None:
                    cost = 0.0 if off is poff else _NONE_COST
                else:
                    cost = 0.0 if abs(off - poff) <= SEGMENT_TOLERANCE_S else _CHANGE_COST
                value = score[j] - cost
                if value > best:
                    best, arg = value, j
            new_score.append(best + rho)
            pointers.append(arg)
        score = new_score
        back.append(pointers)
    i = int(np.argmax(score))
    path = [i]
    for pointers in reversed(back):
        i = pointers[i]
        path.append(i)
    path.reverse()
    chosen = []
    for (start, _), state, k in zip(windows, states, path, strict=True):
        off, rho = state[k]
        if off is not None:
            chosen.append((start, float(off), float(rho)))
    return chosen


def _segments(windows: list[tuple[float, float, float]]) -> list[Segment]:
    segments: list[Segment] = []
    run: list[tuple[float, float, float]] = []

    def close() -> None:
        if run:
            offsets = np.array([w[1] for w in run])
            segments.append(
                Segment(
                    start_s=run[0][0],
                    end_s=run[-1][0] + WINDOW_S,
                    offset_s=float(np.median(offsets)),
                    correlation=float(np.median([w[2] for w in run])),
                )
            )

    last_start = None
    for w in windows:
        gap = last_start is not None and w[0] - last_start > STEP_S * 1.5
        if run and (gap or abs(w[1] - float(np.median([r[1] for r in run]))) > SEGMENT_TOLERANCE_S):
            close()
            run = []
        run.append(w)
        last_start = w[0]
    close()
    # Where two segments overlap in A (a window spans the cut), the boundary goes midway.
    fixed: list[Segment] = []
    for seg in segments:
        if fixed and seg.start_s < fixed[-1].end_s:
            mid = 0.5 * (seg.start_s + fixed[-1].end_s)
            prev = fixed[-1]
            fixed[-1] = Segment(prev.start_s, mid, prev.offset_s, prev.correlation)
            seg = Segment(mid, seg.end_s, seg.offset_s, seg.correlation)
        fixed.append(seg)
    return fixed


def _gcc_phat_offset(
    a: np.ndarray, b: np.ndarray, sample_rate: int, segment: Segment
) -> tuple[float, float] | None:
    """The segment's offset to a fraction of a sample and the peak's z-score, or None where the
    segment is too short or runs off B."""
    n_ex = int(REFINE_EXCERPT_S * sample_rate)
    margin = int(_VERIFY_RANGE_S * sample_rate) + 1
    lo = max(int(segment.start_s * sample_rate), 0)
    hi = min(int(segment.end_s * sample_rate) - n_ex, len(a) - n_ex)
    if hi < lo:
        return None
    # The loudest excerpt of the segment whose match lies inside B: most transients to lock on.
    # Energies from quarter-excerpt blocks, so the cost is one pass over the segment.
    step = max(n_ex // 4, 1)
    n_blocks = (hi - lo) // step + 4
    region = a[lo : lo + n_blocks * step]
    n_blocks = len(region) // step
    blocks = np.einsum("ij,ij->i", *(region[: n_blocks * step].reshape(n_blocks, step),) * 2)
    starts, energies = [], []
    for i in range(0, max(n_blocks - 3, 0)):
        s = lo + i * step
        b_start = int(np.floor(s + segment.offset_s * sample_rate)) - margin
        if s <= hi and b_start >= 0 and b_start + n_ex + 2 * margin <= len(b):
            starts.append(s)
            energies.append(float(blocks[i : i + 4].sum()))
    if not starts:
        return None
    start = starts[int(np.argmax(energies))]
    b_lo = int(np.floor(start + segment.offset_s * sample_rate)) - margin
    ex_a = a[start : start + n_ex] * np.hanning(n_ex)
    ex_b = b[b_lo : b_lo + n_ex + 2 * margin]
    size = 1 << int(np.ceil(np.log2(len(ex_a) + len(ex_b))))
    cross = rfft(ex_b, size) * np.conj(rfft(ex_a, size))
    cross /= np.abs(cross) + 1e-12
    corr = irfft(cross, size)[: 2 * margin + 1]
    # Prefer the peak near the envelope's estimate; the whole range measures the noise.
    near = int(REFINE_RANGE_S * sample_rate)
    window = corr[margin - near : margin + near + 1]
    best = margin - near + int(np.argmax(window))
    rest = np.delete(corr, np.arange(max(best - 50, 0), min(best + 51, len(corr))))
    z = float((corr[best] - rest.mean()) / (rest.std() + 1e-12))
    frac = 0.0
    if 0 < best < len(corr) - 1:
        y0, y1, y2 = corr[best - 1], corr[best], corr[best + 1]
        denom = y0 - 2 * y1 + y2
        if denom < 0:
            frac = float(np.clip(0.5 * (y0 - y2) / denom, -0.5, 0.5))
    lag = b_lo + best + frac - start
    return float(lag / sample_rate), z


def align(
    a: np.ndarray, b: np.ndarray, sample_rate_a: int, sample_rate_b: int | None = None
) -> Alignment:
    """Align B to A.

    Parameters
    ----------
    a, b : np.ndarray [shape=(n,) or (n, channels)]
        The two versions' samples.
    sample_rate_a, sample_rate_b : int
        Their rates (B's defaults to A's). Versions at other rates are aligned on the
        envelopes and refined at A's rate after resampling B.

    Returns
    -------
    Alignment

    Examples
    --------
    Noise with a changing level, and the same 0.25 s (2,000 samples) later and 6 dB louder:

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> rate = 8000
    >>> a = rng.standard_normal(rate * 20) * np.repeat(rng.uniform(0.1, 1, 200), rate // 10)
    >>> b = 2.0 * np.concatenate([np.zeros(2000), a])
    >>> found = align(a, b, rate)
    >>> found.alignable, round(found.offset_s * rate, 2), round(found.b_time(10.0), 4)
    (True, 2000.0, 10.25)
    """
    sample_rate_b = sample_rate_a if sample_rate_b is None else sample_rate_b
    for name, x in (("A", a), ("B", b)):
        if np.asarray(x).size == 0:
            raise ExtractError(f"cannot align: version {name} has no samples")
    mono_a = _mono(a)
    mono_b = _mono(b)
    env_a = onset_envelope(mono_a, sample_rate_a)
    env_b = onset_envelope(mono_b, sample_rate_b)
    segments = _segments(_best_path(_window_candidates(env_a, env_b)))
    if sample_rate_b != sample_rate_a:
        g = np.gcd(int(sample_rate_a), int(sample_rate_b))
        # Imported here: scipy.signal costs every extractor command 0.6-0.8 s of start-up.
        from scipy.signal import resample_poly

        mono_b = resample_poly(mono_b, sample_rate_a // g, sample_rate_b // g)
    kept = []
    for seg in segments:
        exact = _gcc_phat_offset(mono_a, mono_b, sample_rate_a, seg)
        if exact is not None and exact[1] >= MIN_PHAT_Z:
            # The same recording: the signals give the offset to a fraction of a sample.
            kept.append(Segment(seg.start_s, seg.end_s, exact[0], seg.correlation))
        elif seg.correlation >= SAME_MUSIC_CORRELATION:
            # Another recording or transfer of the same music (a vinyl rip): the envelope's
            # offset, to a few milliseconds.
            kept.append(seg)
    covered = sum(s.end_s - s.start_s for s in kept)
    total = max(len(env_a) / ENVELOPE_RATE, 1e-9)
    share = min(covered / total, 1.0)
    if not kept or share < MIN_MATCHED:
        return Alignment(
            alignable=False,
            offset_s=0.0,
            confidence=0.0,
            reason=(
                f"the versions share no music: {100 * share:.0f} % of A found in B "
                f"(at least {100 * MIN_MATCHED:.0f} % needed)"
            ),
        )
    longest = max(kept, key=lambda s: s.end_s - s.start_s)
    median_corr = float(np.median([s.correlation for s in kept]))
    return Alignment(
        alignable=True,
        offset_s=longest.offset_s,
        confidence=float(min(share * median_corr, 1.0)),
        segments=tuple(kept),
    )
