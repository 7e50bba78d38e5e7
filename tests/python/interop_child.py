"""Open one file with one third-party reader; run as a child process by test_interop.py.

    python interop_child.py READER PATH OUT_DIR

READER is plyfile, meshio, trimesh, open3d or vtk. The child prints one JSON line (what the
reader saw: counts and the names of the attributes it exposes) and saves every array it read
as OUT_DIR/NAME.npy, so the parent compares values exactly. A reader that aborts the process
(Open3D does on header lines over 1,024 bytes) shows as the child's exit status.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np


def save(out: str, name: str, values) -> None:
    np.save(os.path.join(out, name + ".npy"), np.asarray(values))


def with_plyfile(path: str, out: str) -> dict:
    import plyfile

    data = plyfile.PlyData.read(path)
    seen = {"comments": len(data.comments)}
    for element in data.elements:
        seen[element.name] = element.count
        seen[element.name + "_properties"] = [p.name for p in element.properties]
        if element.name == "vertex":
            for name in element.data.dtype.names:
                save(out, name, element.data[name])
        if element.name == "face":
            save(out, "faces", np.stack(element.data["vertex_indices"]))
    return seen


def with_meshio(path: str, out: str) -> dict:
    import meshio

    mesh = meshio.read(path)
    save(out, "points", mesh.points)
    for name, values in mesh.point_data.items():
        save(out, name, values)
    cells = {block.type: len(block.data) for block in mesh.cells}
    for block in mesh.cells:
        if block.type == "triangle":
            save(out, "faces", block.data)
    return {"points": len(mesh.points), "point_data": sorted(mesh.point_data), "cells": cells}


def with_trimesh(path: str, out: str) -> dict:
    import trimesh

    loaded = trimesh.load(path, process=False)
    seen = {"type": type(loaded).__name__, "points": len(loaded.vertices)}
    save(out, "points", loaded.vertices)
    faces = getattr(loaded, "faces", None)
    if faces is not None:
        seen["faces"] = len(faces)
        save(out, "faces", faces)
    raw = loaded.metadata.get("_ply_raw", {}).get("vertex", {}).get("data")
    seen["ply_properties"] = list(raw.dtype.names) if raw is not None else []
    for name in seen["ply_properties"]:
        save(out, name, raw[name])
    colors = getattr(loaded.visual, "vertex_colors", None) if hasattr(loaded, "visual") else None
    if colors is None and hasattr(loaded, "colors"):
        colors = loaded.colors
    seen["vertex_colors"] = colors is not None and len(colors) == len(loaded.vertices)
    if seen["vertex_colors"]:
        save(out, "colors", colors)
    return seen


def with_open3d(path: str, out: str) -> dict:
    import open3d as o3d

    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    with open(path, "rb") as handle:
        is_mesh = b"element face" in handle.read(4096) or path.endswith(".obj")
    if is_mesh:
        mesh = o3d.io.read_triangle_mesh(path)
        save(out, "points", np.asarray(mesh.vertices))
        save(out, "faces", np.asarray(mesh.triangles))
        tensor = o3d.t.io.read_triangle_mesh(path)
        names = sorted(tensor.vertex)
        for name in names:
            if name != "positions":
                save(out, name, tensor.vertex[name].numpy())
        return {
            "points": len(mesh.vertices),
            "faces": len(mesh.triangles),
            "normals": mesh.has_vertex_normals(),
            "colors": mesh.has_vertex_colors(),
            "tensor_attributes": names,
        }
    cloud = o3d.io.read_point_cloud(path)
    save(out, "points", np.asarray(cloud.points))
    tensor = o3d.t.io.read_point_cloud(path)
    names = sorted(tensor.point)
    for name in names:
        if name != "positions":
            save(out, name, tensor.point[name].numpy().ravel())
    return {"points": len(cloud.points), "tensor_attributes": names}


def with_vtk(path: str, out: str) -> dict:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    ext = os.path.splitext(path)[1].lower()
    reader = {
        ".ply": vtk.vtkPLYReader,
        ".obj": vtk.vtkOBJReader,
        ".vtp": vtk.vtkXMLPolyDataReader,
        ".nrrd": vtk.vtkNrrdReader,
    }[ext]()
    reader.SetFileName(path)
    reader.Update()
    data = reader.GetOutput()
    point_data = data.GetPointData()
    names = [point_data.GetArrayName(i) for i in range(point_data.GetNumberOfArrays())]
    for i, name in enumerate(names):
        save(out, name or f"array{i}", vtk_to_numpy(point_data.GetArray(i)))
    seen = {"points": data.GetNumberOfPoints(), "point_data": names}
    if ext == ".nrrd":
        seen["dimensions"] = list(data.GetDimensions())
        seen["spacing"] = list(data.GetSpacing())
        seen["origin"] = list(data.GetOrigin())
        return seen
    if data.GetNumberOfPoints():
        save(out, "points", vtk_to_numpy(data.GetPoints().GetData()))
    seen["verts"] = data.GetNumberOfVerts()
    seen["polys"] = data.GetNumberOfPolys()
    field = data.GetFieldData()
    seen["field_data"] = [
        field.GetAbstractArray(i).GetName() for i in range(field.GetNumberOfArrays())
    ]
    meta = field.GetAbstractArray("loudscape_meta")
    if meta is not None:
        seen["loudscape_meta"] = json.loads(meta.GetValue(0))["mode"]
    return seen


READERS = {
    "plyfile": with_plyfile,
    "meshio": with_meshio,
    "trimesh": with_trimesh,
    "open3d": with_open3d,
    "vtk": with_vtk,
}


if __name__ == "__main__":
    reader, path, out = sys.argv[1:4]
    print(json.dumps(READERS[reader](path, out)))
