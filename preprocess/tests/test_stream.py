"""Streamed (block by block) extraction equals the whole-track pipeline."""

from __future__ import annotations

import os

import numpy as np
import pytest
import soundfile

from loudscape_extract import decode_audio, read_ply, song_points, track_features
from loudscape_extract.contract import checked_blocks
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import MAX_LINE_BYTES, write_ply_blocks
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
    assert points.shape == (3, 5) and metadata == {"a": 1, "format_version": 2}


def test_streamed_song_is_format_2_with_short_header_lines(song_wav, tmp_path):
    output = tmp_path / "song.ply"
    metadata = extract_song(
        song_wav, str(output), n_fft=N_FFT, hop_length=HOP, block_samples=1000, block_frames=7
    )
    data = output.read_bytes()
    header = data[: data.index(b"end_header\n") + len(b"end_header\n")]
    lines = header.split(b"\n")[:-1]
    assert max(len(line) + 1 for line in lines) <= MAX_LINE_BYTES
    meta_lines = [line for line in lines if line.startswith(b"comment loudscape-meta")]
    assert meta_lines and all(line.startswith(b"comment loudscape-meta-v2 ") for line in meta_lines)
    assert f"element vertex {metadata['point_count']}".encode() in lines
    assert len(data) - len(header) == 20 * metadata["point_count"]  # exact count, 5 float32
    points, read_back = read_ply(output)
    assert read_back["format_version"] == 2 and points.shape[0] == metadata["point_count"]


def test_streamed_song_runs_the_contract_before_the_file_is_in_place(
    song_wav, tmp_path, monkeypatch
):
    import loudscape_extract.song as song_module

    real = song_module.song_metadata

    def one_value_hp_axis(*args, **kwargs):
        metadata = real(*args, **kwargs)
        metadata["axes"]["hp"]["max"] = metadata["axes"]["hp"]["min"]
        return metadata

    monkeypatch.setattr(song_module, "song_metadata", one_value_hp_axis)
    output = tmp_path / "song.ply"
    with pytest.raises(ExtractError, match="cannot load: axes.hp: min and max are both"):
        extract_song(song_wav, str(output), n_fft=N_FFT, hop_length=HOP)
    assert os.listdir(tmp_path) == []


def test_block_writer_with_the_contract_refuses_a_bad_block_and_leaves_nothing(tmp_path):
    output = tmp_path / "out.ply"
    good = np.zeros((4, 5), np.float32)
    bad = good.copy()
    bad[2, 0] = 1.5  # x outside [-1, 1]
    axes = {name: {"min": 0.0, "max": 1.0} for name in ("x", "y", "z", "scalar", "hp")}
    metadata = {"point_count": 8, "axes": axes}
    with pytest.raises(ExtractError, match="column x leaves"):
        write_ply_blocks(
            output,
            n_points=8,
            metadata=metadata,
            blocks=checked_blocks([good, bad], metadata, n_points=8, path=str(output)),
        )
    with pytest.raises(ExtractError, match="point_count 8 is not 9"):
        write_ply_blocks(
            output,
            n_points=9,
            metadata=metadata,
            blocks=checked_blocks([good, good], metadata, n_points=9, path=str(output)),
        )
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("fmt, name, keep", [("WAV", "cut.wav", 0.6), ("FLAC", "cut.flac", -100)])
def test_streamed_decode_of_a_truncated_file_warns_or_fails_with_strict(tmp_path, fmt, name, keep):
    y = musical_signal(sample_rate=SR, duration_s=6.0) * 0.5
    source = tmp_path / name
    soundfile.write(str(source), np.stack([y, y], axis=1).astype(np.float32), SR, format=fmt)
    data = source.read_bytes()
    source.write_bytes(data[: int(len(data) * keep) if keep > 0 else keep])
    whole = decode_audio(source)
    assert whole.warning.startswith("truncated or corrupt audio: decoded ")
    # Default blocks read the file at the offsets decode_audio reads: the same samples and
    # the same warning.
    track = stream_track(str(source), n_fft=N_FFT, hop_length=HOP)
    assert track.warning == whole.warning
    assert track.n_samples == whole.n_samples
    # Blocks of 1000 samples: the short end is found across many blocks and both passes.
    small = stream_track(str(source), n_fft=N_FFT, hop_length=HOP, block_samples=1000)
    assert small.warning.startswith("truncated or corrupt audio: decoded ")
    assert "of the 6.00 s the file promises" in small.warning
    assert whole.n_samples <= small.n_samples < 6 * SR
    warnings_seen = []
    output = tmp_path / "out.ply"
    extract_song(
        str(source),
        str(output),
        n_fft=N_FFT,
        hop_length=HOP,
        warn=warnings_seen.append,
    )
    assert warnings_seen == [f"{source}: {whole.warning}"]
    assert output.exists()
    output.unlink()
    with pytest.raises(ExtractError, match="truncated or corrupt audio.*without --strict"):
        extract_song(str(source), str(output), n_fft=N_FFT, hop_length=HOP, strict=True)
    assert not output.exists()


@pytest.mark.parametrize("block", [700, 40000, 100000])
def test_one_true_peak_pass_gives_the_decoded_signals_peak_too(block):
    from loudscape_extract.stream_decode import _StreamTruePeak

    rng = np.random.default_rng(5)
    clean = (0.3 * rng.standard_normal((2, 150000))).astype(np.float32)
    clean[:, :200] *= 3.0  # loud start: the partial windows there decide the peak
    offsets = np.array([0.31, -0.02], dtype=np.float32)
    decoded = clean + offsets[:, None]
    shared = _StreamTruePeak(2, offsets=offsets)
    alone_clean, alone_decoded = _StreamTruePeak(2), _StreamTruePeak(2)
    for start in range(0, clean.shape[1], block):
        s0, peak, offset_peak = shared.feed(clean[:, start : start + block])
        s1, expected, _ = alone_clean.feed(clean[:, start : start + block])
        s2, expected_decoded, none = alone_decoded.feed(decoded[:, start : start + block])
        assert s0 == s1 == s2 and none is None
        np.testing.assert_allclose(peak, expected, rtol=0, atol=0)
        np.testing.assert_allclose(offset_peak, expected_decoded, rtol=1e-5, atol=1e-6)
