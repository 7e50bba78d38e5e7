"""The EBU Mode known answers: every EBU Tech 3341 (V4, 2023) and Tech 3342 minimum-requirements
test case that can be synthesized from the specifications' text, read with this package's meter.

Each :class:`Case` builds its signal(s) at 48 kHz as Table 1 of the specification describes
(durations as given, no longer) and reads them the way a file-based meter does; every reading
must lie within the published tolerance. Not synthesized: 3341 cases 7 and 8 and 3342 cases 5
and 6, authentic programme only published as recordings.

The readings:

- ``M``, ``S``: momentary (400 ms) and short-term (3 s) loudness, every window at any sample
  position (:func:`sliding_loudness`), or the maxima of :func:`~loudscape_extract.loudness.
  window_maxima`; ``I``: integrated loudness; ``LRA``; ``TP``: true peak (4x oversampling).
- Cases 11 and 14 are the "live meter" variants of 10 and 13: one file, one maximum per
  successive segment (6 s and 800 ms), read from the windows that end in the segment.

``python preprocess/scripts/ebu_conformance.py`` prints the table docs/DYNAMICS.md holds.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.signal

from loudscape_extract.dsp import sos_filter
from loudscape_extract.loudness import (
    MOMENTARY_S,
    SHORT_TERM_S,
    block_loudness,
    channel_gains,
    integrated_loudness,
    k_weighting_sos,
    loudness_range,
    true_peak_dbtp,
    weighted_power,
    window_maxima,
)

__all__ = [
    "CASES",
    "RATE",
    "Case",
    "Reading",
    "run_case",
    "sliding_loudness",
    "tone",
    "tone_sequence",
    "true_peak_burst",
    "true_peak_sine",
]

#: The sample rate the EBU test set is published at.
RATE = 48000


def tone(level_dbfs: float, duration_s: float, *, start: int = 0, channels: int = 2) -> np.ndarray:
    """A 1 kHz sine of peak level ``level_dbfs`` in ``channels`` channels (in phase),
    ``round(duration_s * 48000)`` samples, its phase continuing from sample ``start``.

    Returns
    -------
    samples : np.ndarray [shape=(n, channels)]
    """
    n = int(round(duration_s * RATE))
    t = (start + np.arange(n)) / RATE
    mono = 10.0 ** (level_dbfs / 20.0) * np.sin(2.0 * np.pi * 1000.0 * t)
    return np.repeat(mono[:, None], channels, axis=1)


def tone_sequence(parts: list[tuple[float | None, float]]) -> np.ndarray:
    """Stereo 1 kHz tones one after another, ``(level_dbfs, duration_s)`` each (``None``:
    digital silence); the phase runs on across the parts.

    Returns
    -------
    samples : np.ndarray [shape=(n, 2)]
    """
    out, start = [], 0
    for level, duration in parts:
        if level is None:
            part = np.zeros((int(round(duration * RATE)), 2))
        else:
            part = tone(level, duration, start=start)
        out.append(part)
        start += part.shape[0]
    return np.concatenate(out)


def sliding_loudness(samples: np.ndarray, *, window_s: float) -> np.ndarray:
    """BS.1770 loudness of every window of ``round(window_s * 48000)`` consecutive samples,
    one sample apart (the reading a meter shows when the window ends at each sample).

    Returns
    -------
    loudness : np.ndarray [shape=(n - length + 1,)]
        LUFS; entry ``k`` is the window ending at sample ``k + length`` (exclusive).
    """
    gains = channel_gains(samples.shape[1])
    used = np.flatnonzero(gains)
    filtered = sos_filter(k_weighting_sos(sample_rate=RATE), samples[:, used].T, dtype=np.float32)
    power = weighted_power(filtered, gains[used])
    length = int(round(window_s * RATE))
    cumulative = np.concatenate([[0.0], np.cumsum(power)])
    sums = cumulative[length:] - cumulative[:-length]
    with np.errstate(divide="ignore"):
        return -0.691 + 10.0 * np.log10(np.maximum(sums, 0.0) / length)


@dataclass(frozen=True)
class Reading:
    """One value read off a test signal: ``what`` (e.g. ``"I"``, ``"max M, file 7"``)."""

    what: str
    value: float


@dataclass(frozen=True)
class Case:
    """One test case of Table 1.

    Attributes
    ----------
    name : str
        ``"3341-13"``, ``"3342-1"``; a variant adds a letter (``"3341-6b"``).
    signal : str
        What the signal is, in the specification's words, shortened.
    expected : str
        The expected response as the specification writes it.
    read : callable
        Returns the :class:`Reading` list; each is checked against ``target(reading)``.
    target : callable
        ``(expected_value, minus, plus)`` for a reading: it passes when
        ``expected - minus <= value <= expected + plus``.
    """

    name: str
    signal: str
    expected: str
    read: Callable[[], list[Reading]]
    target: Callable[[Reading], tuple[float, float, float]]


def _loudness_target(expected: float) -> Callable[[Reading], tuple[float, float, float]]:
    return lambda _reading: (expected, 0.1, 0.1)


def _true_peak_target(expected: float) -> Callable[[Reading], tuple[float, float, float]]:
    return lambda _reading: (expected, 0.4, 0.2)


def _steady(samples: np.ndarray, *, after_s: float = 0.0) -> list[Reading]:
    """M and S over every window position ending after ``after_s`` (the lowest and highest),
    and I."""
    out = []
    for label, window in (("M", MOMENTARY_S), ("S", SHORT_TERM_S)):
        values = sliding_loudness(samples, window_s=window)
        first_end = max(0, int(round(after_s * RATE)) - int(round(window * RATE)))
        values = values[first_end:]
        out += [Reading(f"{label} lowest", float(values.min()))]
        out += [Reading(f"{label} highest", float(values.max()))]
    out.append(Reading("I", integrated_loudness(samples, sample_rate=RATE)))
    return out


def _integrated(samples: np.ndarray) -> list[Reading]:
    return [Reading("I", integrated_loudness(samples, sample_rate=RATE))]


def _case_3341_6(channels: int, *, lfe_level: float | None = None) -> list[Reading]:
    """5.0 (L, R, C, Ls, Rs) or 5.1 in WAV order (L, R, C, LFE, Ls, Rs)."""
    levels = {"L": -28.0, "R": -28.0, "C": -24.0, "Ls": -30.0, "Rs": -30.0}
    order = ["L", "R", "C", "Ls", "Rs"] if channels == 5 else ["L", "R", "C", "LFE", "Ls", "Rs"]
    columns = []
    for name in order:
        if name == "LFE":
            level = lfe_level
            columns.append(
                np.zeros(20 * RATE) if level is None else tone(level, 20, channels=1)[:, 0]
            )
        else:
            columns.append(tone(levels[name], 20, channels=1)[:, 0])
    return _integrated(np.stack(columns, axis=1))


def _maxima(samples: np.ndarray) -> dict:
    return window_maxima(samples, sample_rate=RATE)


def _case_10() -> list[Reading]:
    out = []
    for i in range(20):
        samples = tone_sequence([(None, i * 0.15), (-23.0, 3.0), (None, 1.0)])
        out.append(Reading(f"max S, file {i + 1}", _maxima(samples)["max_short_term_lufs"]))
    return out


def _case_13() -> list[Reading]:
    out = []
    for i in range(20):
        samples = tone_sequence([(None, i * 0.02), (-23.0, 0.4), (None, 1.0)])
        out.append(Reading(f"max M, file {i + 1}", _maxima(samples)["max_momentary_lufs"]))
    return out


def _live_segments(
    parts: list[tuple[float | None, float]], segment_s: float, window_s: float, label: str
) -> list[Reading]:
    """One file of successive segments; per segment, the largest reading among the windows
    that end inside it."""
    samples = tone_sequence(parts)
    values = sliding_loudness(samples, window_s=window_s)
    length = int(round(window_s * RATE))
    ends = np.arange(values.shape[0]) + length  # exclusive end sample of each window
    segment = int(round(segment_s * RATE))
    out = []
    for i in range(int(round(samples.shape[0] / segment))):
        inside = (ends > i * segment) & (ends <= (i + 1) * segment)
        out.append(Reading(f"max {label}, segment {i + 1}", float(values[inside].max())))
    return out


def _case_11() -> list[Reading]:
    parts: list[tuple[float | None, float]] = []
    for i in range(20):
        parts += [(None, i * 0.15), (-38.0 + i, 3.0), (None, 3.0 - i * 0.15)]
    return _live_segments(parts, 6.0, SHORT_TERM_S, "S")


def _case_14() -> list[Reading]:
    parts: list[tuple[float | None, float]] = []
    for i in range(20):
        parts += [(None, i * 0.02), (-38.0 + i, 0.4), (None, 0.4 - i * 0.02)]
    return _live_segments(parts, 0.8, MOMENTARY_S, "M")


def _live_target(first: float) -> Callable[[Reading], tuple[float, float, float]]:
    """Segment ``k`` (1-based, the reading's last word) expects ``first + k - 1``."""
    return lambda reading: (first + int(reading.what.rsplit(" ", 1)[1]) - 1, 0.1, 0.1)


def _faded(x: np.ndarray, fade_s: float) -> np.ndarray:
    n = int(round(fade_s * RATE))
    ramp = np.minimum(1.0, np.minimum(np.arange(x.shape[0]), np.arange(x.shape[0])[::-1]) / n)
    return x * ramp


def true_peak_sine(divisor: int, amplitude: float, phase_deg: float) -> np.ndarray:
    """Cases 15-19: a stereo sine at ``fs / divisor``, 1 s, 10 ms fades.

    Returns
    -------
    samples : np.ndarray [shape=(48000, 2)]
    """
    n = np.arange(RATE)
    x = amplitude * np.sin(2.0 * np.pi * n / divisor + math.radians(phase_deg))
    x = _faded(x, 0.01)
    return np.stack([x, x], axis=1)


def true_peak_burst(offset: int) -> np.ndarray:
    """Cases 20-23: at 4 fs, a sine at fs/6 (amplitude 0.5) holding one period of fs/4 at
    amplitude 1.0, phase-continuous on both sides; low-pass (anti-aliasing) filtered and
    taken every 4th sample from ``offset``; 10 ms fades.

    Returns
    -------
    samples : np.ndarray [shape=(n, 2)]
    """
    fast = 4 * RATE
    period_slow, period_burst = 6 * 4, 4 * 4  # samples at 4 fs of one fs/6 and one fs/4 period
    slow = 0.5 * np.sin(2.0 * np.pi * np.arange(period_slow * 2000) / period_slow)
    burst = np.sin(2.0 * np.pi * np.arange(period_burst) / period_burst)
    half = slow.shape[0] // 2  # a whole number of periods: phase 0 on both sides of the burst
    x = np.concatenate([slow[:half], burst, slow[half:]])
    taps = scipy.signal.firwin(1023, 0.9 * RATE / 2, window=("kaiser", 12.0), fs=fast)
    x = np.convolve(x, taps, mode="same")[offset::4]
    x = _faded(x, 0.01)
    return np.stack([x, x], axis=1)


def _true_peak(samples: np.ndarray) -> list[Reading]:
    return [Reading("TP", true_peak_dbtp(samples, sample_rate=RATE))]


def _lra(parts: list[tuple[float, float]]) -> list[Reading]:
    return [Reading("LRA", loudness_range(tone_sequence(parts), sample_rate=RATE))]


def _grid_momentary_maximum(samples: np.ndarray) -> float:
    """The largest momentary loudness on the 100 ms grid alone (what a 10 Hz series reads)."""
    return float(np.max(block_loudness(samples, sample_rate=RATE)))


CASES: tuple[Case, ...] = (
    Case(
        "3341-1",
        "stereo 1 kHz sine, -23 dBFS per channel, 20 s",
        "M, S, I = -23.0 +-0.1 LUFS",
        lambda: _steady(tone_sequence([(-23.0, 20.0)])),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-2",
        "as 1 at -33 dBFS",
        "M, S, I = -33.0 +-0.1 LUFS",
        lambda: _steady(tone_sequence([(-33.0, 20.0)])),
        _loudness_target(-33.0),
    ),
    Case(
        "3341-3",
        "10 s at -36, 60 s at -23, 10 s at -36 dBFS",
        "I = -23.0 +-0.1 LUFS",
        lambda: _integrated(tone_sequence([(-36.0, 10.0), (-23.0, 60.0), (-36.0, 10.0)])),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-4",
        "10 s at -72, 10 s at -36, 60 s at -23, 10 s at -36, 10 s at -72 dBFS",
        "I = -23.0 +-0.1 LUFS",
        lambda: _integrated(
            tone_sequence(
                [(-72.0, 10.0), (-36.0, 10.0), (-23.0, 60.0), (-36.0, 10.0), (-72.0, 10.0)]
            )
        ),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-5",
        "20 s at -26, 20.1 s at -20, 20 s at -26 dBFS",
        "I = -23.0 +-0.1 LUFS",
        lambda: _integrated(tone_sequence([(-26.0, 20.0), (-20.0, 20.1), (-26.0, 20.0)])),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-6",
        "5.0: L, R -28, C -24, Ls, Rs -30 dBFS, 20 s",
        "I = -23.0 +-0.1 LUFS",
        lambda: _case_3341_6(5),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-6b",
        "as 6 in 5.1 (WAV order), LFE silent",
        "I = -23.0 +-0.1 LUFS",
        lambda: _case_3341_6(6),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-6c",
        "as 6b with a -10 dBFS tone in the LFE (BS.1770 leaves it out)",
        "I = -23.0 +-0.1 LUFS",
        lambda: _case_3341_6(6, lfe_level=-10.0),
        _loudness_target(-23.0),
    ),
    Case(
        "3341-9",
        "(1.34 s at -20, 1.66 s at -30 dBFS) x 5",
        "S = -23.0 +-0.1 LUFS, constant after 3 s",
        lambda: [
            r
            for r in _steady(tone_sequence([(-20.0, 1.34), (-30.0, 1.66)] * 5), after_s=3.0)
            if r.what.startswith("S")
        ],
        _loudness_target(-23.0),
    ),
    Case(
        "3341-10",
        "20 files: i x 0.15 s silence, 3 s at -23 dBFS, 1 s silence",
        "max S = -23.0 +-0.1 LUFS, each file",
        _case_10,
        _loudness_target(-23.0),
    ),
    Case(
        "3341-11",
        "one file: i x 0.15 s silence, 3 s at -38+i dBFS, 3 - i x 0.15 s silence",
        "max S = -38, -37, ..., -19 +-0.1 LUFS",
        _case_11,
        _live_target(-38.0),
    ),
    Case(
        "3341-12",
        "(0.18 s at -20, 0.22 s at -30 dBFS) x 25",
        "M = -23.0 +-0.1 LUFS, constant after 1 s",
        lambda: [
            r
            for r in _steady(tone_sequence([(-20.0, 0.18), (-30.0, 0.22)] * 25), after_s=1.0)
            if r.what.startswith("M")
        ],
        _loudness_target(-23.0),
    ),
    Case(
        "3341-13",
        "20 files: i x 20 ms silence, 400 ms at -23 dBFS, 1 s silence",
        "max M = -23.0 +-0.1 LUFS, each file",
        _case_13,
        _loudness_target(-23.0),
    ),
    Case(
        "3341-14",
        "one file: i x 20 ms silence, 400 ms at -38+i dBFS, 400 - i x 20 ms silence",
        "max M = -38, -37, ..., -19 +-0.1 LUFS",
        _case_14,
        _live_target(-38.0),
    ),
    Case(
        "3341-15",
        "stereo sine fs/4, amplitude 0.5, phase 0",
        "TP = -6.0 +0.2/-0.4 dBTP",
        lambda: _true_peak(true_peak_sine(4, 0.5, 0.0)),
        _true_peak_target(-6.0),
    ),
    Case(
        "3341-16",
        "fs/4, amplitude 0.5, phase 45",
        "TP = -6.0 +0.2/-0.4 dBTP",
        lambda: _true_peak(true_peak_sine(4, 0.5, 45.0)),
        _true_peak_target(-6.0),
    ),
    Case(
        "3341-17",
        "fs/6, amplitude 0.5, phase 60",
        "TP = -6.0 +0.2/-0.4 dBTP",
        lambda: _true_peak(true_peak_sine(6, 0.5, 60.0)),
        _true_peak_target(-6.0),
    ),
    Case(
        "3341-18",
        "fs/8, amplitude 0.5, phase 67.5",
        "TP = -6.0 +0.2/-0.4 dBTP",
        lambda: _true_peak(true_peak_sine(8, 0.5, 67.5)),
        _true_peak_target(-6.0),
    ),
    Case(
        "3341-19",
        "fs/4, amplitude 1.41, phase 45",
        "TP = +3.0 +0.2/-0.4 dBTP",
        lambda: _true_peak(true_peak_sine(4, 1.41, 45.0)),
        _true_peak_target(3.0),
    ),
    *(
        Case(
            f"3341-{20 + offset}",
            f"fs/6 at 0.5 with one period of fs/4 at 1.0, made at 4 fs, offset {offset}",
            "TP = 0.0 +0.2/-0.4 dBTP",
            (lambda offset=offset: _true_peak(true_peak_burst(offset))),
            _true_peak_target(0.0),
        )
        for offset in range(4)
    ),
    Case(
        "3342-1",
        "20 s at -20, 20 s at -30 dBFS",
        "LRA = 10 +-1 LU",
        lambda: _lra([(-20.0, 20.0), (-30.0, 20.0)]),
        lambda _r: (10.0, 1.0, 1.0),
    ),
    Case(
        "3342-2",
        "20 s at -20, 20 s at -15 dBFS",
        "LRA = 5 +-1 LU",
        lambda: _lra([(-20.0, 20.0), (-15.0, 20.0)]),
        lambda _r: (5.0, 1.0, 1.0),
    ),
    Case(
        "3342-3",
        "20 s at -40, 20 s at -20 dBFS",
        "LRA = 20 +-1 LU",
        lambda: _lra([(-40.0, 20.0), (-20.0, 20.0)]),
        lambda _r: (20.0, 1.0, 1.0),
    ),
    Case(
        "3342-4",
        "20 s each at -50, -35, -20, -35, -50 dBFS",
        "LRA = 15 +-1 LU",
        lambda: _lra([(-50.0, 20.0), (-35.0, 20.0), (-20.0, 20.0), (-35.0, 20.0), (-50.0, 20.0)]),
        lambda _r: (15.0, 1.0, 1.0),
    ),
)


def run_case(case: Case) -> list[tuple[Reading, bool]]:
    """Every reading of ``case`` and whether it is within the tolerance."""
    out = []
    for reading in case.read():
        expected, minus, plus = case.target(reading)
        value = reading.value
        ok = value is not None and expected - minus - 1e-9 <= value <= expected + plus + 1e-9
        out.append((reading, ok))
    return out
