import json
import os

import numpy as np
import pytest

from loudscape_extract import ExtractError, write_ply


def tiny_read(path):
    """An independent little PLY reader: header lines, metadata and records."""
    with open(path, "rb") as handle:
        data = handle.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    meta_line = [line for line in header if line.startswith("comment loudscape-meta ")]
    metadata = json.loads(meta_line[0].split(" ", 2)[2])
    count = int([line for line in header if line.startswith("element vertex")][0].split()[2])
    records = np.frombuffer(data[end:], dtype="<f4").reshape(count, 5)
    return header, metadata, records


def test_round_trip(tmp_path, rng):
    points = rng.uniform(-1, 1, (17, 5)).astype(np.float32)
    metadata = {"format_version": 1, "mode": "song", "point_count": 17, "note": "caf\u00e9\nx"}
    path = tmp_path / "cloud.ply"
    write_ply(path, points=points, metadata=metadata)
    header, read_metadata, records = tiny_read(path)
    assert header[:3] == ["ply", "format binary_little_endian 1.0", header[2]]
    assert header[2].startswith("comment loudscape-meta {")
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
    np.testing.assert_array_equal(records, points)
    assert os.path.getsize(path) == len("\n".join(header)) + 1 + 17 * 20
    assert [p.name for p in tmp_path.iterdir()] == ["cloud.ply"]  # no temporary left behind


def test_failed_write_leaves_no_file(tmp_path):
    path = tmp_path / "cloud.ply"
    with pytest.raises(ValueError):
        write_ply(path, points=np.zeros((2, 5)), metadata={"bad": float("nan")})
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ExtractError, match="does not exist"):
        write_ply(tmp_path / "missing" / "c.ply", points=np.zeros((2, 5)), metadata={})
