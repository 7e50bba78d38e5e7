import numpy as np
import pytest

from loudscape_extract import Audio, a_weighting_db, stft_magnitude, track_features
from loudscape_extract.spectrogram import frame_count

from conftest import sine


def test_stft_matches_librosa_scaled():
    librosa = pytest.importorskip("librosa")
    y = np.random.default_rng(0).standard_normal(3000).astype(np.float32)
    ours = stft_magnitude(y, n_fft=256, hop_length=64)
    window_sum = np.hanning(257)[:-1].sum()  # periodic Hann
    reference = np.abs(librosa.stft(y, n_fft=256, hop_length=64)) / (window_sum / 2)
    reference[[0, -1]] /= 2  # DC and Nyquist: no one-sided doubling
    assert ours.shape == reference.shape == (129, frame_count(3000, n_fft=256, hop_length=64))
    np.testing.assert_allclose(ours, reference, atol=1e-5)


def test_full_scale_sine_on_a_bin_reads_0_db_in_the_right_bin():
    sample_rate, n_fft = 8000, 256
    magnitude = stft_magnitude(
        sine(frequency=1000, sample_rate=sample_rate, duration_s=0.5), n_fft=n_fft, hop_length=128
    )
    interior = magnitude[:, 3:-3]
    expected_bin = round(1000 * n_fft / sample_rate)  # 32
    assert np.all(interior.argmax(axis=0) == expected_bin)
    np.testing.assert_allclose(interior[expected_bin], 1.0, atol=1e-4)


def test_dc_and_nyquist_read_their_amplitude():
    n = 4096
    constant = np.full(n, 0.25, dtype=np.float32)
    alternating = (0.5 * (-1.0) ** np.arange(n)).astype(np.float32)
    dc = stft_magnitude(constant, n_fft=256, hop_length=128)[:, 4:-4]
    nyquist = stft_magnitude(alternating, n_fft=256, hop_length=128)[:, 4:-4]
    np.testing.assert_allclose(dc[0], 0.25, rtol=1e-4)
    np.testing.assert_allclose(nyquist[-1], 0.5, rtol=1e-4)


def test_a_weighting_known_values():
    gains = a_weighting_db(np.array([1000.0, 100.0, 10000.0]))
    assert abs(gains[0]) < 0.01
    assert gains[1] == pytest.approx(-19.1, abs=0.1)
    assert gains[2] == pytest.approx(-2.5, abs=0.1)
    assert a_weighting_db(np.array([0.0]))[0] == -200.0


def test_sine_crest_factor_is_3_01_db():
    samples = sine(frequency=1000, sample_rate=8000, duration_s=1.0)[:, None].astype(np.float32)
    features = track_features(
        Audio(samples=samples, sample_rate=8000, path="sine.wav"), n_fft=256, hop_length=128
    )
    assert features.metrics["crest_median_db"] == pytest.approx(3.0103, abs=0.01)
    interior = features.frames.crest_db[2:-2]
    np.testing.assert_allclose(interior, 3.0103, atol=0.01)
    np.testing.assert_allclose(features.frames.rms_dbfs[2:-2], -3.0103, atol=0.01)
    # Spectral A-weighted frame level of a full-scale 1 kHz sine: 0 dB, the reference of Song
    # mode's per-bin scalar too (the two scalars once differed by 3.01 dB).
    np.testing.assert_allclose(features.frames.loudness_a_db[2:-2], 0.0, atol=0.05)
    np.testing.assert_allclose(features.level_a_db[32, 2:-2], 0.0, atol=0.05)


def test_silent_frames_are_flagged():
    y = np.zeros(8000, dtype=np.float32)
    y[4000:] = sine(frequency=500, sample_rate=8000, duration_s=0.5)
    features = track_features(
        Audio(samples=y[:, None], sample_rate=8000, path="x.wav"), n_fft=256, hop_length=256
    )
    silent = features.frames.silent
    assert silent[:15].all() and not silent[-5:].any()
    assert np.isnan(features.frames.crest_db[silent]).all()
