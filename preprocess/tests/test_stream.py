"""Streamed (block by block) extraction equals the whole-track pipeline."""

from __future__ import annotations

import os

import numpy as np
import pytest
import soundfile

from loudscape_extract import decode_audio, read_ply, song_points, track_features
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import write_ply_blocks
from loudscape_extract.song import extract_song
from loudscape_extract.stream import stream_track

from conftest import musical_signal

SR = 8000
N_FFT, HOP = 256, 128
SERIES = (
    "rms_dbfs",
    "peak",
    "crest_db",
    "loudness_a_db",
    "hp_mean",
    "psr_db",
    "crest_3s_db",
    "short_term_lufs",
)


@pytest.fixture(scope="module")
def song_wav(tmp_path_factory):
    """6 s of stereo with a DC offset on one channel and 0.25 s of leading digital silence."""
    y = musical_signal(sample_rate=SR, duration_s=6.0)
    stereo = np.stack([y, 0.5 * y + 0.02], axis=1) * 0.8
    stereo[:2000] = 0.0
    path = os.path.join(tmp_path_factory.mktemp("stream"), "song.wav")
    soundfile.write(path, stereo, SR, subtype="FLOAT")
    return path


# One block holding the whole song, and blocks far shorter than the HPSS kernel's half-width
# (7 frames), the true-peak interpolator and the K-weighting's impulse response.
@pytest.mark.parametrize("block_samples, block_frames", [(1 << 20, 4096), (1000, 7)])
@pytest.mark.parametrize("highpass_hz", [None, 20.0])
def test_streamed_features_equal_whole_track(song_wav, block_samples, block_frames, highpass_hz):
    whole = track_features(
        decode_audio(song_wav), n_fft=N_FFT, hop_length=HOP, highpass_hz=highpass_hz
    )
    streamed = stream_track(
        song_wav,
        n_fft=N_FFT,
        hop_length=HOP,
        highpass_hz=highpass_hz,
        block_samples=block_samples,
        block_frames=block_frames,
    )
    assert np.array_equal(whole.frames.silent, streamed.frames.silent)
    assert whole.frames.silent.sum() > 10  # the leading silence is there
    for name in SERIES:
        a, b = getattr(whole.frames, name), getattr(streamed.frames, name)
        assert np.allclose(a, b, rtol=1e-5, atol=1e-6, equal_nan=True), name
    assert whole.metrics.keys() == streamed.metrics.keys()
    for key, value in whole.metrics.items():
        assert value is not None, key
        assert streamed.metrics[key] == pytest.approx(value, rel=1e-5, abs=1e-6), key
    assert streamed.metrics["dc_offset"] > 0.005


@pytest.mark.parametrize("block_samples, block_frames", [(1 << 20, 4096), (1500, 9)])
@pytest.mark.parametrize("freq_scale, floor_db", [("linear", 40.0), ("log", 0.0)])
def test_streamed_song_file_equals_whole_track_points(
    song_wav, tmp_path, block_samples, block_frames, freq_scale, floor_db
):
    whole = track_features(decode_audio(song_wav), n_fft=N_FFT, hop_length=HOP)
    expected = song_points(whole, floor_db=floor_db, freq_scale=freq_scale)
    output = str(tmp_path / "song.ply")
    metadata = extract_song(
        song_wav,
        output,
        n_fft=N_FFT,
        hop_length=HOP,
        floor_db=floor_db,
        freq_scale=freq_scale,
        block_samples=block_samples,
        block_frames=block_frames,
    )
    points, read_back = read_ply(output)
    assert np.array_equal(points, expected.points)  # bit for bit, HPSS across block edges
    assert read_back == metadata
    assert metadata["point_count"] == expected.points.shape[0]
    assert metadata["axes"]["y"]["max"] == pytest.approx(expected.axes["y"]["max"], abs=1e-6)
    assert metadata["stft"]["frames_kept"] == expected.frames_kept
    assert os.listdir(tmp_path) == ["song.ply"]


def test_block_writer_leaves_nothing_on_a_failing_producer(tmp_path):
    output = tmp_path / "out.ply"

    def failing():
        yield np.zeros((10, 5), np.float32)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_ply_blocks(output, n_points=20, metadata={}, blocks=failing())
    assert os.listdir(tmp_path) == []
    with pytest.raises(ExtractError, match="promises 20 points but 10"):
        write_ply_blocks(output, n_points=20, metadata={}, blocks=[np.zeros((10, 5))])
    with pytest.raises(ExtractError, match="promises 5 points but 10"):
        write_ply_blocks(output, n_points=5, metadata={}, blocks=[np.zeros((10, 5))])
    assert os.listdir(tmp_path) == []
    write_ply_blocks(
        output, n_points=3, metadata={"a": 1}, blocks=[np.ones((1, 5)), np.ones((2, 5))]
    )
    points, metadata = read_ply(output)
    assert points.shape == (3, 5) and metadata == {"a": 1}
