import numpy as np
import pytest

from loudscape_extract import (
    Audio,
    hp_ratio,
    hpss_masks,
    median_filter_axis,
    stft_magnitude,
    track_features,
)

from conftest import musical_signal, sine

librosa = pytest.importorskip("librosa")
scipy_ndimage = pytest.importorskip("scipy.ndimage")


def _assert_masks_match(magnitude):
    ours_h, ours_p = hpss_masks(magnitude, kernel_size=31, power=2.0, margin=1.0)
    ref_h, ref_p = librosa.decompose.hpss(
        magnitude, kernel_size=31, power=2.0, margin=1.0, mask=True
    )
    assert ours_h.shape == ref_h.shape
    assert np.max(np.abs(ours_h - ref_h)) <= 1e-4
    assert np.max(np.abs(ours_p - ref_p)) <= 1e-4
    # The edges (first/last 15 rows and columns) are where padding could go wrong.
    for mask, ref in ((ours_h, ref_h), (ours_p, ref_p)):
        np.testing.assert_allclose(mask[:15], ref[:15], atol=1e-6)
        np.testing.assert_allclose(mask[-15:], ref[-15:], atol=1e-6)
        np.testing.assert_allclose(mask[:, :15], ref[:, :15], atol=1e-6)
        np.testing.assert_allclose(mask[:, -15:], ref[:, -15:], atol=1e-6)


@pytest.mark.parametrize("shape", [(97, 83), (10, 7), (40, 200), (1, 50)])
def test_masks_match_librosa_on_random_spectrograms(shape, rng):
    magnitude = (rng.random(shape) ** 3).astype(np.float32)
    magnitude[rng.random(shape) < 0.05] = 0.0  # zeros exercise the split-zeros rule
    _assert_masks_match(magnitude)


def test_masks_match_librosa_on_a_musical_spectrogram():
    magnitude = stft_magnitude(musical_signal(), n_fft=512, hop_length=128)
    _assert_masks_match(magnitude)


@pytest.mark.parametrize("axis", [0, 1])
def test_median_filter_equals_scipy_reflect(axis, rng):
    data = rng.random((33, 45))
    size = [1, 1]
    size[axis] = 9
    expected = scipy_ndimage.median_filter(data, size=size, mode="reflect")
    np.testing.assert_array_equal(median_filter_axis(data, size=9, axis=axis), expected)


def test_hp_ratio_formula():
    magnitude = np.array([[1.0, 0.0]], dtype=np.float32)
    hp = hp_ratio(magnitude, np.array([[0.8, 0.5]]), np.array([[0.2, 0.5]]))
    np.testing.assert_allclose(hp, [[0.8, 0.0]], atol=1e-6)


def _features(y, sample_rate=8000):
    audio = Audio(samples=np.asarray(y, np.float32)[:, None], sample_rate=sample_rate, path="t")
    return track_features(audio, n_fft=256, hop_length=64)


def test_sine_is_harmonic():
    features = _features(sine(frequency=1000, sample_rate=8000, duration_s=2.0, amplitude=0.5))
    assert features.hp[32, 10:-10].min() > 0.99
    assert np.nanmean(features.frames.hp_mean[10:-10]) > 0.95


def test_click_train_is_percussive():
    y = np.zeros(16000)
    y[::800] = 0.9  # a click every 100 ms
    features = _features(y)
    assert np.nanmedian(features.frames.hp_mean) < 0.1
    assert np.median(features.hp[5:-5, 20:-20]) < 0.1


def test_masks_match_librosa_with_margin_and_power(rng):
    magnitude = (rng.random((60, 70)) ** 3).astype(np.float32)
    ours = hpss_masks(magnitude, kernel_size=11, power=1.0, margin=2.0)
    theirs = librosa.decompose.hpss(magnitude, kernel_size=11, power=1.0, margin=2.0, mask=True)
    for mask, ref in zip(ours, theirs, strict=True):
        assert np.max(np.abs(mask - ref)) <= 1e-4
