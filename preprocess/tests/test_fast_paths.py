"""The extractor's fast paths give what the plain computations give (issue 37)."""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest
import scipy.ndimage
import soundfile

from loudscape_extract import stream, stream_decode
from loudscape_extract.audio import audio_info, mix_to_mono
from loudscape_extract.hpss import median_filter_axis
from loudscape_extract.song import extract_song
from loudscape_extract.spectrogram import level_db
from loudscape_extract.stream import level_range
from loudscape_extract.stream_decode import _StreamTruePeak, decode_pass, signal_pass

from conftest import musical_signal


def _awkward_rows(channels: int) -> np.ndarray:
    rng = np.random.default_rng(3)
    samples = rng.standard_normal((4096, channels)).astype(np.float32)
    samples[0] = -0.0
    samples[1, 0] = -0.0
    samples[2] = 1e-45  # the smallest subnormal
    samples[3, 0], samples[3, 1] = 1e-40, -3e-40
    samples[4, 0], samples[4, 1] = np.float32(1) / 3, np.float32(2) / 3
    return samples


@pytest.mark.parametrize("channels", [2, 3, 6])
def test_mix_to_mono_is_numpys_mean_bit_for_bit(channels):
    samples = _awkward_rows(channels)
    expected = samples.mean(axis=1, dtype=np.float32)
    mono = mix_to_mono(samples)
    assert mono.dtype == np.float32
    assert np.array_equal(mono.view(np.uint32), expected.view(np.uint32))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("axis", [0, 1])
def test_median_of_magnitudes_equals_scipys_2d_median_bit_for_bit(dtype, axis):
    rng = np.random.default_rng(4)
    magnitude = np.abs(rng.standard_normal((257, 300))).astype(dtype)
    magnitude[10] = 0.0
    magnitude[20, 5] = np.inf
    magnitude[30, :40] = 1e-42  # subnormal in float32
    size = [1, 1]
    size[axis] = 31
    expected = scipy.ndimage.median_filter(magnitude, size=size, mode="reflect")
    filtered = median_filter_axis(magnitude, size=31, axis=axis)
    assert np.array_equal(filtered.view(np.uint8), expected.view(np.uint8))
    # Negative values (and -0.0) take the float path and agree too.
    signed = magnitude.copy()
    signed[40] *= -1
    signed[50, 3] = -0.0
    expected = scipy.ndimage.median_filter(signed, size=size, mode="reflect")
    assert np.array_equal(median_filter_axis(signed, size=31, axis=axis), expected)


def _peaks(blocks, offsets):
    meter = _StreamTruePeak(2, offsets=offsets)
    peaks, offset_peaks = [], []
    for block in blocks:
        _, peak, offset_peak = meter.feed(block)
        peaks.append(peak)
        offset_peaks.append(offset_peak)
    return np.concatenate(peaks), np.concatenate(offset_peaks)


def test_true_peak_fft_path_equals_the_shifted_sums(monkeypatch):
    """Long blocks (the phases by short FFTs, phase 0 as its one tap) against the direct
    shifted sums of every tap: equal to float32 rounding of the FFTs (1e-6 at this level)."""
    rng = np.random.default_rng(6)
    signal = (0.3 * rng.standard_normal((2, 250_000))).astype(np.float32)
    signal[:, :300] *= 3.0  # the partial windows at the start decide the first peaks
    offsets = np.array([0.2, -0.05], dtype=np.float32)
    blocks = [signal[:, :100_000], signal[:, 100_000:230_000], signal[:, 230_000:]]
    fast, fast_offset = _peaks(blocks, offsets)
    monkeypatch.setattr(stream_decode, "_SHORT_PEAK", 1 << 30)
    direct, direct_offset = _peaks(blocks, offsets)
    assert fast.shape == direct.shape
    np.testing.assert_allclose(fast, direct, rtol=0, atol=1e-6)
    np.testing.assert_allclose(fast_offset, direct_offset, rtol=0, atol=1e-6)
    assert float(fast.max()) > 1.0  # the loud start is there


@pytest.fixture(scope="module")
def stereo_wav(tmp_path_factory):
    y = musical_signal(sample_rate=8000, duration_s=5.0)
    stereo = np.stack([y, 0.4 * y + 0.01], axis=1) * 0.7
    path = os.path.join(tmp_path_factory.mktemp("fast"), "stereo.wav")
    soundfile.write(path, stereo, 8000, subtype="PCM_16")
    return path


def test_a_song_is_decoded_once_and_the_kept_blocks_give_the_same_measures(stereo_wav, monkeypatch):
    calls = []
    original = stream_decode.read_blocks

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(stream_decode, "read_blocks", counting)
    info = audio_info(stereo_wav)
    kept = decode_pass(info, block=7000)
    assert kept.blocks is not None
    kept_stats = signal_pass(kept, n_fft=256, hop_length=128, block=7000)
    assert len(calls) == 1
    again = decode_pass(info, block=7000, keep_values=0)  # too long to keep: decoded twice
    assert again.blocks is None
    again_stats = signal_pass(again, n_fft=256, hop_length=128, block=7000)
    assert len(calls) == 3
    for name, value in dataclasses.asdict(kept_stats).items():
        other = getattr(again_stats, name)
        if isinstance(value, np.ndarray):
            assert np.array_equal(value, other), name
        else:
            assert value == other, name


def test_song_points_reuse_the_level_pass_spectrogram_and_equal_a_second_stft(
    stereo_wav, tmp_path, monkeypatch
):
    """Song mode's points pass slices the magnitudes the level pass kept (one STFT of the
    track); a track too long to keep them computes the STFT again, and the files are equal
    byte for byte."""
    transforms = []
    original = stream._magnitude

    def counting(frames, window_scaled):
        transforms.append(frames.shape[0])
        return original(frames, window_scaled)

    monkeypatch.setattr(stream, "_magnitude", counting)
    kept = tmp_path / "kept.ply"
    extract_song(stereo_wav, str(kept), n_fft=256, hop_length=128, block_frames=40)
    n_frames = 1 + (5 * 8000) // 128
    assert sum(transforms) == n_frames  # the level pass's blocks only, no context, once
    transforms.clear()
    monkeypatch.setattr(stream, "KEEP_MAGNITUDE_VALUES", 0)
    again = tmp_path / "again.ply"
    extract_song(stereo_wav, str(again), n_fft=256, hop_length=128, block_frames=40)
    assert sum(transforms) > 2 * n_frames  # the points pass's own STFT, with HPSS context
    assert kept.read_bytes() == again.read_bytes()


@pytest.mark.parametrize("shape", [(1025, 2048), (129, 1), (2, 7), (513, 333)])
def test_level_range_equals_the_levels_of_every_bin(shape):
    rng = np.random.default_rng(sum(shape))
    spread = np.exp(rng.uniform(-30.0, 2.0, size=shape))
    cases = [
        (rng.standard_normal(shape) ** 2 * spread).astype(np.float32),
        np.zeros(shape, dtype=np.float32),
        np.full(shape, 1e-42, dtype=np.float32),  # subnormal, below the -200 dB floor
    ]
    cases[0][0, 0] = 7.5  # the loudest in the 0 Hz bin: counted with first bin 0 only
    for magnitude in cases:
        levels = level_db(magnitude)
        expected = {b: (float(levels[b:].max()), float(levels[b:].min())) for b in (0, 1)}
        assert level_range(magnitude) == expected
