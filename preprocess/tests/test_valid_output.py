"""Every file a command writes is one the app loads: the degenerate cases, written and checked
with the Python reader and the loader's rules (tests/loader_rules.py), or refused unwritten."""

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.contract import check_cloud, spread_range
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import read_ply

from conftest import musical_signal
from loader_rules import loader_problems, no_null

RATE = 8000


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def assert_loads(path):
    points, metadata = read_ply(path)
    assert loader_problems(path) == []
    assert points.shape == (metadata["point_count"], 5)
    return points, metadata


def test_one_kept_frame_gets_half_a_hop_either_side(tmp_path, capsys):
    # hop == n_fft: frames do not overlap, so a 50-sample burst around sample 1024 is heard
    # by frame 4 only (it spans samples 896..1152).
    y = np.zeros(RATE, np.float32)
    y[1000:1050] = 0.5 * np.sin(np.arange(50))
    source, out = tmp_path / "one.wav", tmp_path / "one.ply"
    soundfile.write(source, y, RATE)
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 256], capsys)
    assert status == 0, err
    points, metadata = assert_loads(out)
    assert metadata["stft"]["frames_kept"] == 1
    x = metadata["axes"]["x"]
    assert x["min"] == pytest.approx(4 * 256 / RATE - 128 / RATE)
    assert x["max"] == pytest.approx(4 * 256 / RATE + 128 / RATE)
    assert np.all(points[:, 0] == 0)  # the middle of the axis: the frame's own time


def test_one_level_everywhere_gets_half_a_db_either_side():
    assert spread_range(-20.0, -20.0, 0.5) == (-20.5, -19.5)
    assert spread_range(-20.0, -19.0, 0.5) == (-20.0, -19.0)
    # Equal once rounded to the metadata's 6 decimals counts as equal.
    assert spread_range(1.0, 1.0 + 1e-8, 0.5)[1] - spread_range(1.0, 1.0 + 1e-8, 0.5)[0] == 1.0


def square_wave(path, *, seconds=10.0):
    # |sample| is constant: every frame but the zero-padded first and last has peak == RMS,
    # crest 0 dB, so the 1st and 99th percentiles are equal: a constant z.
    y = np.where((np.arange(int(RATE * seconds)) // 20) % 2 == 0, 0.5, -0.5)
    soundfile.write(path, y.astype(np.float32), RATE)


@pytest.mark.parametrize("x_by", ["order", "year"])
def test_one_song_and_constant_crest(tmp_path, capsys, x_by):
    square_wave(tmp_path / "square.wav")
    (tmp_path / "songs.csv").write_text("path,year\nsquare.wav,1990\n")
    out = tmp_path / "t.ply"
    argv = ["timeline", "--manifest", tmp_path / "songs.csv", "-o", out, "--no-cache"]
    # The frame crest of a square wave is constant (PSR, the default z, varies a little).
    argv += ["--z-measure", "crest-frame"]
    status, err = run([*argv, "--x-by", x_by, "--n-fft", 256, "--hop", 128], capsys)
    assert status == 0, err
    points, metadata = assert_loads(out)
    assert metadata["axes"]["x"]["min"] == 1990 and metadata["axes"]["x"]["max"] == 1991
    z = metadata["axes"]["z"]
    assert z["max"] - z["min"] == pytest.approx(1.0)  # half a dB either side of the crest
    assert np.all(points[:, 2] == 0)


def test_x_by_order_with_one_year(tmp_path, capsys):
    for i in range(3):
        y = musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5
        soundfile.write(tmp_path / f"s{i}.wav", y.astype(np.float32), RATE)
    (tmp_path / "songs.csv").write_text("path,year\ns0.wav,2001\ns1.wav,2001\ns2.wav,2001\n")
    out = tmp_path / "t.ply"
    argv = ["timeline", "--manifest", tmp_path / "songs.csv", "-o", out, "--no-cache"]
    status, err = run([*argv, "--x-by", "order", "--n-fft", 256, "--hop", 128], capsys)
    assert status == 0, err
    _, metadata = assert_loads(out)
    assert (metadata["axes"]["x"]["min"], metadata["axes"]["x"]["max"]) == (2001, 2002)


def test_hot_float_wav_is_written_finite(tmp_path, capsys):
    y = 10.0 * musical_signal(sample_rate=RATE, duration_s=2.0)  # peaks near +26 dBFS
    source, out = tmp_path / "hot.wav", tmp_path / "hot.ply"
    soundfile.write(source, y.astype(np.float32), RATE, subtype="FLOAT")
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128], capsys)
    assert status == 0, err
    _, metadata = assert_loads(out)
    assert no_null(metadata["axes"]) == []
    assert metadata["metrics"]["sample_peak_dbfs"] > 20


@pytest.mark.parametrize("value", [1e30, 3e38, -1e5])
def test_absurd_float_wav_is_refused_unwritten(tmp_path, capsys, value):
    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    y[RATE // 2] = value
    source, out = tmp_path / "absurd.wav", tmp_path / "absurd.ply"
    soundfile.write(source, y.astype(np.float32), RATE, subtype="FLOAT")
    status, err = run(["song", source, "-o", out], capsys)
    assert status == 1 and not out.exists()
    assert err.count("\n") == 1 and "beyond +/-1000" in err and "0.500 s" in err
    manifest = tmp_path / "songs.csv"
    manifest.write_text("path,year\nabsurd.wav,1999\n")
    timeline_out = tmp_path / "t.ply"
    status, err = run(
        ["timeline", "--manifest", manifest, "-o", timeline_out, "--no-cache"], capsys
    )
    assert status == 1 and not timeline_out.exists() and "beyond +/-1000" in err


def test_check_cloud_refuses_what_the_loader_refuses():
    good_axis = {"min": 0.0, "max": 1.0, "scale": "linear"}
    metadata = {
        "point_count": 1,
        "axes": {name: dict(good_axis) for name in "x y z scalar hp".split()},
    }
    points = np.zeros((1, 5), np.float32)
    check_cloud(points, metadata)
    cases = [
        (points, {**metadata, "point_count": 2}, "point_count"),
        (points + np.array([2, 0, 0, 0, 0], np.float32), metadata, "column x"),
        (points + np.array([0, 0, 0, np.nan, 0], np.float32), metadata, "column scalar"),
        (points, {**metadata, "axes": {**metadata["axes"], "y": {"min": 3, "max": 3}}}, "both 3"),
        (points, {**metadata, "axes": {**metadata["axes"], "z": {"min": None, "max": 1}}}, "z"),
        (points, {**metadata, "extra": float("inf")}, "plain JSON"),
        (
            points,
            {**metadata, "axes": {**metadata["axes"], "z": {"min": 0, "max": 9, "scale": "log"}}},
            "log axis",
        ),
    ]
    for bad_points, bad_metadata, expected in cases:
        with pytest.raises(ExtractError, match=expected):
            check_cloud(bad_points, bad_metadata, path="c.ply")
