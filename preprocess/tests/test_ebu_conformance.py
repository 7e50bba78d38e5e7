"""EBU Mode conformance: every EBU Tech 3341 / Tech 3342 minimum-requirements case that can be
synthesized from the specifications (loudscape_extract.conformance), each reading within its
published tolerance; integrated loudness, LRA and true peak cross-checked with libebur128."""

from __future__ import annotations

import numpy as np
import pyebur128
import pytest

from loudscape_extract.conformance import (
    CASES,
    RATE,
    Reading,
    _grid_momentary_maximum,
    run_case,
    tone_sequence,
    true_peak_burst,
    true_peak_sine,
)
from loudscape_extract.loudness import (
    integrated_loudness,
    loudness_range,
    true_peak_dbtp,
    window_maxima,
)


@pytest.mark.parametrize("case", CASES, ids=[case.name for case in CASES])
def test_case_within_published_tolerance(case):
    results = run_case(case)
    assert results, case.name
    failed = [f"{reading.what}: {reading.value}" for reading, ok in results if not ok]
    assert not failed, f"{case.name} ({case.expected}): {failed}"


def test_every_synthesizable_case_is_there():
    names = {case.name.rstrip("abc") for case in CASES}
    expected = {f"3341-{i}" for i in [1, 2, 3, 4, 5, 6, *range(9, 24)]}
    expected |= {f"3342-{i}" for i in range(1, 5)}
    assert names == expected
    assert {"3341-6b", "3341-6c"} <= {case.name for case in CASES}  # 5.1 with and without LFE


def test_a_mislevelled_signal_fails_its_case():
    """The tolerance bites: case 1 played 0.2 dB too quiet is out."""
    case = next(c for c in CASES if c.name == "3341-1")
    quiet = tone_sequence([(-23.2, 20.0)])
    reading = Reading("I", integrated_loudness(quiet, sample_rate=RATE))
    expected, minus, plus = case.target(reading)
    assert not expected - minus <= reading.value <= expected + plus


def test_case_13_needs_every_window_position():
    """Read on the 100 ms grid alone (a 10 Hz momentary series), most of case 13's files miss
    the burst's maximum by more than the tolerance; the any-position maximum never does."""
    grid_misses = 0
    for i in range(20):
        samples = tone_sequence([(None, i * 0.02), (-23.0, 0.4), (None, 1.0)])
        exact = window_maxima(samples, sample_rate=RATE)["max_momentary_lufs"]
        assert exact == pytest.approx(-23.0, abs=0.1), i
        grid_misses += abs(_grid_momentary_maximum(samples) + 23.0) > 0.1
    assert grid_misses >= 12


def test_maxima_times_are_where_the_meter_shows_them():
    """The time of a maximum is the end of its window: case 13's file 4 (60 ms of silence)
    peaks when the 400 ms window ends with the burst, at 0.46 s."""
    samples = tone_sequence([(None, 0.06), (-23.0, 0.4), (None, 1.0)])
    maxima = window_maxima(samples, sample_rate=RATE)
    assert maxima["max_momentary_s"] == pytest.approx(0.46, abs=0.002)
    samples = tone_sequence([(None, 0.45), (-23.0, 3.0), (None, 1.0)])
    maxima = window_maxima(samples, sample_rate=RATE)
    assert maxima["max_short_term_s"] == pytest.approx(3.45, abs=0.002)


def _libebur128(samples: np.ndarray) -> dict:
    modes = pyebur128.MeasurementMode
    mode = modes.MODE_I | modes.MODE_LRA | modes.MODE_TRUE_PEAK
    state = pyebur128.R128State(samples.shape[1], RATE, mode)
    interleaved = np.ascontiguousarray(samples, dtype=np.float64)
    state.add_frames(interleaved.ravel(), samples.shape[0])
    peak = max(pyebur128.get_true_peak(state, c) for c in range(samples.shape[1]))
    return {
        "I": pyebur128.get_loudness_global(state),
        "LRA": pyebur128.get_loudness_range(state),
        "TP": 20.0 * np.log10(peak),
    }


@pytest.mark.parametrize(
    "parts",
    [
        [(-36.0, 10.0), (-23.0, 60.0), (-36.0, 10.0)],  # 3341-3
        [(-26.0, 20.0), (-20.0, 20.1), (-26.0, 20.0)],  # 3341-5
        [(-50.0, 20.0), (-35.0, 20.0), (-20.0, 20.0), (-35.0, 20.0), (-50.0, 20.0)],  # 3342-4
    ],
    ids=["3341-3", "3341-5", "3342-4"],
)
def test_integrated_and_range_agree_with_libebur128(parts):
    samples = tone_sequence(parts)
    theirs = _libebur128(samples)
    assert integrated_loudness(samples, sample_rate=RATE) == pytest.approx(theirs["I"], abs=0.02)
    assert loudness_range(samples, sample_rate=RATE) == pytest.approx(theirs["LRA"], abs=0.2)


@pytest.mark.parametrize(
    "samples",
    [true_peak_sine(4, 0.5, 45.0), true_peak_sine(8, 0.5, 67.5), true_peak_burst(2)],
    ids=["3341-16", "3341-18", "3341-22"],
)
def test_true_peak_agrees_with_libebur128(samples):
    ours = true_peak_dbtp(samples, sample_rate=RATE)
    assert ours == pytest.approx(_libebur128(samples)["TP"], abs=0.2)
