"""No command writes over its input: same path, symbolic or hard link, default output; output
extensions checked; all refused with one line before any work."""

import os
import subprocess
import sys

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main

from conftest import musical_signal

RATE = 8000


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def write_wav(path, seconds=1.0):
    y = musical_signal(sample_rate=RATE, duration_s=seconds) * 0.5
    soundfile.write(str(path), y.astype(np.float32), RATE, format="WAV")
    return path.read_bytes()


def assert_refused(status, err, *needles):
    assert status == 1, err
    assert err.count("\n") == 1 and err.startswith("loudscape-extract: error: ")
    for needle in needles:
        assert needle in err


def test_song_output_is_input_through_path_symlink_and_hard_link(tmp_path, capsys):
    source = tmp_path / "a.ply"  # a WAV named .ply: the default output is the input
    data = write_wav(source)
    (tmp_path / "link.ply").symlink_to(source)
    os.link(source, tmp_path / "hard.ply")
    for argv in (
        ["song", source],
        ["song", source, "-o", source],
        ["song", source, "-o", tmp_path / "link.ply"],
        ["song", source, "-o", tmp_path / "hard.ply"],
        ["song", tmp_path / "link.ply", "-o", source],
        ["song", source, "-o", tmp_path / "sub" / ".." / "a.ply"],
    ):
        (tmp_path / "sub").mkdir(exist_ok=True)
        status, err = run(argv, capsys)
        assert_refused(status, err, "refusing to write over an input")
        assert source.read_bytes() == data


def test_song_default_output_beside_a_wav_is_fine(tmp_path, capsys):
    source = tmp_path / "a.wav"
    write_wav(source)
    status, err = run(["song", source, "--n-fft", 256, "--hop", 128], capsys)
    assert status == 0 and (tmp_path / "a.ply").is_file(), err


@pytest.mark.parametrize("name", ["a.wav", "a.png", "a", "a.ply.tmp"])
def test_song_output_extension(tmp_path, capsys, name):
    source = tmp_path / "in.wav"
    write_wav(source)
    status, err = run(["song", source, "-o", tmp_path / name], capsys)
    assert_refused(status, err, "output must end with .ply")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.wav"]


def test_timeline_output_is_one_of_its_songs_or_manifest(tmp_path, capsys):
    songs = [tmp_path / "x.ply", tmp_path / "y.wav"]  # x.ply: audio under a .ply name
    data = [write_wav(path) for path in songs]
    manifest = tmp_path / "songs.csv"
    manifest.write_text("path,year\nx.ply,1990\ny.wav,1991\n")
    status, err = run(["timeline", "--manifest", manifest, "-o", songs[0], "--no-cache"], capsys)
    assert_refused(status, err, "refusing to write over an input", "x.ply")
    status, err = run(["timeline", "--manifest", manifest, "-o", manifest, "--no-cache"], capsys)
    assert_refused(status, err)
    assert [p.read_bytes() for p in songs] == data
    assert manifest.read_text().startswith("path,year")


def test_report_outputs(tmp_path, capsys):
    cloud = tmp_path / "t.png"  # a timeline named .png, and one named .ply
    write_wav(tmp_path / "s.wav")
    (tmp_path / "m.csv").write_text("path,year\ns.wav,1990\n")
    plain = tmp_path / "t.ply"
    args = ["--no-cache", "--n-fft", 256, "--hop", 128]
    assert run(["timeline", "--manifest", tmp_path / "m.csv", "-o", plain, *args], capsys)[0] == 0
    cloud.write_bytes(plain.read_bytes())
    before = cloud.read_bytes()
    assert_refused(*run(["report", cloud, "-o", cloud], capsys), "refusing to write over")
    assert_refused(*run(["report", plain, "-o", tmp_path / "r.jpg"], capsys), "must end with .png")
    assert_refused(
        *run(["report", plain, "-o", tmp_path / "r.png", "--csv", tmp_path / "r.txt"], capsys),
        "must end with .csv",
    )
    assert_refused(*run(["report", plain, "-o", tmp_path / "r.png", "--csv", plain], capsys))
    assert cloud.read_bytes() == before and not (tmp_path / "r.png").exists()


def test_output_that_is_a_fifo_or_directory(tmp_path, capsys):
    source = tmp_path / "in.wav"
    write_wav(source)
    os.mkfifo(tmp_path / "pipe.ply")
    (tmp_path / "dir.ply").mkdir()
    assert_refused(*run(["song", source, "-o", tmp_path / "pipe.ply"], capsys), "FIFO")
    assert_refused(*run(["song", source, "-o", tmp_path / "dir.ply"], capsys), "directory")


def test_refused_before_any_work_in_a_real_process(tmp_path):
    # A long input: refusing must not decode it first.
    source = tmp_path / "long.ply"
    data = write_wav(source, seconds=120.0)
    result = subprocess.run(
        [sys.executable, "-m", "loudscape_extract.cli", "song", str(source)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 1 and result.stdout == ""
    assert result.stderr.count("\n") == 1 and "refusing to write over an input" in result.stderr
    assert source.read_bytes() == data
