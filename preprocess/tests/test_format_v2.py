"""Format version 2: metadata in short comment lines, non-UTF-8 paths kept losslessly."""

import base64
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import soundfile

from loudscape_extract import ExtractError
from loudscape_extract.ply import (
    MAX_LINE_BYTES,
    encode_metadata,
    read_ply,
    read_ply_metadata,
    write_ply,
)

from conftest import musical_signal
from test_ply import tiny_read


def big_metadata(n_songs):
    songs = [
        {
            "path": f"music/Artist {i % 97}/Album {i % 13}/{i:05d} A song title, with spaces.flac",
            "year": 1950 + i % 70,
            "title": f"A song title {i} \u00e9\u266b",
            "artist": f"Artist {i % 97}",
            "point_offset": i * 1024,
            "point_count": 1024,
            "metrics": {"integrated_lufs": -14.1234, "lra_lu": None, "hp_mean": 0.5},
        }
        for i in range(n_songs)
    ]
    return {"mode": "timeline", "point_count": 1024 * n_songs, "songs": songs}


def header_lines(path):
    data = open(path, "rb").read()
    return data[: data.index(b"end_header\n") + len(b"end_header\n")].split(b"\n")[:-1]


def test_every_header_line_is_short_and_the_chunks_rebuild_the_json(tmp_path):
    meta = big_metadata(300)
    path = tmp_path / "t.ply"
    write_ply(path, points=np.zeros((2, 5), np.float32), metadata=meta)
    lines = header_lines(path)
    assert max(len(line) + 1 for line in lines) <= MAX_LINE_BYTES
    parts = [line.split(b" ") for line in lines if line.startswith(b"comment loudscape-meta-v2 ")]
    assert len(parts) > 100
    assert all(len(p) == 4 for p in parts)  # no whitespace inside a chunk
    assert all(len(p[3]) == 900 for p in parts[:-1]) and 1 <= len(parts[-1][3]) <= 900
    text = b"".join(p[3] for p in parts)
    assert all(0x21 <= b <= 0x7E for b in text)
    assert json.loads(text) == {**meta, "format_version": 2}
    assert read_ply(path)[1] == {**meta, "format_version": 2} == read_ply_metadata(path)
    assert tiny_read(path)[1]["songs"][299]["title"] == "A song title 299 \u00e9\u266b"


def test_non_utf8_path_is_valid_json_and_round_trips(tmp_path):
    name = os.fsdecode(b"caf\xe9 \xff.wav")  # a Latin-1 file name, as os.listdir returns it
    meta = {
        "mode": "song",
        "source": {"path": name},
        "labels": [name],
    }
    path = tmp_path / "s.ply"
    write_ply(path, points=np.zeros((1, 5), np.float32), metadata=meta)
    _, raw, _ = tiny_read(path)  # json.loads of the file's bytes: strict JSON
    assert raw["source"]["path"] == "caf\ufffd \ufffd.wav"
    assert base64.b64decode(raw["source"]["path_bytes_b64"]) == b"caf\xe9 \xff.wav"
    assert raw["labels"] == ["caf\ufffd \ufffd.wav"]  # outside a dict value: replaced only
    header = open(path, "rb").read().split(b"end_header")[0]
    assert b"\\udc" not in header.lower()
    read = read_ply(path)[1]
    assert read["source"] == {"path": name}
    assert os.fsencode(read["source"]["path"]) == b"caf\xe9 \xff.wav"


def test_surrogates_no_file_name_has_are_replaced():
    assert encode_metadata({"a": "x\ud800y"}) == {"a": "x\ufffdy"}
    with pytest.raises(ExtractError, match="path_bytes_b64"):
        encode_metadata({"path": "\udcff", "path_bytes_b64": "AA=="})


def broken(tmp_path, lines):
    body = b"\n".join(
        [b"ply", b"format binary_little_endian 1.0", *lines, b"element vertex 0"]
        + [b"property float " + p for p in (b"x", b"y", b"z", b"scalar", b"hp")]
        + [b"end_header", b""]
    )
    path = tmp_path / "b.ply"
    path.write_bytes(body)
    return path


@pytest.mark.parametrize(
    ("lines", "reason"),
    [
        ([b'comment loudscape-meta-v2 2/2 "b"}', b'comment loudscape-meta-v2 1/2 {"a":'], "order"),
        ([b'comment loudscape-meta-v2 1/2 {"a":1'], "has 1 of 2 parts"),
        ([b"comment loudscape-meta-v2 1/1 {} x"], "I/N CHUNK"),
        ([b"comment loudscape-meta-v2 01/1 {}"], "I/N CHUNK"),
        ([b'comment loudscape-meta-v2 1/1 {"a":}'], "bad loudscape-meta JSON"),
        ([b"comment loudscape-meta-v2 1/1 [1]"], "not a JSON object"),
        ([b"comment loudscape-meta {}", b"comment loudscape-meta-v2 1/1 {}"], "both"),
        ([b'comment loudscape-meta-v2 1/1 {"path":"x","path_bytes_b64":"!"}'], "base64"),
    ],
)
def test_bad_v2_metadata_is_one_clear_error(tmp_path, lines, reason):
    path = broken(tmp_path, lines)
    for reader in (read_ply, read_ply_metadata):
        with pytest.raises(ExtractError, match=reason) as info:
            reader(path)
        assert str(path) in str(info.value)


def test_other_comments_and_order_of_parts(tmp_path):
    path = broken(
        tmp_path,
        [
            b'comment loudscape-meta-v2 1/2 {"a":',
            b"comment made by hand",
            b"comment loudscape-meta-v2 2/2 1}",
        ],
    )
    assert read_ply(path)[1] == {"a": 1} == read_ply_metadata(path)


def test_timeline_with_a_non_utf8_file_name(tmp_path):
    folder = tmp_path / "music"
    folder.mkdir()
    y = musical_signal(sample_rate=8000, duration_s=1.0).astype(np.float32)
    good = folder / "good.flac"
    soundfile.write(str(good), y, 8000)
    import mutagen.flac

    tags = mutagen.flac.FLAC(str(good))
    tags["date"] = "1999"
    tags.save()
    bad_name = os.path.join(os.fsencode(folder), b"no year \xe9.flac")
    soundfile.write(str(folder / "tmp.flac"), y, 8000)  # no tags: skipped, path in the metadata
    os.rename(os.fsencode(folder / "tmp.flac"), bad_name)
    out = tmp_path / "t.ply"
    # A child process: its stderr writes the undecodable name with backslashreplace, as a
    # terminal's does (pytest's captured stderr would refuse it).
    args = ["timeline", str(folder), "-o", str(out), "--no-cache", "--jobs", "1"]
    done = subprocess.run(
        [sys.executable, "-m", "loudscape_extract.cli", *args, "--n-fft", "256", "--hop", "128"],
        capture_output=True,
    )
    assert done.returncode == 0, done.stderr
    assert b"no year \\udce9.flac: no year in its tags" in done.stderr
    _, raw, points = tiny_read(out)
    skipped = raw["extraction"]["skipped"]
    assert len(skipped) == 1
    assert base64.b64decode(skipped[0]["path_bytes_b64"]) == bad_name
    assert skipped[0]["path"] == os.fsdecode(bad_name).encode("utf-8", "surrogateescape").decode(
        "utf-8", "replace"
    )
    meta = read_ply(out)[1]
    assert os.fsencode(meta["extraction"]["skipped"][0]["path"]) == bad_name
    assert points.shape[0] == meta["point_count"] > 0
