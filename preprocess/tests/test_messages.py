"""Messages: one line of at most a few hundred characters on every path, honest reasons, no
library noise, non-regular inputs refused at once, and the same 'wrote PATH (N points, ...)'
summaries with or without a terminal (-q silences them)."""

import json
import os
import re
import subprocess
import sys
import time

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.messages import MAX_MESSAGE_CHARS, one_line
from loudscape_extract.ply import read_ply, write_ply

from conftest import musical_signal

RATE = 8000
CLI = [sys.executable, "-m", "loudscape_extract.cli"]


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def assert_one_line(err):
    assert err.count("\n") == 1 and err.endswith("\n"), err
    assert len(err) <= MAX_MESSAGE_CHARS + 1
    assert "Traceback" not in err and "internal error" not in err


def test_one_line_collapses_escapes_and_caps():
    assert one_line("a\n  b\tc") == "a b c"
    assert one_line("bell\x07") == "bell\\x07"
    long = one_line("x" * 10_000)
    assert len(long) == MAX_MESSAGE_CHARS and long.endswith("...")


def timeline_cloud(tmp_path, capsys):
    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    soundfile.write(tmp_path / "s.wav", y.astype(np.float32), RATE)
    (tmp_path / "m.csv").write_text("path,year\ns.wav,1990\n")
    out = tmp_path / "t.ply"
    argv = ["timeline", "--manifest", tmp_path / "m.csv", "-o", out, "--no-cache"]
    assert run([*argv, "--n-fft", 256, "--hop", 128], capsys)[0] == 0
    return out


@pytest.mark.parametrize("version", [1, 2])
def test_report_on_mutated_clouds_answers_in_one_line(tmp_path, capsys, version):
    points, metadata = read_ply(timeline_cloud(tmp_path, capsys))
    write_ply(tmp_path / "good.ply", points=points, metadata=metadata, format_version=version)
    good = (tmp_path / "good.ply").read_bytes()
    if version == 2:
        # The mutations below are spelled on the one-line layout; version 2 files get the
        # byte-level mutations and the truncations.
        good_v1 = tmp_path / "good_v1.ply"
        write_ply(good_v1, points=points, metadata=metadata, format_version=1)
        meta = metadata
    else:
        good_v1 = None
    end = good.index(b"end_header\n")
    if good_v1 is None:
        meta_start = good.index(b"comment loudscape-meta ") + len(b"comment loudscape-meta ")
        meta = json.loads(good[meta_start : good.index(b"\n", meta_start)])
    variants = [
        b"",
        b"ply\n",
        good[:end],
        good.replace(b"comment loudscape-meta {", b"comment loudscape-meta {\n", 1),
        good.replace(b'"mode":"timeline"', b'"mode":{"a":"' + b"x" * 5000 + b'"}', 1),
        good.replace(b'"songs":[', b'"songs":[7,', 1),
        good.replace(b'"year":1990', b'"year":"1990\\n1991"', 1),
        good.replace(b'"metrics":{', b'"metrics":{"lra_lu":"bad","x":[1],', 1),
        b"ply\nformat binary_little_endian 1.0\ncomment loudscape-meta "
        + json.dumps(json.dumps(meta, indent=2)).encode()
        + b"\nend_header\n",
        b"ply\nformat binary_little_endian 1.0\ncomment loudscape-meta [1,2]\nend_header\n",
    ]
    rng = np.random.default_rng(7)
    for _ in range(40):
        data = bytearray(good[: end + 11])
        for position in rng.integers(0, len(data), size=4):
            data[position] = int(rng.integers(0, 256))
        variants.append(bytes(data))
    for index, data in enumerate(variants):
        cloud = tmp_path / f"v{index}.ply"
        cloud.write_bytes(data)
        status, err = run(["report", cloud, "-o", tmp_path / "r.png", "-q"], capsys)
        if status == 0:
            assert err == ""
        else:
            assert status == 1
            assert_one_line(err)


def test_long_echoed_values_are_shortened(tmp_path, capsys):
    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    soundfile.write(tmp_path / "s.wav", y.astype(np.float32), RATE)
    (tmp_path / "m.csv").write_text("path,year\ns.wav," + "9" * 5000 + "x\n")
    status, err = run(
        ["timeline", "--manifest", tmp_path / "m.csv", "-o", tmp_path / "t.ply"], capsys
    )
    assert status == 1 and "line 2" in err
    assert_one_line(err)


def test_missing_file_reports_its_os_error_once(tmp_path, capsys):
    for command in ("song", "report"):
        status, err = run([command, tmp_path / "missing.wav"], capsys)
        assert status == 1
        assert_one_line(err)
        assert err.count("no such file") == 1


def test_a_regular_file_libsndfile_cannot_open_gets_an_honest_reason(tmp_path, capsys):
    for name, data in (("noise.mp3", bytes(range(256)) * 40), ("text.wav", b"hello\n" * 100)):
        (tmp_path / name).write_bytes(data)
        status, err = run(["song", tmp_path / name, "-o", tmp_path / "o.ply"], capsys)
        assert status == 1
        assert_one_line(err)
        assert "does not exist" not in err and "not a regular file" not in err
        assert "does not recognize the data as audio" in err or "corrupt" in err


def test_song_on_a_fifo_is_refused_at_once(tmp_path):
    fifo = tmp_path / "pipe.wav"
    os.mkfifo(fifo)
    for argv in (["song", str(fifo)], ["timeline", str(fifo), "-o", str(tmp_path / "t.ply")]):
        start = time.monotonic()
        result = subprocess.run([*CLI, *argv], capture_output=True, text=True, timeout=30)
        assert time.monotonic() - start < 20
        assert result.returncode == 1 and "FIFO" in result.stderr
        assert_one_line(result.stderr)


def test_fifo_in_a_folder_is_passed_over_and_reported(tmp_path, capsys):
    import mutagen.flac

    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    soundfile.write(tmp_path / "s.flac", y.astype(np.float32), RATE)
    tags = mutagen.flac.FLAC(tmp_path / "s.flac")
    tags["date"] = "1990"
    tags.save()
    os.mkfifo(tmp_path / "pipe.flac")
    status, err = run(["timeline", tmp_path, "-o", tmp_path / "t.ply", "--no-cache", "-q"], capsys)
    # Not read (it would block), but said: a song the user meant may be missing.
    assert status == 1 and (tmp_path / "t.ply").exists()
    assert f"skipped: {tmp_path / 'pipe.flac'}: not a regular file: a FIFO" in err


@pytest.mark.parametrize("quiet", [False, True])
def test_wrote_summaries_without_a_terminal(tmp_path, quiet):
    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    soundfile.write(tmp_path / "s.wav", y.astype(np.float32), RATE)
    (tmp_path / "m.csv").write_text("path,year\ns.wav,1990\n")
    q = ["-q"] if quiet else []
    commands = [
        (["song", "s.wav", "-o", "s.ply", *q], r"wrote s.ply \(\d+ points, 8 of 8 frames, "),
        (
            [
                "timeline",
                "--manifest",
                "m.csv",
                "-o",
                "t.ply",
                "--no-cache",
                "--frames-per-song",
                "8",
                *q,
            ],
            r"wrote t.ply \(8 points, 1 song\(s\), 0 from cache, ",
        ),
        (
            ["report", "t.ply", "-o", "r.png", "--csv", "r.csv", *q],
            r"wrote r.png \(1 song\(s\), 1 year\(s\)\)",
        ),
    ]
    for argv, pattern in commands:
        result = subprocess.run(
            [*CLI, *argv], cwd=tmp_path, capture_output=True, text=True, timeout=120
        )
        assert result.returncode == 0 and result.stdout == "", result.stderr
        if quiet:
            assert result.stderr == ""
        else:
            first = result.stderr.splitlines()[0]
            assert re.match("loudscape-extract: " + pattern, first), result.stderr
            assert len(first) < 200
    assert (tmp_path / "r.csv").read_text().startswith("year,songs,")
