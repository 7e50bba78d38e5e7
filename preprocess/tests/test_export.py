"""``loudscape-extract export``: VTK XML PolyData with scalar and hp, never over its input."""

import json
import os
import re

import numpy as np
import pytest

from loudscape_extract import export
from loudscape_extract.cli import main
from loudscape_extract.ply import write_ply


def read_vtp(path):
    """An independent reader of the raw appended layout: {array name: bytes}, attributes."""
    data = open(path, "rb").read()
    start = data.index(b"<AppendedData")
    base = data.index(b"_", start) + 1
    xml = data[:start].decode("ascii")
    assert 'header_type="UInt64"' in xml and 'byte_order="LittleEndian"' in xml
    arrays = {}
    for match in re.finditer(r'<(?:Data)?Array type="(\w+)" Name="(\w+)"[^>]*offset="(\d+)"', xml):
        kind, name, offset = match.group(1), match.group(2), int(match.group(3))
        size = int(np.frombuffer(data, "<u8", 1, base + offset)[0])
        arrays[name] = (kind, data[base + offset + 8 : base + offset + 8 + size])
    assert data.endswith(b"\n  </AppendedData>\n</VTKFile>\n")
    return xml, arrays


AXES = {n: {"min": 0.0, "max": 1.0} for n in ("x", "y", "z", "scalar", "hp")}


def cloud(tmp_path, n=9, name="c.ply"):
    points = np.random.default_rng(5).uniform(0, 1, (n, 5)).astype(np.float32)
    meta = {
        "mode": "song",
        "point_count": n,
        "axes": AXES,
        "source": {"path": os.fsdecode(b"a\xff b.wav")},
    }
    path = tmp_path / name
    write_ply(path, points=points, metadata=meta)
    return path, points


def test_export_writes_every_column(tmp_path, capsys):
    path, points = cloud(tmp_path)
    assert main(["export", str(path)]) == 0
    out = tmp_path / "c.vtp"
    assert f"wrote {out} (9 points" in capsys.readouterr().err
    xml, arrays = read_vtp(out)
    assert 'NumberOfPoints="9" NumberOfVerts="9"' in xml and 'Scalars="scalar"' in xml
    np.testing.assert_array_equal(np.frombuffer(arrays["Points"][1], "<f4"), points[:, :3].ravel())
    np.testing.assert_array_equal(np.frombuffer(arrays["scalar"][1], "<f4"), points[:, 3])
    np.testing.assert_array_equal(np.frombuffer(arrays["hp"][1], "<f4"), points[:, 4])
    assert arrays["connectivity"][0] == "Int32"
    np.testing.assert_array_equal(np.frombuffer(arrays["connectivity"][1], "<i4"), np.arange(9))
    np.testing.assert_array_equal(np.frombuffer(arrays["offsets"][1], "<i4"), np.arange(1, 10))
    kind, meta = arrays["loudscape_meta"]
    assert kind == "String" and meta.endswith(b"\0")
    decoded = json.loads(meta[:-1])
    assert decoded["source"]["path_bytes_b64"] == "Yf8gYi53YXY="  # b"a\xff b.wav"
    assert decoded["format_version"] == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.ply", "c.vtp"]


def test_export_streams_in_blocks(tmp_path, monkeypatch):
    monkeypatch.setattr(export, "BLOCK_POINTS", 4)  # 9 points: blocks of 4, 4 and 1
    path, points = cloud(tmp_path)
    assert main(["export", str(path), "-o", str(tmp_path / "b.vtp"), "-q"]) == 0
    _, arrays = read_vtp(tmp_path / "b.vtp")
    np.testing.assert_array_equal(np.frombuffer(arrays["Points"][1], "<f4"), points[:, :3].ravel())
    np.testing.assert_array_equal(np.frombuffer(arrays["offsets"][1], "<i4"), np.arange(1, 10))


def test_export_of_an_empty_cloud(tmp_path):
    path, _ = cloud(tmp_path, n=0)
    assert main(["export", str(path), "-q"]) == 0
    xml, arrays = read_vtp(tmp_path / "c.vtp")
    assert 'NumberOfPoints="0"' in xml and arrays["Points"][1] == b""


def test_export_refuses_to_write_over_its_input(tmp_path, capsys):
    path, _ = cloud(tmp_path, name="c.vtp")  # a PLY that is named .vtp
    before = path.read_bytes()
    os.symlink(path, tmp_path / "link.vtp")
    for target in (path, tmp_path / "link.vtp", tmp_path / "." / "c.vtp"):
        assert main(["export", str(path), "-o", str(target)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "refusing to write over an input" in err
    assert path.read_bytes() == before


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.ply"], "missing.ply: no such file"),
        (["c.ply", "-o", "c.txt"], "output must end with .vtp"),
        (["c.ply", "-o", "nowhere/c.vtp"], "does not exist"),
        (["bad.ply"], "not a PLY file"),
    ],
)
def test_export_bad_inputs_one_line(tmp_path, capsys, monkeypatch, args, message):
    cloud(tmp_path)
    (tmp_path / "bad.ply").write_bytes(b"hello\n")
    monkeypatch.chdir(tmp_path)
    assert main(["export", *args]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.ply", "c.ply"]


def raw_cloud(path, meta_json, points):
    """A PLY written by hand (version-1 layout), so the metadata can break any rule."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment loudscape-meta {meta_json}\n"
        f"element vertex {points.shape[0]}\n"
        + "".join(f"property float {n}\n" for n in ("x", "y", "z", "scalar", "hp"))
        + "end_header\n"
    )
    path.write_bytes(header.encode() + points.astype("<f4").tobytes())


def good_meta(n, **changes):
    meta = {"format_version": 1, "mode": "song", "point_count": n, "axes": AXES}
    meta.update(changes)
    return {k: v for k, v in meta.items() if v is not None}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m, p: (json.dumps(good_meta(4, format_version=3)), p), "format_version"),
        (lambda m, p: (json.dumps(good_meta(4, format_version="2")), p), "format_version"),
        (lambda m, p: (json.dumps(good_meta(4, format_version=2.0)), p), "format_version"),
        (lambda m, p: (json.dumps(good_meta(4, mode="video")), p), "mode"),
        (lambda m, p: (m, np.where(np.arange(5) == 0, 1.5, p)), "column x leaves [-1, 1]"),
        (lambda m, p: (m, np.where(np.arange(5) == 3, np.nan, p)), "column scalar has a NaN"),
        (lambda m, p: (json.dumps(good_meta(5)), p), "point_count 5 is not 4"),
        (lambda m, p: (json.dumps(good_meta(4, point_count=True)), p[:1]), "point_count True"),
        (lambda m, p: (m.replace("1.0}", "NaN}", 1), p), "not plain JSON"),
        (lambda m, p: (m.replace("1.0}", "Infinity}", 1), p), "not plain JSON"),
        (lambda m, p: (json.dumps(good_meta(4, axes={"x": AXES["x"]})), p), "axes.y"),
        (lambda m, p: (json.dumps(good_meta(4, axes=None)), p), "no axes"),
    ],
)
def test_export_refuses_what_the_app_refuses(tmp_path, capsys, change, message):
    points = np.full((4, 5), 0.5, np.float32)
    meta_json, bad_points = change(json.dumps(good_meta(4)), points)
    raw_cloud(tmp_path / "bad.ply", meta_json, bad_points)
    assert main(["export", str(tmp_path / "bad.ply")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a cloud the app loads" in err and message in err, err
    assert not (tmp_path / "bad.vtp").exists()


def test_export_accepts_every_format_fixture(tmp_path):
    folder = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "fixtures", "format")
    for name in sorted(os.listdir(folder)):
        if name.endswith(".ply"):
            out = tmp_path / (name[:-4] + ".vtp")
            assert main(["export", os.path.join(folder, name), "-o", str(out), "-q"]) == 0, name
