"""Known answers from EBU Tech 3341 (loudness), Tech 3342 (loudness range), BS.1770-4."""

import numpy as np
import pytest

from loudscape_extract import (
    integrated_loudness,
    k_weighting_sos,
    loudness_range,
    sample_peak_dbfs,
    true_peak_dbtp,
)
from loudscape_extract.loudness import WindowMaxima, loudness_metrics, window_maxima

RATE = 48000


def stereo_sine_sequence(levels_dbfs, durations_s, *, sample_rate=RATE, frequency=1000.0):
    """1 kHz sine in both channels, one level (dBFS = peak amplitude) per section, continuous."""
    parts = []
    start = 0
    for level, duration in zip(levels_dbfs, durations_s, strict=True):
        n = int(round(duration * sample_rate))
        t = (start + np.arange(n)) / sample_rate
        parts.append(10 ** (level / 20) * np.sin(2 * np.pi * frequency * t))
        start += n
    mono = np.concatenate(parts)
    return np.stack([mono, mono], axis=1)


def test_k_weighting_matches_bs1770_coefficients_at_48k():
    sos = k_weighting_sos(sample_rate=48000)
    shelf = [
        1.53512485958697,
        -2.69169618940638,
        1.19839281085285,
        1,
        -1.69065929318241,
        0.73248077421585,
    ]
    highpass = [1.0, -2.0, 1.0, 1, -1.99004745483398, 0.99007225036621]
    np.testing.assert_allclose(sos[0], shelf, atol=1e-8)
    np.testing.assert_allclose(sos[1], highpass, atol=1e-8)


@pytest.mark.parametrize(
    ("case", "levels", "durations"),
    [
        (1, [-23], [20]),
        (2, [-33], [20]),
        (3, [-36, -23, -36], [10, 60, 10]),
        (4, [-72, -36, -23, -36, -72], [10, 10, 60, 10, 10]),
        (5, [-26, -20, -26], [20, 20.1, 20]),
    ],
)
def test_tech_3341_integrated_loudness(case, levels, durations):
    expected = -33.0 if case == 2 else -23.0
    samples = stereo_sine_sequence(levels, durations)
    assert integrated_loudness(samples, sample_rate=RATE) == pytest.approx(expected, abs=0.1)


def test_integrated_loudness_agrees_with_pyloudnorm_on_music_like_signal(rng):
    pyloudnorm = pytest.importorskip("pyloudnorm")
    sample_rate = 22050
    n = sample_rate * 12
    envelope = np.repeat(rng.uniform(0.01, 0.5, n // 2205 + 1), 2205)[:n]
    samples = rng.standard_normal((n, 2)) * envelope[:, None]
    ours = integrated_loudness(samples, sample_rate=sample_rate)
    # pyloudnorm's "DeMan" filter is the same analogue-derived K-weighting as ours.
    theirs = pyloudnorm.Meter(sample_rate, filter_class="DeMan").integrated_loudness(samples)
    assert ours == pytest.approx(theirs, abs=0.05)


@pytest.mark.parametrize(
    ("levels", "durations", "expected"),
    [
        ([-20, -30], [20, 20], 10),
        ([-20, -15], [20, 20], 5),
        ([-40, -20], [20, 20], 20),
        ([-50, -35, -20, -35, -50], [20, 20, 20, 20, 20], 15),
    ],
    ids=["case1", "case2", "case3", "case4"],
)
def test_tech_3342_loudness_range(levels, durations, expected):
    samples = stereo_sine_sequence(levels, durations, sample_rate=16000)
    assert loudness_range(samples, sample_rate=16000) == pytest.approx(expected, abs=1.0)


def test_true_peak_of_quarter_rate_sine_at_45_degrees():
    n = np.arange(RATE // 10)
    fade = np.minimum(1.0, np.minimum(n, n[-1] - n) / 480)  # 10 ms fades: no onset overshoot
    x = 0.5 * np.sin(np.pi / 2 * n + np.pi / 4) * fade
    assert sample_peak_dbfs(x) == pytest.approx(-9.03, abs=0.05)
    assert true_peak_dbtp(x, sample_rate=RATE) == pytest.approx(-6.02, abs=0.4)
    assert true_peak_dbtp(x, sample_rate=RATE) == pytest.approx(-6.02, abs=0.02)


def test_true_peak_equals_full_oversampling(rng):
    """The block skipping must not change the result."""
    signal = pytest.importorskip("scipy.signal")
    from loudscape_extract.loudness import _interpolator

    x = rng.standard_normal((30000, 2)) * np.linspace(0.05, 0.6, 30000)[:, None]
    taps = _interpolator(4)
    reference = max(np.abs(signal.upfirdn(taps, x[:, c], 4)).max() for c in range(2))
    assert true_peak_dbtp(x, sample_rate=44100) == pytest.approx(20 * np.log10(reference), abs=1e-4)


def test_metrics_of_short_or_quiet_audio_are_none():
    short = stereo_sine_sequence([-20], [0.3])
    metrics = loudness_metrics(short, sample_rate=RATE)
    assert metrics["integrated_lufs"] is None and metrics["lra_lu"] is None
    assert metrics["plr_db"] is None
    assert metrics["sample_peak_dbfs"] == pytest.approx(-20, abs=0.01)
    quiet = stereo_sine_sequence([-90], [1.0])
    assert integrated_loudness(quiet, sample_rate=RATE) is None


def test_plr_is_true_peak_minus_integrated():
    samples = stereo_sine_sequence([-20], [4.0])
    metrics = loudness_metrics(samples, sample_rate=RATE)
    assert metrics["plr_db"] == pytest.approx(
        metrics["true_peak_dbtp"] - metrics["integrated_lufs"], abs=1e-9
    )
    assert metrics["integrated_lufs"] == pytest.approx(-20, abs=0.1)
    assert metrics["lra_lu"] == pytest.approx(0, abs=0.1)


def test_window_maxima_do_not_depend_on_the_blocks(rng):
    """Fed in blocks shorter and longer than either window, the maxima and their times are
    those of one whole feed."""
    power = rng.uniform(0.0, 1e-3, 8000 * 9) * np.repeat(rng.uniform(0, 1, 90), 800)
    whole = WindowMaxima(sample_rate=8000)
    whole.feed(power)
    for sizes in ([1000] * 72, [7, 30000, 3, 12345, 29990, 645]):
        pieces = WindowMaxima(sample_rate=8000)
        for piece in np.split(power, np.cumsum(sizes)[:-1]):
            pieces.feed(piece)
        assert pieces.result() == pytest.approx(whole.result(), rel=1e-9)


def test_metrics_carry_the_maxima_at_any_position():
    """A 400 ms burst 30 ms off the 100 ms grid: the metrics' maximum is the burst's loudness
    (the 10 Hz blocks read it lower), at the time its window ends."""
    samples = stereo_sine_sequence([-90, -20, -90], [1.03, 0.4, 3.0])
    samples[: int(1.03 * RATE)] = 0.0
    samples[int(1.43 * RATE) :] = 0.0
    metrics = loudness_metrics(samples, sample_rate=RATE)
    assert metrics["max_momentary_lufs"] == pytest.approx(-20.0, abs=0.02)
    assert metrics["max_momentary_s"] == pytest.approx(1.43, abs=0.002)
    assert metrics["max_short_term_lufs"] == pytest.approx(-20 + 10 * np.log10(0.4 / 3), abs=0.02)
    assert (
        metrics["max_momentary_lufs"]
        == window_maxima(samples, sample_rate=RATE)["max_momentary_lufs"]
    )
    too_short = loudness_metrics(samples[: RATE // 4], sample_rate=RATE)
    assert too_short["max_momentary_lufs"] is None and too_short["max_short_term_s"] is None
