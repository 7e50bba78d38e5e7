"""tests/fixtures/format/ must be what the writer writes today, and say what it holds."""

import base64
import json
import os

import numpy as np

from loudscape_extract.ply import MAX_LINE_BYTES, read_ply, read_ply_metadata
from loudscape_fixtures.formats import (
    NON_UTF8_SKIPPED_PATH,
    NON_UTF8_SONG_PATH,
    NON_UTF8_TIMELINE_PATH,
    write_format_fixtures,
)

from test_ply import tiny_read

FIXTURES = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "fixtures", "format")


def test_committed_fixtures_are_a_fresh_run_byte_for_byte(tmp_path):
    written = write_format_fixtures(str(tmp_path))
    names = sorted(os.path.basename(p) for p in written)
    assert names == sorted(os.listdir(FIXTURES))
    for name in names:
        with open(tmp_path / name, "rb") as fresh, open(os.path.join(FIXTURES, name), "rb") as old:
            assert fresh.read() == old.read(), name


def test_versions_1_and_2_hold_the_same_cloud():
    for kind in ("song", "timeline"):
        p1, m1 = read_ply(os.path.join(FIXTURES, f"{kind}_v1.ply"))
        p2, m2 = read_ply(os.path.join(FIXTURES, f"{kind}_v2.ply"))
        np.testing.assert_array_equal(p1, p2)
        assert m1.pop("format_version") == 1 and m2.pop("format_version") == 2
        assert m1 == m2 and m1["mode"] == kind


def test_expected_json_describes_each_fixture():
    for name in sorted(os.listdir(FIXTURES)):
        if not name.endswith(".ply"):
            continue
        path = os.path.join(FIXTURES, name)
        with open(path.removesuffix(".ply") + ".expected.json") as handle:
            expected = json.load(handle)
        header, raw, points = tiny_read(path)
        assert expected["metadata"] == raw
        assert expected["point_count"] == points.shape[0] == raw["point_count"]
        assert expected["first_records"] == points[:3].tolist()
        assert expected["last_records"] == points[-3:].tolist()
        assert expected["header_bytes"] == os.path.getsize(path) - points.nbytes
        v2 = [line for line in header if line.startswith("comment loudscape-meta-v2 ")]
        assert expected["meta_v2_lines"] == len(v2)
        assert (len(v2) == 0) == ("_v1" in name)
        if "_v2" in name:
            assert max(len(line) + 1 for line in header) <= MAX_LINE_BYTES


def test_non_utf8_fixtures_hold_the_exact_bytes():
    song = tiny_read(os.path.join(FIXTURES, "song_v2_non_utf8.ply"))[1]
    assert base64.b64decode(song["source"]["path_bytes_b64"]) == NON_UTF8_SONG_PATH
    assert song["source"]["path"] == "data/caf\ufffd \ufffd.wav"
    timeline = read_ply_metadata(os.path.join(FIXTURES, "timeline_v2_non_utf8.ply"))
    assert os.fsencode(timeline["songs"][1]["path"]) == NON_UTF8_TIMELINE_PATH
    assert os.fsencode(timeline["extraction"]["skipped"][0]["path"]) == NON_UTF8_SKIPPED_PATH
    assert "path_bytes_b64" not in timeline["songs"][1]


def test_large_timeline_fixture(tmp_path):
    ply, expected_json = write_format_fixtures(str(tmp_path), large=True)
    header, raw, points = tiny_read(ply)
    assert len(raw["songs"]) == 10_000 and points.shape == (80_000, 5)
    header_bytes = len("\n".join(header)) + 1
    assert header_bytes > 4_900_000  # at least the ~490 bytes a song of real libraries
    assert max(len(line) + 1 for line in header) <= MAX_LINE_BYTES
    assert read_ply(ply)[1] == raw == read_ply_metadata(ply)
    with open(expected_json) as handle:
        assert json.load(handle)["header_bytes"] == header_bytes
