"""Writing and reading loudscape PLY files (binary little endian, five float32 per vertex).

The writer writes format version 2 (docs/FORMAT.md): the JSON metadata cut into
``comment loudscape-meta-v2 I/N CHUNK`` lines of at most :data:`MAX_LINE_BYTES` bytes, so that
readers with short line buffers (Open3D: 1,024 bytes, VTK: about 4 KB) open the files. The
reader reads versions 1 (one ``comment loudscape-meta {JSON}`` line) and 2.

Strings that hold undecodable file-name bytes (Python's ``surrogateescape`` code points
U+DC80..U+DCFF, as ``os.listdir`` returns them for a name that is not UTF-8) are written
losslessly: the text with U+FFFD in place of each bad byte, plus a sibling key
``<key>_bytes_b64`` with the exact bytes in base64. :func:`read_ply` puts the original string
back.
"""

from __future__ import annotations

import base64
import contextlib
import errno
import io
import json
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from typing import BinaryIO

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.paths import fsync_directory, open_regular_input, write_failure

__all__ = [
    "MAX_LINE_BYTES",
    "META_CHUNK_BYTES",
    "PROPERTIES",
    "WRITTEN_VERSION",
    "decode_metadata",
    "encode_header",
    "encode_metadata",
    "map_ply",
    "read_ply",
    "read_ply_metadata",
    "write_atomically",
    "write_ply",
    "write_ply_blocks",
]

PROPERTIES = ("x", "y", "z", "scalar", "hp")
WRITTEN_VERSION = 2
META_PREFIX = "comment loudscape-meta "
META_V2_KEYWORD = "loudscape-meta-v2"
#: Longest header line a version-2 writer produces, counting its ``\n``.
MAX_LINE_BYTES = 1000
#: JSON bytes per ``loudscape-meta-v2`` line; with the prefix and ``I/N`` (up to 40 digits
#: each) a line stays under :data:`MAX_LINE_BYTES`.
META_CHUNK_BYTES = 900
BYTES_SUFFIX = "_bytes_b64"
_V2_LINE = re.compile(r"comment loudscape-meta-v2 ([1-9][0-9]*)/([1-9][0-9]*) ([!-~]+)")
_SURROGATE = re.compile("[\ud800-\udfff]")


# --- metadata: JSON-safe strings ---------------------------------------------------------------


def _safe_text(value: str) -> tuple[str, bytes | None]:
    """``(text, raw)``: text without lone surrogates, and the bytes it stood for (or None)."""
    if not _SURROGATE.search(value):
        return value, None
    try:
        raw = value.encode("utf-8", "surrogateescape")
    except UnicodeEncodeError:
        # A surrogate no POSIX file name decodes to (U+D800..U+DC7F, U+DD00..U+DFFF): no bytes
        # to keep; replace it.
        return _SURROGATE.sub("\ufffd", value), None
    return raw.decode("utf-8", "replace"), raw


def encode_metadata(metadata: dict) -> dict:
    """A copy of ``metadata`` in which every string is valid Unicode (see the module docs).

    A dict value ``key: str`` holding surrogate-escaped bytes becomes its text with U+FFFD
    for each bad byte plus ``key + "_bytes_b64"``: the bytes in standard base64 (with ``=``
    padding). Strings elsewhere (list items, dict keys) only get the U+FFFD replacement.

    Raises
    ------
    ExtractError
        When a dict already has the ``_bytes_b64`` key of a string that needs one.
    """

    def encode(value):
        if isinstance(value, dict):
            out = {}
            for key, item in value.items():
                safe_key = _safe_text(key)[0] if isinstance(key, str) else key
                if isinstance(item, str):
                    text, raw = _safe_text(item)
                    out[safe_key] = text
                    if raw is not None:
                        sibling = safe_key + BYTES_SUFFIX
                        if sibling in value:
                            raise ExtractError(f"metadata has both {key!r} bytes and {sibling!r}")
                        out[sibling] = base64.b64encode(raw).decode("ascii")
                else:
                    out[safe_key] = encode(item)
            return out
        if isinstance(value, (list, tuple)):
            return [encode(item) for item in value]
        if isinstance(value, str):
            return _safe_text(value)[0]
        return value

    return encode(metadata)


def decode_metadata(metadata: dict) -> dict:
    """Undo :func:`encode_metadata`: ``key`` from ``key + "_bytes_b64"`` (UTF-8 with
    surrogateescape), the ``_bytes_b64`` keys removed."""

    def decode(value):
        if isinstance(value, dict):
            out = {}
            for key, item in value.items():
                if isinstance(key, str) and key.endswith(BYTES_SUFFIX):
                    base = key[: -len(BYTES_SUFFIX)]
                    if isinstance(item, str) and isinstance(value.get(base), str):
                        continue
                out[key] = decode(item)
            for key, item in value.items():
                if isinstance(key, str) and key.endswith(BYTES_SUFFIX) and isinstance(item, str):
                    base = key[: -len(BYTES_SUFFIX)]
                    if isinstance(value.get(base), str):
                        try:
                            raw = base64.b64decode(item.encode("ascii"), validate=True)
                        except (ValueError, UnicodeEncodeError) as exc:
                            raise ValueError(f"{key!r} is not base64 ({exc})") from exc
                        out[base] = raw.decode("utf-8", "surrogateescape")
            return out
        if isinstance(value, list):
            return [decode(item) for item in value]
        return value

    return decode(metadata)


# --- header ------------------------------------------------------------------------------------


def metadata_json(metadata: dict) -> str:
    """The metadata as the one-line JSON text both versions carry: compact, ASCII only
    (non-ASCII escaped), NaN refused, strings made safe by :func:`encode_metadata`.

    Compact JSON has whitespace only inside strings; every space there is written ``\\u0020``,
    so the text has no whitespace at all and no reader that trims or splits comment lines can
    change it."""
    text = json.dumps(
        encode_metadata(metadata), ensure_ascii=True, separators=(",", ":"), allow_nan=False
    )
    return text.replace(" ", "\\u0020")


def meta_lines(text: str, *, chunk_bytes: int = META_CHUNK_BYTES) -> list[str]:
    """``comment loudscape-meta-v2 I/N CHUNK`` lines (no ``\\n``) for the JSON ``text``."""
    chunks = [text[i : i + chunk_bytes] for i in range(0, len(text), chunk_bytes)] or ["{}"]
    count = len(chunks)
    return [f"comment {META_V2_KEYWORD} {i}/{count} {chunk}" for i, chunk in enumerate(chunks, 1)]


def encode_header(*, n_points: int, metadata: dict, format_version: int = WRITTEN_VERSION) -> bytes:
    """The PLY header, ending with ``end_header\\n``.

    Parameters
    ----------
    n_points : int
    metadata : dict
        JSON-serialisable (NaN is refused). Its ``format_version`` is set to
        ``format_version``: the writer owns that key.
    format_version : {2, 1}
        2 (default): metadata in ``loudscape-meta-v2`` lines of at most 1,000 bytes. 1: one
        ``loudscape-meta`` line of any length (for readers that know only version 1).
    """
    if format_version not in (1, 2):
        raise ValueError(f"format_version must be 1 or 2, got {format_version!r}")
    text = metadata_json({**metadata, "format_version": format_version})
    lines = ["ply", "format binary_little_endian 1.0"]
    lines += [META_PREFIX + text] if format_version == 1 else meta_lines(text)
    lines.append(f"element vertex {n_points}")
    lines += [f"property float {name}" for name in PROPERTIES]
    lines.append("end_header")
    return ("\n".join(lines) + "\n").encode("ascii")


def _meta_from_lines(lines: Iterable[tuple[int, str]], name: str) -> dict:
    """The metadata object of a header's lines (``(line number, text without \\n)``)."""
    v1: tuple[int, str] | None = None
    chunks: list[str] = []
    count = None
    first_v2 = None
    for number, line in lines:
        if line.startswith(META_PREFIX):
            if v1 is not None:
                raise ExtractError(
                    f"header line {number}: second loudscape-meta comment "
                    f"(the first is line {v1[0]})",
                    path=name,
                )
            v1 = (number, line[len(META_PREFIX) :])
        elif line.startswith(f"comment {META_V2_KEYWORD} ") or line == f"comment {META_V2_KEYWORD}":
            match = _V2_LINE.fullmatch(line)
            if match is None:
                raise ExtractError(
                    f"header line {number}: expected `comment {META_V2_KEYWORD} I/N CHUNK`",
                    path=name,
                )
            index, total = int(match.group(1)), int(match.group(2))
            if first_v2 is None:
                first_v2, count = number, total
            if total != count or index != len(chunks) + 1:
                raise ExtractError(
                    f"header line {number}: {META_V2_KEYWORD} part {index}/{total} out of order "
                    f"(expected {len(chunks) + 1}/{count})",
                    path=name,
                )
            chunks.append(match.group(3))
    if v1 is not None and first_v2 is not None:
        raise ExtractError(
            f"header lines {v1[0]} and {first_v2}: both loudscape-meta and {META_V2_KEYWORD}",
            path=name,
        )
    if first_v2 is not None:
        if len(chunks) != count:
            raise ExtractError(
                f"header line {first_v2}: {META_V2_KEYWORD} has {len(chunks)} of {count} parts",
                path=name,
            )
        number, text = first_v2, "".join(chunks)
    elif v1 is not None:
        number, text = v1
    else:
        return {}
    try:
        metadata = json.loads(text)
        if not isinstance(metadata, dict):
            raise ValueError("not a JSON object")
        return decode_metadata(metadata)
    except RecursionError:
        raise ExtractError(
            f"header line {number}: bad loudscape-meta JSON (nested too deeply: arrays or "
            "objects inside each other hundreds of levels down; the format has a few)",
            path=name,
        ) from None
    except ValueError as exc:
        raise ExtractError(
            f"header line {number}: bad loudscape-meta JSON ({exc})", path=name
        ) from exc


# --- writing -----------------------------------------------------------------------------------


def write_atomically(
    path: str | os.PathLike, parts: Iterable[bytes | np.ndarray | BinaryIO]
) -> None:
    """Write ``parts`` in order to a temporary file beside ``path``, then ``os.replace`` it.

    An interrupted or failed write leaves no partial file at ``path``; the data is synced to
    the disk before the rename and the folder after it. Arrays are written as their bytes in
    memory (C order); an open binary file, the rest of its bytes (copied by the kernel where
    it can: :func:`copy_rest`). A full disk is reported as such (:func:`paths.write_failure`).

    Raises
    ------
    ExtractError
        The directory does not exist or cannot be written.
    """
    name = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=name)
    try:
        handle = tempfile.NamedTemporaryFile(
            dir=directory, prefix="." + os.path.basename(name) + ".", suffix=".tmp", delete=False
        )
    except OSError as exc:
        raise ExtractError(f"cannot write to {directory!r} ({exc.strerror})", path=name) from exc
    try:
        with handle:
            for part in parts:
                if isinstance(part, np.ndarray):
                    # Through Python's write (not tofile): a full disk is ENOSPC, not a count.
                    handle.write(np.ascontiguousarray(part).reshape(-1).view(np.uint8).data)
                elif isinstance(part, (bytes, bytearray, memoryview)):
                    handle.write(part)
                else:
                    copy_rest(part, handle)
            handle.flush()
            os.fsync(handle.fileno())  # the data is on disk before the name points at it
        os.chmod(handle.name, 0o666 & ~_umask())
        os.replace(handle.name, name)
        fsync_directory(directory)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise ExtractError(write_failure(exc, directory=directory), path=name) from exc
        raise


#: What ``os.copy_file_range`` raises where the kernel cannot copy between the two files (other
#: file systems, no such call, a file system that does not offer it): then through user space.
_NO_KERNEL_COPY = {errno.EXDEV, errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP, errno.ENOTSUP}


def copy_rest(source: BinaryIO, target: BinaryIO) -> None:
    """Append the rest of ``source`` (from its position) to ``target``, both open binary files.

    On Linux ``os.copy_file_range`` copies inside the kernel (no read into Python and write
    back: for a 100 MB Song body about half the CPU time and under half the wall time, and no
    copy at all where the file system shares blocks); elsewhere, or where the kernel declines,
    ``shutil.copyfileobj``. Errors other than those are raised (a full disk is ``ENOSPC``).
    """
    target.flush()
    copy_range = getattr(os, "copy_file_range", None)
    try:
        source_fd, target_fd = source.fileno(), target.fileno()
    except (AttributeError, io.UnsupportedOperation):  # in memory (io.BytesIO)
        copy_range = None
    if copy_range is not None:
        # From the source's position by an explicit offset (its descriptor's own offset, which
        # its buffer relies on, is left alone); onto the target at its descriptor's offset.
        start = copied = source.tell()
        try:
            while step := copy_range(source_fd, target_fd, 1 << 30, copied):
                copied += step
        except OSError as exc:
            if exc.errno not in _NO_KERNEL_COPY:
                raise
        else:
            source.seek(copied)
            target.seek(0, os.SEEK_END)  # the target's descriptor moved on under its buffer
            return
        # Declined: the rest through user space, from as far as the kernel got.
        source.seek(copied)
        if copied != start:
            target.seek(0, os.SEEK_END)
    shutil.copyfileobj(source, target, 1 << 22)


def write_ply(
    path: str | os.PathLike,
    *,
    points: np.ndarray,
    metadata: dict,
    format_version: int = WRITTEN_VERSION,
) -> None:
    """Write points atomically: to a temporary file beside ``path``, then ``os.replace``.

    An interrupted or failed write leaves no partial file at ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its directory must exist.
    points : np.ndarray [shape=(n_points, 5)]
        x, y, z, scalar, hp; stored as little-endian float32.
    metadata : dict
        The ``loudscape-meta`` object; its ``format_version`` is written as ``format_version``.
    format_version : {2, 1}
        See :func:`encode_header`. 1 only for readers that know nothing newer.
    """
    name = os.fspath(path)
    points = np.asarray(points)
    if points.ndim != 2 or points.shape[1] != len(PROPERTIES):
        raise ExtractError(f"points must have shape (n_points, 5), got {points.shape}", path=name)
    directory = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=name)
    header = encode_header(
        n_points=points.shape[0], metadata=metadata, format_version=format_version
    )
    write_atomically(name, [header, np.ascontiguousarray(points, dtype="<f4")])


def write_ply_blocks(
    path: str | os.PathLike,
    *,
    n_points: int,
    metadata: dict,
    blocks: Iterable[np.ndarray],
    format_version: int = WRITTEN_VERSION,
) -> None:
    """Write points as they are produced, atomically (as :func:`write_ply`, same header).

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
    n_points = int(n_points)
    directory = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=name)
    header = encode_header(n_points=n_points, metadata=metadata, format_version=format_version)

    def parts() -> Iterator[bytes | np.ndarray]:
        yield header
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
            yield np.ascontiguousarray(block, dtype="<f4")
        if written != n_points:
            raise ExtractError(
                f"the header promises {n_points} points but {written} were produced",
                path=name,
            )

    write_atomically(name, parts())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --- reading -----------------------------------------------------------------------------------


def read_ply(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read a loudscape PLY file, version 1 or 2.

    Only a regular file is read (a FIFO, a device or a directory is refused at once, without
    blocking); the header is read line by line up to :data:`MAX_HEADER_BYTES`, and the body
    only when the file's size is exactly what the header promises, so the memory used is the
    points' own, whatever else a file holds.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    metadata : dict
        The metadata object ({} when absent), with ``_bytes_b64`` strings decoded.

    Raises
    ------
    ExtractError
        Not a regular file, unreadable, not a loudscape PLY, or bad metadata.
    """
    name = os.fspath(path)
    try:
        with open_regular_input(name) as handle:
            n_points, metadata, offset, size = _read_header(handle, name)
            points = np.empty((n_points, len(PROPERTIES)), dtype="<f4")
            got = handle.readinto(memoryview(points).cast("B")) if n_points else 0
    except OSError as exc:
        raise ExtractError(f"cannot read file ({exc.strerror or exc})", path=name) from exc
    if got != points.nbytes:
        raise ExtractError(
            f"body has {got} bytes, expected {points.nbytes} (the file changed while read)",
            path=name,
        )
    return points.astype(np.float32, copy=False), metadata


#: Bytes of the first line a reader reads: ``ply`` and its line end, with room to spare; a
#: file that is not a PLY is refused after reading no more.
_FIRST_LINE_BYTES = 16


def _first_line(handle, name: str) -> None:
    if handle.readline(_FIRST_LINE_BYTES) not in (b"ply\n", b"ply\r\n"):
        raise ExtractError("not a PLY file (no 'ply' line)", path=name)


def _read_header(handle, name: str) -> tuple[int, dict, int, int]:
    """Read the header of the open file ``handle`` (at its start): ``(n_points, metadata,
    body offset, file size)``, after checking the body's size against the vertex count.
    The rules :func:`read_ply` and :func:`map_ply` share."""
    _first_line(handle, name)
    lines = list(_header_line_iter(handle, name, MAX_HEADER_BYTES))
    offset = handle.tell()
    size = os.fstat(handle.fileno()).st_size
    texts = [text for _, text in lines]
    if "format binary_little_endian 1.0" not in texts:
        raise ExtractError("not a binary little-endian PLY", path=name)
    metadata = _meta_from_lines(lines, name)
    counts = [text.split() for text in texts if text.startswith("element ")]
    properties = [tuple(text.split()[1:]) for text in texts if text.startswith("property ")]
    if (
        len(counts) != 1
        or counts[0][:2] != ["element", "vertex"]
        or properties != [("float", p) for p in PROPERTIES]
    ):
        raise ExtractError(f"unexpected vertex layout {properties}", path=name)
    try:
        n_points = int(counts[0][2])
    except (IndexError, ValueError):
        raise ExtractError(f"bad vertex count {counts[0][2:]}", path=name) from None
    if n_points < 0:
        raise ExtractError(f"negative vertex count {n_points}", path=name)
    expected = n_points * 4 * len(PROPERTIES)
    if size - offset != expected:
        raise ExtractError(f"body has {size - offset} bytes, expected {expected}", path=name)
    return n_points, metadata, offset, size


def _header_line_iter(handle, name: str, max_header_bytes: int) -> Iterator[tuple[int, str]]:
    read = 0
    number = 1
    carry = b""  # the last bytes before the scan below, for an end_header cut across
    while read < max_header_bytes:
        line = handle.readline(max_header_bytes - read)  # bounded: a file without newlines
        if not line:
            raise ExtractError("not a PLY file (no 'end_header')", path=name)
        read += len(line)
        number += 1
        if read >= max_header_bytes and not line.endswith(b"\n"):
            carry = line[-16:]
            line = b""  # a line cut at the limit: never decoded, and not held while scanning
            break
        if line in (b"end_header\n", b"end_header\r\n"):
            return
        yield number, line.decode("ascii", errors="replace").rstrip("\n").removesuffix("\r")
    # Over the limit: say which it is, a header too large or no header at all (the rest of
    # the file is scanned in bounded pieces for end_header).
    while chunk := handle.read(1 << 20):
        if b"\nend_header\n" in carry + chunk:
            raise ExtractError(
                f"the header is larger than the {max_header_bytes / (1 << 20):g} MiB a reader "
                "holds (it does end with end_header; see docs/FORMAT.md, Header size)",
                path=name,
            )
        carry = chunk[-16:]
    raise ExtractError(
        f"not a PLY file (no 'end_header' in its first {max_header_bytes / (1 << 20):g} MiB "
        "or after)",
        path=name,
    )


#: The largest header the readers hold (the app's limit, docs/FORMAT.md "Header size").
MAX_HEADER_BYTES = 64 << 20


def read_ply_metadata(path: str | os.PathLike, *, max_header_bytes: int = MAX_HEADER_BYTES) -> dict:
    """The metadata object of a PLY file (version 1 or 2), reading only its header ({} when
    absent).

    Raises
    ------
    ExtractError
        Unreadable file, not a PLY, a header without ``end_header``, or bad metadata.
    """
    name = os.fspath(path)
    try:
        with open_regular_input(name) as handle:
            _first_line(handle, name)
            return _meta_from_lines(_header_line_iter(handle, name, max_header_bytes), name)
    except OSError as exc:
        raise ExtractError(f"cannot read file ({exc.strerror or exc})", path=name) from exc


def map_ply(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Like :func:`read_ply`, but the points are a read-only memory map of the file's body,
    so a cloud of any size costs no memory until it is read.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype='<f4']
        Read-only.
    metadata : dict
    """
    name = os.fspath(path)
    try:
        with open_regular_input(name) as handle:
            n_points, metadata, offset, _size = _read_header(handle, name)
    except OSError as exc:
        raise ExtractError(f"cannot read file ({exc.strerror or exc})", path=name) from exc
    if n_points == 0:
        return np.zeros((0, len(PROPERTIES)), "<f4"), metadata
    points = np.memmap(name, dtype="<f4", mode="r", offset=offset, shape=(n_points, 5))
    return points, metadata
