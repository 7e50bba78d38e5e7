"""Export a loudscape cloud for VTK and ParaView: ``loudscape-extract export cloud.ply``.

VTK's PLY reader (and so ParaView's) reads only positions, normals, colours and texture
coordinates, so the ``scalar`` and ``hp`` columns never reach a ParaView user from the PLY. The
export writes the same cloud as VTK XML PolyData (``.vtp``), which every VTK reader opens with
all its arrays, numpy only:

- ``Points``: x, y, z (Float32, 3 components), as in the PLY (normalized, [-1, 1]).
- ``PointData``: ``scalar`` (the active scalars, so ParaView colours by it) and ``hp``, Float32.
- ``Verts``: one vertex cell per point (connectivity ``0..N-1``, offsets ``1..N``; Int32 below
  2**31 points, Int64 above), so ParaView draws the points in its default Surface
  representation.
- ``FieldData``: ``loudscape_meta``, one string: the PLY's metadata as one line of JSON (the
  object of docs/FORMAT.md, non-UTF-8 paths as there), so the axes' physical units travel
  along.

The arrays are in one raw appended block (``header_type="UInt64"``: each array is preceded by
its byte count as a little-endian uint64). The file is written to a temporary file beside the
output and renamed; the command refuses to write over its input.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterator

import numpy as np

from loudscape_extract.contract import check_loadable
from loudscape_extract.paths import check_output_path, check_regular_input
from loudscape_extract.ply import encode_metadata, map_ply, write_atomically

__all__ = ["add_parser", "export_vtp", "vtp_parts"]

#: Points converted per block while writing, so memory stays bounded for any cloud.
BLOCK_POINTS = 1 << 20


def _blocks(points: np.ndarray, columns: slice | int, dtype: str) -> Iterator[np.ndarray]:
    for start in range(0, points.shape[0], BLOCK_POINTS):
        yield np.ascontiguousarray(points[start : start + BLOCK_POINTS, columns], dtype=dtype)


def _ramp(start: int, stop: int, dtype: str) -> Iterator[np.ndarray]:
    for first in range(start, stop, BLOCK_POINTS):
        yield np.arange(first, min(first + BLOCK_POINTS, stop), dtype=dtype)


def vtp_parts(points: np.ndarray, metadata: dict) -> Iterator[bytes | np.ndarray]:
    """The bytes of a ``.vtp`` file for ``points`` (shape (n, 5): x, y, z, scalar, hp), in
    order, as a stream of bytes and arrays (see the module docs for the layout)."""
    n = int(points.shape[0])
    index = "Int32" if n < 2**31 else "Int64"
    index_dtype = "<i4" if index == "Int32" else "<i8"
    index_size = 4 if index == "Int32" else 8
    meta = json.dumps(encode_metadata(metadata), ensure_ascii=True, separators=(",", ":"))
    meta = meta.encode("ascii") + b"\0"
    # (name, VTK type, components, byte count, parts)
    arrays = [
        ("loudscape_meta", "String", 1, len(meta), [meta]),
        ("scalar", "Float32", 1, 4 * n, _blocks(points, 3, "<f4")),
        ("hp", "Float32", 1, 4 * n, _blocks(points, 4, "<f4")),
        ("Points", "Float32", 3, 12 * n, _blocks(points, slice(0, 3), "<f4")),
        ("connectivity", index, 1, index_size * n, _ramp(0, n, index_dtype)),
        ("offsets", index, 1, index_size * n, _ramp(1, n + 1, index_dtype)),
    ]
    offsets = []
    position = 0
    for *_, size, _ in arrays:
        offsets.append(position)
        position += 8 + size

    def element(i: int) -> str:
        name, kind, components, _, _ = arrays[i]
        extra = ' NumberOfTuples="1"' if kind == "String" else ""
        return (
            f'<DataArray type="{kind}" Name="{name}" NumberOfComponents="{components}"{extra} '
            f'format="appended" offset="{offsets[i]}"/>'
        )

    field_element = element(0).replace("<DataArray", "<Array")
    xml = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n'
        "  <PolyData>\n"
        f"    <FieldData>\n      {field_element}\n    </FieldData>\n"
        f'    <Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" '
        'NumberOfStrips="0" NumberOfPolys="0">\n'
        '      <PointData Scalars="scalar">\n'
        f"        {element(1)}\n        {element(2)}\n"
        "      </PointData>\n"
        f"      <Points>\n        {element(3)}\n      </Points>\n"
        f"      <Verts>\n        {element(4)}\n        {element(5)}\n      </Verts>\n"
        "    </Piece>\n"
        "  </PolyData>\n"
        '  <AppendedData encoding="raw">\n   _'
    )
    yield xml.encode("ascii")
    for *_, size, parts in arrays:
        yield np.uint64(size).astype("<u8").tobytes()
        yield from parts
    yield b"\n  </AppendedData>\n</VTKFile>\n"


def export_vtp(source: str, output: str) -> int:
    """Write the cloud in ``source`` (a loudscape PLY, version 1 or 2) as VTK XML PolyData.

    Returns
    -------
    n_points : int

    Raises
    ------
    ExtractError
        Unreadable or malformed input, a cloud the app's loader refuses
        (:func:`contract.check_loadable`), an output that is the input, an output not ending
        in ``.vtp``, or an output that cannot be written.
    """
    check_regular_input(source)
    check_output_path(output, inputs=[source], extensions=(".vtp",))
    points, metadata = map_ply(source)
    check_loadable(points, metadata, path=source)  # the app's loader's rules, not looser
    write_atomically(output, vtp_parts(points, metadata))
    return int(points.shape[0])


def add_parser(commands) -> argparse.ArgumentParser:
    """The ``export`` subcommand's parser, added to ``commands`` (argparse subparsers)."""
    export = commands.add_parser(
        "export",
        help="a cloud as VTK XML PolyData (.vtp) for ParaView, with scalar and hp",
        description="Write a loudscape PLY (song or timeline) as VTK XML PolyData: points x, "
        "y, z, point arrays scalar and hp, one vertex cell per point, the metadata JSON as "
        "field data loudscape_meta. ParaView's PLY reader drops scalar and hp; this keeps "
        "them.",
    )
    export.add_argument("input", help="loudscape PLY file (format version 1 or 2)")
    export.add_argument("-o", "--output", help="VTP file (default: the input's name with .vtp)")
    return export
