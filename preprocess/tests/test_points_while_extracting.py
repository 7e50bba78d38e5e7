"""Song mode's points while extracting: the body file, the ``points`` progress lines, and an
output that stays byte for byte what the whole pipeline writes (docs/FORMAT.md)."""

from __future__ import annotations

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
import soundfile

import loudscape_extract.song as song_module
import loudscape_extract.stream as stream_module
from loudscape_extract import decode_audio, read_ply, song_metadata, song_points, track_features
from loudscape_extract.cli import main
from loudscape_extract.errors import ExtractError
from loudscape_extract.notices import track_warnings
from loudscape_extract.ply import read_ply_metadata, write_ply
from loudscape_extract.song import body_file_path, extract_song
from loudscape_extract.stream import stream_track
from loudscape_extract.version import GENERATOR

from conftest import musical_signal

REPO = pathlib.Path(__file__).resolve().parents[2]
MUSIC = pathlib.Path(os.environ.get("LOUDSCAPE_REAL_MUSIC", REPO / "data" / "real-music"))
SR = 8000
N_FFT, HOP = 256, 128


@pytest.fixture(scope="module")
def long_wav(tmp_path_factory):
    """40 s of stereo (about 2500 frames: ten blocks of the points pass), a silent start."""
    y = musical_signal(sample_rate=SR, duration_s=40.0) * 0.6
    stereo = np.stack([y, 0.7 * y], axis=1)
    stereo[:3000] = 0.0
    path = tmp_path_factory.mktemp("points") / "long.wav"
    soundfile.write(path, stereo, SR, subtype="FLOAT")
    return str(path)


@pytest.fixture(scope="module")
def music():
    script = REPO / "scripts" / "fetch-real-music.sh"
    result = subprocess.run(
        ["bash", str(script), str(MUSIC)], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, f"{script.name} failed: {result.stderr.strip()}"
    return MUSIC


def body_of(path) -> bytes:
    data = pathlib.Path(path).read_bytes()
    return data[data.index(b"end_header\n") + len(b"end_header\n") :]


def test_points_reports_grow_to_the_file_body_with_its_axes(long_wav, tmp_path, monkeypatch):
    monkeypatch.setattr(song_module, "POINTS_EVERY_S", 0.0)  # every block reports
    output = tmp_path / "song.ply"
    seen = []

    def points(update):
        data = pathlib.Path(update.path).read_bytes()  # what a reader finds at this moment
        seen.append((update, data))

    metadata = extract_song(long_wav, str(output), n_fft=N_FFT, hop_length=HOP, points=points)
    assert len(seen) >= 5
    body = body_of(output)
    rows = [update.rows for update, _ in seen]
    assert rows == sorted(rows) and len(set(rows)) == len(rows) and rows[0] > 0
    assert rows[-1] == metadata["point_count"]
    assert seen[-1][0].share == 1.0
    assert [u.share for u, _ in seen] == sorted(u.share for u, _ in seen)
    for update, data in seen:
        assert update.path == body_file_path(str(output))
        assert os.path.isabs(update.path)
        assert os.path.dirname(update.path) == str(tmp_path)
        assert os.path.basename(update.path) == f".song.ply.points-{os.getpid()}"
        assert update.axes == read_ply_metadata(output)["axes"] == metadata["axes"]
        assert update.freq_scale == "linear"
        assert len(data) == update.rows * 20
        assert data == body[: len(data)]
    assert seen[-1][1] == body  # the whole body, byte for byte
    assert os.listdir(tmp_path) == ["song.ply"]  # the body file is gone


def test_points_reports_are_throttled_but_the_last_block_always_reports(
    long_wav, tmp_path, monkeypatch
):
    monkeypatch.setattr(song_module, "POINTS_EVERY_S", 3600.0)
    seen = []
    metadata = extract_song(
        long_wav, str(tmp_path / "s.ply"), n_fft=N_FFT, hop_length=HOP, points=seen.append
    )
    assert [u.rows for u in seen][-1] == metadata["point_count"]
    assert len(seen) == 2  # the first block, then the last


def test_progress_json_prints_points_lines(long_wav, tmp_path, capsys):
    output = tmp_path / "song.ply"
    status = main(["song", long_wav, "-o", str(output), "--n-fft", str(N_FFT), "--hop",
                   str(HOP), "--freq-scale", "log", "--progress", "json"])  # fmt: skip
    assert status == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert records[-1] == {"done": str(output)}
    lines = [r for r in records if "points" in r]
    assert lines
    metadata = read_ply_metadata(output)
    for record in lines:
        assert record["stage"] == "hpss" and 0.0 < record["fraction"] < 1.0
        assert isinstance(record["message"], str)
        assert set(record["points"]) == {"path", "rows", "axes", "mode", "freq_scale"}
        assert record["points"]["path"] == body_file_path(str(output))
        assert record["points"]["axes"] == metadata["axes"]
        assert record["points"]["mode"] == "song"
        assert record["points"]["freq_scale"] == "log"
    rows = [r["points"]["rows"] for r in lines]
    assert rows == sorted(rows) and rows[-1] == metadata["point_count"]
    fractions = [r["fraction"] for r in records[:-1]]
    assert fractions == sorted(fractions)
    # The points come before the loudness pass; the file is written after it.
    stages = [r["stage"] for r in records[:-1]]
    assert stages.index("hpss") < stages.index("loudness") < stages.index("write")
    assert os.listdir(tmp_path) == ["song.ply"]


def test_without_progress_json_no_points_line(long_wav, tmp_path, capsys):
    status = main(["song", long_wav, "-o", str(tmp_path / "s.ply"), "--n-fft", str(N_FFT),
                   "--hop", str(HOP), "-q"])  # fmt: skip
    assert status == 0 and capsys.readouterr().out == ""


def previous_pipeline_bytes(source, path, *, floor_db, freq_scale, highpass_hz):
    """The file as the pipeline before points-while-extracting wrote it: stream_track's
    metadata (metrics, curves, warnings) and song_points' points, header + body."""
    track = stream_track(source, highpass_hz=highpass_hz, frame_hp=False)
    whole = track_features(decode_audio(source), highpass_hz=highpass_hz)
    cloud = song_points(whole, floor_db=floor_db, freq_scale=freq_scale)
    metadata = song_metadata(track, cloud, generator=GENERATOR, source_format=track.source_format)
    found = track_warnings(decode_warning=track.warning, metrics=track.metrics, signal=track.signal)
    if found:
        metadata["warnings"] = found
    write_ply(path, points=cloud.points, metadata=metadata)
    return pathlib.Path(path).read_bytes()


@pytest.mark.parametrize(
    "name, floor_db, freq_scale, highpass_hz",
    [
        ("demo", 80.0, "linear", None),
        ("torus-trooper-data/tt3.ogg", 80.0, "linear", None),  # DC offset and clipping warnings
        ("hex-a-hop-data/music-ending.ogg", 60.0, "log", 20.0),
    ],
)
def test_output_is_byte_for_byte_the_previous_pipelines(
    music, tmp_path, name, floor_db, freq_scale, highpass_hz
):
    source = str(REPO / "data" / "demo_song.flac") if name == "demo" else str(music / name)
    output = tmp_path / "new.ply"
    extract_song(
        source,
        str(output),
        floor_db=floor_db,
        freq_scale=freq_scale,
        highpass_hz=highpass_hz,
        warn=lambda _line: None,
    )
    expected = previous_pipeline_bytes(
        source,
        str(tmp_path / "old.ply"),
        floor_db=floor_db,
        freq_scale=freq_scale,
        highpass_hz=highpass_hz,
    )
    assert output.read_bytes() == expected
    assert read_ply(output)[0].shape[0] > 1000


class Boom(RuntimeError):
    pass


@pytest.mark.parametrize("error", [Boom, KeyboardInterrupt])
def test_body_file_removed_after_a_failure_mid_points(long_wav, tmp_path, monkeypatch, error):
    real = song_module.song_point_blocks
    output = tmp_path / "song.ply"
    body = body_file_path(str(output))
    written = []

    def failing(*args, **kwargs):
        for n, item in enumerate(real(*args, **kwargs)):
            if n == 2:
                written.append(os.path.getsize(body))  # two blocks are in the body file
                raise error("stop")
            yield item

    monkeypatch.setattr(song_module, "song_point_blocks", failing)
    with pytest.raises(error):
        extract_song(long_wav, str(output), n_fft=N_FFT, hop_length=HOP, points=lambda _u: None)
    assert written and written[0] > 0
    assert os.listdir(tmp_path) == []


def test_body_file_removed_after_a_failure_in_the_signal_pass(long_wav, tmp_path, monkeypatch):
    def failing(*_args, **_kwargs):
        raise ExtractError("the file changed while it was read (fewer samples)")

    monkeypatch.setattr(stream_module, "signal_pass", failing)
    with pytest.raises(ExtractError, match="changed while it was read") as caught:
        extract_song(long_wav, str(tmp_path / "song.ply"), n_fft=N_FFT, hop_length=HOP)
    assert caught.value.path == long_wav
    assert os.listdir(tmp_path) == []


def test_unwritable_body_file_is_one_clear_error(long_wav, tmp_path):
    output = tmp_path / "song.ply"
    os.mkdir(body_file_path(str(output)))  # something that cannot be opened as a file
    with pytest.raises(ExtractError) as caught:
        extract_song(long_wav, str(output), n_fft=N_FFT, hop_length=HOP)
    assert "cannot write file" in str(caught.value) and str(output) in str(caught.value)
    assert not output.exists()


def test_song_metadata_reads_streamed_and_whole_track_through_its_protocols(long_wav):
    from loudscape_extract.song_cloud import SongCloudFacts, SongSource
    from loudscape_extract.stream_points import StreamedCloud

    track = stream_track(long_wav, n_fft=N_FFT, hop_length=HOP, frame_hp=False)
    whole = track_features(decode_audio(long_wav), n_fft=N_FFT, hop_length=HOP)
    cloud = song_points(whole)
    streamed = StreamedCloud(
        point_count=cloud.point_count,
        axes=cloud.axes,
        frames_total=cloud.frames_total,
        frames_kept=cloud.frames_kept,
        peak_level_db=cloud.peak_level_db,
        floor_db=cloud.floor_db,
        freq_scale=cloud.freq_scale,
    )
    assert isinstance(track, SongSource) and isinstance(whole, SongSource)
    assert isinstance(cloud, SongCloudFacts) and isinstance(streamed, SongCloudFacts)
    assert not isinstance(object(), SongSource)
    a = song_metadata(track, streamed, generator=GENERATOR)
    b = song_metadata(whole, cloud, generator=GENERATOR)
    assert a.keys() == b.keys() and a["stft"] == b["stft"] and a["axes"] == b["axes"]
