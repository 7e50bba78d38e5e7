"""Every kind of file loudscape writes, opened by the readers other people use.

Files: the extractor's song and timeline PLY (format version 2, written here by
``loudscape-extract``), the committed format fixtures (tests/fixtures/format/, with non-UTF-8
paths), a 10,000-song timeline (6.9 MB of header), the VTK XML export (``.vtp``), and the app's
meshes (``loudscape mesh``: .ply and .obj) and grids (``loudscape voxelize``: .npy and .nrrd).
Readers: plyfile, meshio, trimesh, Open3D and VTK, each in a child process
(tests/python/interop_child.py), so a reader that aborts the process (Open3D does on header
lines over 1,024 bytes) fails its test instead of the run. What each reader sees is asserted
exactly, counts and values; docs/FORMAT.md has the same table.

The app is ``$LOUDSCAPE_BIN``, by default ``target/debug/loudscape``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mutagen.flac
import numpy as np
import pytest
import soundfile

from loudscape_extract.ply import read_ply
from loudscape_fixtures.formats import write_format_fixtures

ROOT = Path(__file__).resolve().parents[1].parent
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape"))
CHILD = Path(__file__).with_name("interop_child.py")
FIXTURES = ROOT / "tests" / "fixtures" / "format"
RATE = 8000


def run(args, **kwargs):
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    assert done.returncode == 0, f"{args}: exit {done.returncode}\n{done.stderr[-3000:]}"
    return done


def open_with(reader: str, path: Path, out: Path) -> tuple[dict, dict]:
    """What ``reader`` sees in ``path`` (its JSON line) and the arrays it read, by name."""
    out.mkdir(parents=True)
    done = subprocess.run(
        [sys.executable, str(CHILD), reader, str(path), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, (
        f"{reader} on {path.name}: exit {done.returncode} (negative: killed by signal)\n"
        f"{done.stderr[-2000:]}"
    )
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    arrays = {p.stem: np.load(p) for p in out.glob("*.npy")}
    return seen, arrays


# --- the files ---------------------------------------------------------------------------------


def tone(seconds: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * RATE)) / RATE
    y = 0.3 * np.sin(2 * np.pi * 440 * t) + 0.2 * np.sin(2 * np.pi * 660 * t)
    y[:: RATE // 4] += 0.6  # clicks: some percussive bins
    return (y + 0.01 * rng.standard_normal(t.size)).astype(np.float32)


@pytest.fixture(scope="module")
def clouds(tmp_path_factory) -> dict[str, Path]:
    """Point clouds written by today's extractor and fixtures: name -> path."""
    folder = tmp_path_factory.mktemp("clouds")
    music = folder / "music"
    music.mkdir()
    for i, year in enumerate((1984, 2004)):
        path = music / f"song {i}.flac"
        soundfile.write(str(path), tone(1.0, i), RATE)
        tags = mutagen.flac.FLAC(str(path))
        # A title beyond ASCII (recorded in the song's source since tags are): every reader copes.
        title = f"Song {i} \u266a \u05e9\u05dc\u05d5\u05dd"
        tags["date"], tags["title"], tags["artist"] = str(year), title, "Band"
        tags.save()
    extract = [sys.executable, "-m", "loudscape_extract.cli"]
    fast = ["--n-fft", "256", "--hop", "128", "-q"]
    run([*extract, "song", music / "song 0.flac", "-o", folder / "song.ply", *fast])
    run([*extract, "timeline", music, "-o", folder / "timeline.ply", "--no-cache", *fast])
    write_format_fixtures(str(folder), large=True)
    files = {
        "song": folder / "song.ply",
        "timeline": folder / "timeline.ply",
        "timeline_10000_songs": folder / "timeline_v2_10000_songs.ply",
    }
    for name in ("song_v2_non_utf8", "timeline_v2_non_utf8"):
        files[name] = FIXTURES / f"{name}.ply"
    return files


@pytest.fixture(scope="module")
def app_files(tmp_path_factory) -> dict[str, Path]:
    """Meshes and grids written by the app from the committed song fixture."""
    if not BINARY.exists():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    folder = tmp_path_factory.mktemp("app")
    source = ROOT / "data" / "fixture_song.ply"  # format version 2
    files = {}
    for method in ("mt", "dc"):
        for ext in ("ply", "obj"):
            files[f"mesh_{method}.{ext}"] = folder / f"mesh_{method}.{ext}"
            run(
                [
                    BINARY,
                    "mesh",
                    source,
                    "--method",
                    method,
                    "--res",
                    "64",
                    "-o",
                    folder / f"mesh_{method}.{ext}",
                ]
            )
    for ext in ("npy", "nrrd"):
        files[f"grid.{ext}"] = folder / f"grid.{ext}"
        run([BINARY, "voxelize", source, "--res", "64", "-o", folder / f"grid.{ext}"])
    return files


# --- point clouds ------------------------------------------------------------------------------

CLOUD_NAMES = [
    "song",
    "timeline",
    "timeline_10000_songs",
    "song_v2_non_utf8",
    "timeline_v2_non_utf8",
]
READERS = ["plyfile", "meshio", "trimesh", "open3d", "vtk"]
#: The per-point values each reader gives besides positions (docs/FORMAT.md, "Other readers").
CLOUD_ATTRIBUTES = {
    "plyfile": ["x", "y", "z", "scalar", "hp"],
    "meshio": ["hp", "scalar"],
    "trimesh": ["x", "y", "z", "scalar", "hp"],
    "open3d": ["hp", "positions", "scalar"],
    "vtk": [],  # vtkPLYReader keeps positions, normals, colours, uv only: use the .vtp export
}


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("name", CLOUD_NAMES)
def test_cloud_ply(clouds, tmp_path, name, reader):
    path = clouds[name]
    points, metadata = read_ply(path)
    assert metadata["format_version"] == 2 and len(points) == metadata["point_count"] > 0
    seen, arrays = open_with(reader, path, tmp_path / "out")
    attributes = {
        "plyfile": seen.get("vertex_properties"),
        "meshio": seen.get("point_data"),
        "trimesh": seen.get("ply_properties"),
        "open3d": seen.get("tensor_attributes"),
        "vtk": seen.get("point_data"),
    }[reader]
    assert attributes == CLOUD_ATTRIBUTES[reader]
    if reader == "plyfile":
        assert seen["vertex"] == len(points)
        xyz = np.stack([arrays["x"], arrays["y"], arrays["z"]], axis=1)
        assert seen["comments"] >= 1
    else:
        assert seen["points"] == len(points)
        xyz = arrays["points"]
    np.testing.assert_array_equal(xyz.astype(np.float32), points[:, :3])
    if "scalar" in attributes:
        np.testing.assert_array_equal(arrays["scalar"].ravel(), points[:, 3])
        np.testing.assert_array_equal(arrays["hp"].ravel(), points[:, 4])
    if reader == "trimesh":
        assert seen["type"] == "PointCloud"


# --- the VTK export ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["song", "timeline_10000_songs", "timeline_v2_non_utf8"])
def test_vtp_export_in_vtk(clouds, tmp_path, name):
    vtp = tmp_path / f"{name}.vtp"
    run([sys.executable, "-m", "loudscape_extract.cli", "export", clouds[name], "-o", vtp, "-q"])
    points, metadata = read_ply(clouds[name])
    seen, arrays = open_with("vtk", vtp, tmp_path / "out")
    assert seen["points"] == seen["verts"] == len(points) and seen["polys"] == 0
    assert seen["point_data"] == ["scalar", "hp"]
    assert seen["field_data"] == ["loudscape_meta"] and seen["loudscape_meta"] == metadata["mode"]
    np.testing.assert_array_equal(arrays["points"], points[:, :3])
    np.testing.assert_array_equal(arrays["scalar"], points[:, 3])
    np.testing.assert_array_equal(arrays["hp"], points[:, 4])


# --- the app's meshes --------------------------------------------------------------------------


def mesh_ply(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertex records and triangles of a ``loudscape mesh`` PLY, read here."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    counts = {ln.split()[1]: int(ln.split()[2]) for ln in header if ln.startswith("element")}
    vertex = np.dtype([("p", "<f4", 3), ("n", "<f4", 3), ("rgb", "u1", 3), ("hp", "<f4")])
    face = np.dtype([("k", "u1"), ("i", "<u4", 3)])
    vertices = np.frombuffer(data, vertex, counts["vertex"], end)
    faces = np.frombuffer(data, face, counts["face"], end + vertices.nbytes)
    assert (faces["k"] == 3).all() and len(faces) > 1000
    return vertices, faces["i"].astype(np.int64)


def mesh_obj(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions, normals and triangles (0-based) of a ``loudscape mesh`` OBJ, read here."""
    v, vn, f = [], [], []
    for line in path.read_text().splitlines():
        kind, *rest = line.split()
        if kind == "v":
            v.append([float(x) for x in rest[:3]])
        elif kind == "vn":
            vn.append([float(x) for x in rest])
        elif kind == "f":
            f.append([int(t.split("//")[0]) - 1 for t in rest])
    return np.array(v), np.array(vn), np.array(f)


MESH_READERS = ["plyfile", "meshio", "trimesh", "open3d", "vtk"]


@pytest.mark.parametrize("reader", MESH_READERS)
@pytest.mark.parametrize("method", ["mt", "dc"])
def test_app_mesh_ply(app_files, tmp_path, method, reader):
    vertices, faces = mesh_ply(app_files[f"mesh_{method}.ply"])
    seen, arrays = open_with(reader, app_files[f"mesh_{method}.ply"], tmp_path / "out")
    n = len(vertices)
    if reader == "plyfile":
        assert seen["vertex"] == n and seen["face"] == len(faces)
        assert seen["vertex_properties"] == [
            "x",
            "y",
            "z",
            "nx",
            "ny",
            "nz",
            "red",
            "green",
            "blue",
            "hp",
        ]
        np.testing.assert_array_equal(arrays["hp"], vertices["hp"])
    elif reader == "meshio":
        assert seen["cells"] == {"triangle": len(faces)} and seen["points"] == n
        assert seen["point_data"] == ["blue", "green", "hp", "nx", "ny", "nz", "red"]
        np.testing.assert_array_equal(arrays["hp"], vertices["hp"])
    elif reader == "trimesh":
        assert seen["type"] == "Trimesh" and seen["faces"] == len(faces) and seen["vertex_colors"]
        assert "hp" in seen["ply_properties"]
        np.testing.assert_array_equal(arrays["hp"], vertices["hp"])
        np.testing.assert_array_equal(arrays["colors"][:, :3], vertices["rgb"])
    elif reader == "open3d":
        assert seen["points"] == n and seen["faces"] == len(faces)
        assert seen["normals"] and seen["colors"]
        assert seen["tensor_attributes"] == ["colors", "normals", "positions"]  # no hp
    elif reader == "vtk":
        assert seen["points"] == n and seen["polys"] == len(faces)
        assert seen["point_data"] == ["RGB", "Normals"]
        np.testing.assert_array_equal(arrays["RGB"], vertices["rgb"])
    np.testing.assert_array_equal(
        arrays.get("points", vertices["p"]).astype(np.float32), vertices["p"]
    )
    if "faces" in arrays:
        np.testing.assert_array_equal(arrays["faces"], faces)


@pytest.mark.parametrize("reader", ["meshio", "trimesh", "open3d", "vtk"])
@pytest.mark.parametrize("method", ["mt", "dc"])
def test_app_mesh_obj(app_files, tmp_path, method, reader):
    positions, normals, faces = mesh_obj(app_files[f"mesh_{method}.obj"])
    assert len(positions) == len(normals) and len(faces) > 1000
    seen, arrays = open_with(reader, app_files[f"mesh_{method}.obj"], tmp_path / "out")
    if reader == "open3d":
        # Open3D's OBJ reader merges vertices equal in position and normal.
        unique = len(np.unique(np.hstack([positions, normals]), axis=0))
        assert seen["points"] == unique and seen["faces"] == len(faces)
        assert seen["normals"] and seen["colors"]
        return
    assert seen["points"] == len(positions)
    xyz = arrays["points"]
    if reader == "meshio":
        # meshio takes the colour after x y z on a `v` line for three more coordinates.
        assert xyz.shape == (len(positions), 6)
        xyz = xyz[:, :3]
    np.testing.assert_allclose(xyz, positions, rtol=0, atol=1e-6)
    if reader == "meshio":
        assert seen["cells"] == {"triangle": len(faces)} and seen["point_data"] == ["obj:vn"]
        np.testing.assert_array_equal(arrays["faces"], faces)
    elif reader == "trimesh":
        assert seen["type"] == "Trimesh" and seen["vertex_colors"]
        np.testing.assert_array_equal(arrays["faces"], faces)
    elif reader == "vtk":
        assert seen["polys"] == len(faces) and seen["point_data"] == ["Normals", "RGB"]


# --- the app's grids ---------------------------------------------------------------------------


def test_app_grid_npy(app_files):
    grid = np.load(app_files["grid.npy"])
    box = json.loads(Path(str(app_files["grid.npy"]) + ".json").read_text())
    assert grid.dtype == np.float32 and grid.shape == (2, 64, 64, 64)
    assert box["dims"] == [64, 64, 64] and box["fields"] == ["density", "hp_mean"]
    assert 0 <= grid.min() and grid.max() <= 1 and (grid[0] > 0).sum() == box["nonempty_voxels"]


@pytest.mark.parametrize("field", ["density", "hp"])
def test_app_grid_nrrd_in_vtk(app_files, tmp_path, field):
    grid = np.load(app_files["grid.npy"])  # the same voxelization, as .npy
    path = app_files["grid.nrrd"]
    if field == "hp":
        path = path.with_name("grid_hp.nrrd")
    seen, arrays = open_with("vtk", path, tmp_path / "out")
    assert seen["dimensions"] == [64, 64, 64] and seen["points"] == 64**3
    box = json.loads(Path(str(app_files["grid.nrrd"]) + ".json").read_text())
    spacing = (np.array(box["box_max"]) - np.array(box["box_min"])) / 64
    np.testing.assert_allclose(seen["spacing"], spacing, rtol=1e-6)
    np.testing.assert_allclose(seen["origin"], np.array(box["box_min"]) + spacing / 2, atol=1e-6)
    (values,) = arrays.values()
    np.testing.assert_array_equal(values, grid[0 if field == "density" else 1].ravel())
