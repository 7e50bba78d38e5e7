"""Writing and reading loudscape PLY files (binary little endian, five float32 per vertex)."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterable

import numpy as np

from loudscape_extract.errors import ExtractError

__all__ = [
    "PROPERTIES",
    "encode_header",
    "read_ply",
    "read_ply_metadata",
    "write_ply",
    "write_ply_blocks",
]

PROPERTIES = ("x", "y", "z", "scalar", "hp")
META_PREFIX = "comment loudscape-meta "


def encode_header(*, n_points: int, metadata: dict) -> bytes:
    """The PLY header, ending with ``end_header\\n``.

    Parameters
    ----------
    n_points : int
    metadata : dict
        JSON-serialisable; written on one line with non-ASCII escaped (NaN is refused).
    """
    meta = json.dumps(metadata, ensure_ascii=True, separators=(",", ":"), allow_nan=False)
    lines = [
        "ply",
        "format binary_little_endian 1.0",
        META_PREFIX + meta,
        f"element vertex {n_points}",
    ]
    lines += [f"property float {name}" for name in PROPERTIES]
    lines.append("end_header")
    return ("\n".join(lines) + "\n").encode("ascii")


def write_ply(path: str | os.PathLike, *, points: np.ndarray, metadata: dict) -> None:
    """Write points atomically: to a temporary file beside ``path``, then ``os.replace``.

    An interrupted or failed write leaves no partial file at ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its directory must exist.
    points : np.ndarray [shape=(n_points, 5)]
        x, y, z, scalar, hp; stored as little-endian float32.
    metadata : dict
        The ``loudscape-meta`` object.
    """
    name = os.fspath(path)
    points = np.asarray(points)
    if points.ndim != 2 or points.shape[1] != len(PROPERTIES):
        raise ExtractError(f"points must have shape (n_points, 5), got {points.shape}", path=name)
    directory = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=name)
    header = encode_header(n_points=points.shape[0], metadata=metadata)
    body = np.ascontiguousarray(points, dtype="<f4")
    try:
        handle = tempfile.NamedTemporaryFile(
            dir=directory, prefix="." + os.path.basename(name) + ".", suffix=".tmp", delete=False
        )
    except OSError as exc:
        raise ExtractError(f"cannot write to {directory!r} ({exc.strerror})", path=name) from exc
    try:
        with handle:
            handle.write(header)
            body.tofile(handle)
        os.chmod(handle.name, 0o666 & ~_umask())
        os.replace(handle.name, name)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise ExtractError(f"cannot write file ({exc.strerror or exc})", path=name) from exc
        raise


def write_ply_blocks(
    path: str | os.PathLike, *, n_points: int, metadata: dict, blocks: Iterable[np.ndarray]
) -> None:
    """Write points as they are produced, atomically (as :func:`write_ply`).

    The header, with ``n_points``, goes first; each block of shape (n, 5) is appended as it
    arrives, so only one block is in memory. When the blocks do not add up to ``n_points``
    exactly, or anything fails (an exception in the producer, Ctrl+C), the temporary file is
    removed and nothing is left at ``path``.

    Raises
    ------
    ExtractError
        Unwritable directory, a block of the wrong shape, or a wrong total.
    """
    name = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=name)
    header = encode_header(n_points=int(n_points), metadata=metadata)
    try:
        handle = tempfile.NamedTemporaryFile(
            dir=directory, prefix="." + os.path.basename(name) + ".", suffix=".tmp", delete=False
        )
    except OSError as exc:
        raise ExtractError(f"cannot write to {directory!r} ({exc.strerror})", path=name) from exc
    try:
        with handle:
            handle.write(header)
            written = 0
            for block in blocks:
                block = np.asarray(block)
                if block.ndim != 2 or block.shape[1] != len(PROPERTIES):
                    raise ExtractError(
                        f"points must have shape (n_points, 5), got {block.shape}", path=name
                    )
                written += block.shape[0]
                if written > n_points:
                    break
                np.ascontiguousarray(block, dtype="<f4").tofile(handle)
            if written != n_points:
                raise ExtractError(
                    f"the header promises {n_points} points but {written} were produced",
                    path=name,
                )
        os.chmod(handle.name, 0o666 & ~_umask())
        os.replace(handle.name, name)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise ExtractError(f"cannot write file ({exc.strerror or exc})", path=name) from exc
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def read_ply(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read a loudscape PLY file written by :func:`write_ply`.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    metadata : dict
        The ``loudscape-meta`` object ({} when absent).
    """
    name = os.fspath(path)
    with open(name, "rb") as handle:
        data = handle.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise ExtractError("not a PLY file (no 'ply' / 'end_header')", path=name)
    lines = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in lines:
        raise ExtractError("not a binary little-endian PLY", path=name)
    metadata: dict = {}
    n_points = None
    properties = []
    for line in lines:
        if line.startswith(META_PREFIX):
            metadata = json.loads(line[len(META_PREFIX) :])
        elif line.startswith("element vertex "):
            n_points = int(line.split()[2])
        elif line.startswith("property "):
            properties.append(tuple(line.split()[1:]))
    if n_points is None or properties != [("float", p) for p in PROPERTIES]:
        raise ExtractError(f"unexpected vertex layout {properties}", path=name)
    body = data[end + len(b"end_header\n") :]
    if len(body) != n_points * 4 * len(PROPERTIES):
        raise ExtractError(f"body has {len(body)} bytes, expected {n_points * 20}", path=name)
    points = np.frombuffer(body, dtype="<f4").reshape(n_points, len(PROPERTIES))
    return points.astype(np.float32), metadata


def read_ply_metadata(path: str | os.PathLike, *, max_header_bytes: int = 64 << 20) -> dict:
    """The ``loudscape-meta`` object of a PLY file, reading only its header ({} when absent).

    Raises
    ------
    ExtractError
        Unreadable file, not a PLY, or a header without ``end_header``.
    """
    name = os.fspath(path)
    try:
        with open(name, "rb") as handle:
            if handle.readline() != b"ply\n":
                raise ExtractError("not a PLY file (no 'ply' line)", path=name)
            read = 4
            while read < max_header_bytes:
                line = handle.readline()
                if not line:
                    break
                read += len(line)
                if line == b"end_header\n":
                    return {}
                text = line.decode("ascii", errors="replace").rstrip("\n")
                if text.startswith(META_PREFIX):
                    try:
                        return json.loads(text[len(META_PREFIX) :])
                    except ValueError as exc:
                        raise ExtractError(f"bad loudscape-meta JSON ({exc})", path=name) from exc
    except OSError as exc:
        raise ExtractError(f"cannot read file ({exc.strerror or exc})", path=name) from exc
    raise ExtractError("not a PLY file (no 'end_header')", path=name)
