import json
import os

import numpy as np
import pytest

from loudscape_extract import ExtractError, read_ply, read_ply_metadata, write_ply


def tiny_read(path):
    """An independent little PLY reader: header lines, metadata (versions 1 and 2) and records."""
    with open(path, "rb") as handle:
        data = handle.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    v1 = [line.split(" ", 2)[2] for line in header if line.startswith("comment loudscape-meta ")]
    v2 = [line.split(" ") for line in header if line.startswith("comment loudscape-meta-v2 ")]
    assert not (v1 and v2)
    if v2:
        assert [part[2] for part in v2] == [f"{i}/{len(v2)}" for i in range(1, len(v2) + 1)]
        metadata = json.loads("".join(part[3] for part in v2))
    else:
        metadata = json.loads(v1[0])
    count = int([line for line in header if line.startswith("element vertex")][0].split()[2])
    records = np.frombuffer(data[end:], dtype="<f4").reshape(count, 5)
    return header, metadata, records


def test_round_trip(tmp_path, rng):
    points = rng.uniform(-1, 1, (17, 5)).astype(np.float32)
    metadata = {"format_version": 2, "mode": "song", "point_count": 17, "note": "caf\u00e9\nx y"}
    path = tmp_path / "cloud.ply"
    write_ply(path, points=points, metadata=metadata)
    header, read_metadata, records = tiny_read(path)
    assert header[:2] == ["ply", "format binary_little_endian 1.0"]
    assert header[2].startswith("comment loudscape-meta-v2 1/1 {")
    assert header[3:] == [
        "element vertex 17",
        "property float x",
        "property float y",
        "property float z",
        "property float scalar",
        "property float hp",
        "end_header",
    ]
    assert read_metadata == metadata
    assert read_ply(path)[1] == metadata == read_ply_metadata(path)
    np.testing.assert_array_equal(records, points)
    np.testing.assert_array_equal(read_ply(path)[0], points)
    assert os.path.getsize(path) == len("\n".join(header)) + 1 + 17 * 20
    assert [p.name for p in tmp_path.iterdir()] == ["cloud.ply"]  # no temporary left behind


def test_version_1_is_still_written_and_read(tmp_path, rng):
    points = rng.uniform(-1, 1, (3, 5)).astype(np.float32)
    path = tmp_path / "v1.ply"
    write_ply(path, points=points, metadata={"mode": "song", "x": "a b"}, format_version=1)
    header, metadata, _ = tiny_read(path)
    assert header[2] == 'comment loudscape-meta {"mode":"song","x":"a\\u0020b","format_version":1}'
    assert metadata == {"mode": "song", "x": "a b", "format_version": 1}
    assert read_ply(path)[1] == metadata == read_ply_metadata(path)


def test_failed_write_leaves_no_file(tmp_path):
    path = tmp_path / "cloud.ply"
    with pytest.raises(ValueError):
        write_ply(path, points=np.zeros((2, 5)), metadata={"bad": float("nan")})
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ExtractError, match="does not exist"):
        write_ply(tmp_path / "missing" / "c.ply", points=np.zeros((2, 5)), metadata={})
