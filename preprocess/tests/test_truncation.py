"""Truncated or corrupt audio is found and reported the same way for every format: a one-line
warning with how much was decoded, or an error with --strict; complete files stay silent."""

import os
import subprocess
import sys

import numpy as np
import pytest
import soundfile

from loudscape_extract.audio import decode_audio
from loudscape_extract.cli import main

from conftest import musical_signal

RATE = 22050
SECONDS = 8.0


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def write(path, fmt):
    y = musical_signal(sample_rate=RATE, duration_s=SECONDS) * 0.4
    soundfile.write(str(path), np.stack([y, y], axis=1).astype(np.float32), RATE, format=fmt)


def cut(path, *, keep=None, drop=None):
    data = path.read_bytes()
    size = len(data) - drop if drop else int(len(data) * keep)
    path.write_bytes(data[:size])


CASES = {
    "ogg cut at 50 %": ("a.ogg", "OGG", {"keep": 0.5}, "Ogg stream"),
    "flac missing its last 100 bytes": ("a.flac", "FLAC", {"drop": 100}, "of the 8.00 s"),
    "wav cut mid-data": ("a.wav", "WAV", {"keep": 0.6}, "of the 8.00 s"),
    "mp3 cut": ("a.mp3", "MP3", {"keep": 0.5}, "of the 8.00 s"),
}


@pytest.mark.parametrize("case", CASES)
def test_truncated_file_warns_then_strict_refuses(tmp_path, capsys, case):
    name, fmt, how, detail = CASES[case]
    source = tmp_path / name
    write(source, fmt)
    complete = decode_audio(source)
    assert complete.warning == ""
    cut(source, **how)
    audio = decode_audio(source)
    assert 0 < audio.n_samples < complete.n_samples
    assert audio.warning.startswith("truncated or corrupt audio: decoded ")
    assert detail in audio.warning

    out = tmp_path / "a.ply"
    status, err = run(["song", source, "-o", out, "--n-fft", 512, "--hop", 256], capsys)
    lines = err.splitlines()
    assert status == 0 and out.is_file()
    assert len(lines) == 2 and lines[0].startswith(f"loudscape-extract: warning: {source}: ")
    assert "truncated or corrupt audio" in lines[0] and lines[1].startswith(
        "loudscape-extract: wrote"
    )
    out.unlink()
    status, err = run(["song", source, "-o", out, "--strict"], capsys)
    assert status == 1 and not out.exists()
    assert err.count("\n") == 1 and "truncated or corrupt audio" in err and "--strict" in err


def test_complete_files_of_every_format_decode_silently(tmp_path, capsys):
    for name, fmt in (("a.ogg", "OGG"), ("a.flac", "FLAC"), ("a.wav", "WAV"), ("a.mp3", "MP3")):
        write(tmp_path / name, fmt)
        audio = decode_audio(tmp_path / name, strict=True)
        assert audio.warning == "" and audio.duration_s == pytest.approx(SECONDS, abs=0.06)


def test_timeline_warns_or_skips_a_truncated_song(tmp_path, capsys):
    write(tmp_path / "good.flac", "FLAC")
    write(tmp_path / "cut.flac", "FLAC")
    cut(tmp_path / "cut.flac", drop=100)
    (tmp_path / "songs.csv").write_text("path,year\ngood.flac,1990\ncut.flac,1991\n")
    out = tmp_path / "t.ply"
    argv = ["timeline", "--manifest", tmp_path / "songs.csv", "-o", out]
    argv += ["--cache-dir", tmp_path / "cache", "--jobs", 1]
    for _ in range(2):  # computed, then from the cache: the same warning
        status, err = run(argv, capsys)
        assert status == 0, err
        warnings = [line for line in err.splitlines() if "warning" in line]
        assert len(warnings) == 1 and "cut.flac" in warnings[0] and "truncated" in warnings[0]
    status, err = run([*argv, "--strict"], capsys)
    assert status == 1 and "skipped:" in err and "cut.flac" in err and "--strict" in err


def test_mp3_decoding_prints_no_library_noise(tmp_path):
    source = tmp_path / "a.mp3"
    write(source, "MP3")
    cut(source, keep=0.5)
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "loudscape_extract.cli",
            "song",
            str(source),
            "-o",
            str(tmp_path / "a.ply"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONWARNINGS": "error"},
    )
    assert result.returncode == 0, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 2, result.stderr
    assert all(line.startswith("loudscape-extract: ") for line in lines)
    assert "Note:" not in result.stderr and "libmpg123" not in lines[1]
