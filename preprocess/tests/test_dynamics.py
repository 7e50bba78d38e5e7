"""Dynamics against reference implementations: DR (dr14meter), short-term loudness and true
peak (pyebur128, libebur128); DC removal and the frame-centred 3 s windows."""

import numpy as np
import pytest

from loudscape_extract import Audio, track_features
from loudscape_extract.dsp import kaiser_lowpass
from loudscape_extract.dynamics import (
    dc_and_highpass,
    dr_meter,
    frame_windows,
    short_term_dynamics,
)
from loudscape_extract.loudness import true_peak_dbtp

from conftest import musical_signal

RATE = 48000


def dynamic_stereo(seed, *, duration_s=24.0, rate=RATE, depth=0.8):
    """A musical signal whose level swells and falls (phrases), slightly different per side,
    with a 12 kHz line (inter-sample peaks), band-limited to 0.8 of Nyquist as a recording
    chain is: true-peak meters differ by design on content at Nyquist (their interpolators'
    pass bands differ), not on music."""
    y = musical_signal(sample_rate=rate, duration_s=duration_s, seed=seed)
    t = np.arange(y.shape[0]) / rate
    y = y + 0.25 * np.sin(2 * np.pi * min(12000.0, rate / 5) * t + 0.7)
    taps = kaiser_lowpass(129, 0.8, beta=8.0)
    y = np.convolve(y, taps, mode="same")
    envelope = (1.0 - depth) + depth * np.sin(2 * np.pi * t / 11.0) ** 2
    return np.stack([0.7 * y * envelope, 0.6 * np.roll(y, 37) * envelope], axis=1)


def ebur128(samples, rate, *, short_term=False):
    pyebur128 = pytest.importorskip("pyebur128")
    modes = pyebur128.MeasurementMode
    state = pyebur128.R128State(samples.shape[1], rate, modes.MODE_S | modes.MODE_TRUE_PEAK)
    hop = rate // 10
    loudness = []
    for i, start in enumerate(range(0, samples.shape[0] - hop + 1, hop)):
        block = np.ascontiguousarray(samples[start : start + hop], dtype=np.float64)
        state.add_frames(block.ravel(), hop)
        if short_term and i >= 29:
            loudness.append(pyebur128.get_loudness_shortterm(state))
    peak = max(pyebur128.get_true_peak(state, c) for c in range(samples.shape[1]))
    return np.array(loudness), 20 * np.log10(peak)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_dr_within_one_of_dr14meter(seed):
    dr14 = pytest.importorskip("dr14meter.compute_dr14")
    for depth in (0.2, 0.9):
        x = dynamic_stereo(seed, depth=depth, rate=44100)
        reference, _, _ = dr14.compute_dr14(x, 44100)
        assert dr_meter(x, sample_rate=44100) == pytest.approx(reference, abs=1.0)


def test_dr_of_a_sine_is_zero():
    t = np.arange(10 * RATE) / RATE
    x = np.sin(2 * np.pi * 1000 * t)[:, None]
    assert dr_meter(x, sample_rate=RATE) == pytest.approx(0.0, abs=0.01)


def test_short_term_loudness_and_true_peak_match_libebur128():
    x = dynamic_stereo(3)
    reference, reference_peak = ebur128(x, RATE, short_term=True)
    dynamics = short_term_dynamics(x, x.mean(axis=1), sample_rate=RATE)
    assert dynamics.short_term_lufs.shape == reference.shape
    np.testing.assert_allclose(dynamics.short_term_lufs, reference, atol=0.01)
    assert true_peak_dbtp(x, sample_rate=RATE) == pytest.approx(reference_peak, abs=0.05)
    assert 20 * np.log10(dynamics.true_peak) == pytest.approx(reference_peak, abs=0.05)
    # PSR is the window's true peak minus its short-term loudness.
    assert np.all(dynamics.psr_db >= dynamics.crest_3s_db - 6.0)
    assert np.all(np.isfinite(dynamics.psr_db))


def test_true_peak_does_not_overshoot_at_an_abrupt_end():
    """A full-scale sine cut at its crest: libebur128 reads 0.0 dBTP; zero padding made +1 dB."""
    t = np.arange(RATE) / RATE
    x = np.sin(2 * np.pi * 997 * t)
    x = x[: np.flatnonzero(np.abs(x) > 0.999)[-1] + 1]  # end on a crest
    x = np.stack([x, x], axis=1)
    _, reference = ebur128(x, RATE)
    ours = true_peak_dbtp(x, sample_rate=RATE)
    assert ours == pytest.approx(0.0, abs=0.05)
    assert ours == pytest.approx(reference, abs=0.1)


def test_dc_is_removed_and_recorded():
    x = dynamic_stereo(4, duration_s=8.0)
    clean, dc = dc_and_highpass(x + np.array([0.3, -0.1]), sample_rate=RATE)
    np.testing.assert_allclose(dc, np.array([0.3, -0.1]) + x.mean(axis=0), atol=1e-6)
    np.testing.assert_allclose(clean.mean(axis=0), 0.0, atol=1e-5)
    rumble = 0.2 * np.sin(2 * np.pi * 5 * np.arange(x.shape[0]) / RATE)[:, None]
    filtered, _ = dc_and_highpass(x + rumble, sample_rate=RATE, highpass_hz=20.0)
    residual = (
        filtered[RATE:-RATE] - dc_and_highpass(x, sample_rate=RATE, highpass_hz=20.0)[0][RATE:-RATE]
    )
    assert np.sqrt(np.mean(residual**2)) < 0.02 * np.sqrt(np.mean(rumble**2)) * 10


def test_frames_see_the_window_centred_on_them():
    x = dynamic_stereo(5, duration_s=12.0, rate=8000)
    dynamics = short_term_dynamics(x, x.mean(axis=1), sample_rate=8000)
    times = np.array([0.0, 1.5, 6.0, 11.9])
    index = frame_windows(times, dynamics)
    centres = dynamics.start_s[index] + 1.5
    assert index[0] == 0 and index[-1] == dynamics.start_s.shape[0] - 1  # clamped at the ends
    np.testing.assert_allclose(centres[1:3], times[1:3], atol=0.051)


def test_track_features_carry_the_dynamics():
    x = dynamic_stereo(6, duration_s=10.0, rate=8000).astype(np.float32)
    features = track_features(
        Audio(samples=x, sample_rate=8000, path="x"), n_fft=256, hop_length=128
    )
    frames = features.frames
    assert frames.psr_db.shape == frames.crest_3s_db.shape == frames.rms_dbfs.shape
    assert np.isfinite(frames.psr_db[~frames.silent]).all()
    metrics = features.metrics
    assert metrics["psr_p10_db"] <= metrics["psr_median_db"] <= metrics["psr_p90_db"]
    assert metrics["psr_spread_db"] == pytest.approx(
        metrics["psr_p90_db"] - metrics["psr_p10_db"], abs=1e-9
    )
    assert metrics["dr_db"] == pytest.approx(dr_meter(x, sample_rate=8000), abs=0.01)
