"""Odd inputs get a correct result or one clear line: file names that are not UTF-8, numeric
flags out of range, deeply nested JSON, headers over the size limit."""

import os

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import MAX_HEADER_BYTES, read_ply, read_ply_metadata
from loudscape_extract.song import extract_song

from conftest import musical_signal

RATE = 16000
FAST = ["--n-fft", "512", "--hop", "256"]
NAME = os.fsdecode(b"caf\xe9 \xff.flac")  # Latin-1 and a stray byte: not UTF-8


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def write_song(path, *, year=None):
    y = musical_signal(sample_rate=RATE, duration_s=1.5) * 0.4
    soundfile.write(os.fsencode(path), y.astype(np.float32), RATE, format="FLAC")
    if year is not None:
        import mutagen.flac

        tags = mutagen.flac.FLAC(path)
        tags["date"] = str(year)
        tags.save()


def test_non_utf8_file_name_extracts_in_both_modes(tmp_path, capsys):
    folder = tmp_path / "m"
    folder.mkdir()
    source = os.path.join(str(folder), NAME)
    write_song(source, year=1999)
    out = tmp_path / "s.ply"
    status, err = run(["song", source, "-o", out, *FAST], capsys)
    assert status == 0, err
    assert read_ply(out)[1]["source"]["path"] == source  # the exact bytes, kept
    status, err = run(["timeline", folder, "-o", tmp_path / "t.ply", "--no-cache", *FAST], capsys)
    assert status == 0, err
    assert read_ply(tmp_path / "t.ply")[1]["songs"][0]["path"] == source


@pytest.mark.parametrize(
    ("command", "flag", "value", "needle"),
    [
        ("song", "--floor-db", "1e308", "from 0 to 400"),
        ("song", "--floor-db", "inf", "from 0 to 400"),
        ("song", "--floor-db", "nan", "from 0 to 400"),
        ("song", "--n-fft", "1000000000", "from 4 to 65,536"),
        ("song", "--hop", "100000", "from 1 to 65,536"),
        ("timeline", "--frames-per-song", "0", "from 1 to 1,000,000"),
        ("timeline", "--frames-per-song", "99999999", "from 1 to 1,000,000"),
        ("timeline", "--max-points", "-1", "from 0 to"),
        ("timeline", "--max-points", "1e3", "expected an integer"),
        ("timeline", "--jobs", "99999", "from 1 to"),
        ("timeline", "--n-fft", "6.5", "expected an integer"),
        ("timeline", "--hop", "4096", "larger than --n-fft 2048"),
    ],
)
def test_numeric_flags_are_range_checked(tmp_path, capsys, command, flag, value, needle):
    with pytest.raises(SystemExit) as exit_info:
        main([command, str(tmp_path / "x.flac"), "-o", str(tmp_path / "o.ply"), flag, value])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    assert needle in err and "Traceback" not in err
    assert f"argument {flag}" in err or flag in err


def test_library_refuses_an_absurd_floor(tmp_path):
    source = tmp_path / "a.flac"
    write_song(str(source))
    with pytest.raises(ExtractError, match="floor_db must be from 0 to 400 dB"):
        extract_song(str(source), str(tmp_path / "a.ply"), floor_db=1e308)
    assert not (tmp_path / "a.ply").exists()


def header_file(path, comment_bytes, *, end=True, meta=None):
    with open(path, "wb") as handle:
        handle.write(b"ply\nformat binary_little_endian 1.0\n")
        if meta is not None:
            handle.write(b"comment loudscape-meta " + meta + b"\n")
        handle.write(b"comment " + b"x" * comment_bytes + b"\n")
        handle.write(b"element vertex 0\n")
        if end:
            handle.write(b"end_header\n")


def test_deeply_nested_json_is_a_clear_line(tmp_path, capsys):
    deep = b'{"format_version":1,"mode":"song","x":' + b"[" * 100_000 + b"]" * 100_000 + b"}"
    path = tmp_path / "deep.ply"
    header_file(path, 10, meta=deep)
    for argv in (["export", path], ["report", path, "-o", tmp_path / "r.png"]):
        status, err = run(argv, capsys)
        assert status == 1 and err.count("\n") == 1, err
        assert "nested too deeply" in err and "internal error" not in err
    with pytest.raises(ExtractError, match="nested too deeply"):
        read_ply_metadata(path)


def test_header_over_the_limit_says_too_large_not_missing(tmp_path):
    path = tmp_path / "big.ply"
    header_file(path, 5000)
    with pytest.raises(ExtractError, match="larger than the 0.00390625 MiB"):
        read_ply_metadata(path, max_header_bytes=4096)
    header_file(path, 5000, end=False)
    with pytest.raises(ExtractError, match="no 'end_header'"):
        read_ply_metadata(path, max_header_bytes=4096)
    # The real limit, with a real 65 MiB header that ends properly.
    header_file(path, MAX_HEADER_BYTES + (1 << 20))
    with pytest.raises(ExtractError, match="larger than the 64 MiB") as caught:
        read_ply_metadata(path)
    assert "without end_header" not in str(caught.value)
