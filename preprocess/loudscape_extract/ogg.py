"""Ogg page walk: mid-stream damage that the decoders pass over in silence.

libsndfile's Vorbis and Opus decoders skip or misread a damaged page without an error (64
flipped bytes in the middle of an Opus file lose a quarter of it; in Vorbis they decode as
noise), so :func:`ogg_damage` walks every page of the file and checks what the container
itself guarantees: each page's CRC32 (RFC 3533: polynomial 0x04C11DB7, not reflected, initial
value 0, computed over the page with its CRC field zeroed), that pages follow each other with
no bytes between them, and that each stream's page sequence numbers do not jump.
"""

from __future__ import annotations

import mmap
import os
import struct
import zlib

__all__ = ["ogg_crc", "ogg_damage"]

_CAPTURE = b"OggS"
_HEADER = struct.Struct("<4sBBqIIIB")  # capture, version, flags, granule, serial, seq, crc, n
_REVERSED = bytes(int(f"{b:08b}"[::-1], 2) for b in range(256))


def _reverse32(value: int) -> int:
    return int(f"{value:032b}"[::-1], 2)


def ogg_crc(data: bytes) -> int:
    """Ogg's CRC32 of ``data`` (RFC 3533). Computed with zlib's reflected CRC-32 on the
    bit-reversed bytes (same polynomial; the reflections cancel), so it runs at C speed."""
    raw = zlib.crc32(data.translate(_REVERSED), 0xFFFFFFFF) ^ 0xFFFFFFFF
    return _reverse32(raw)


def _codec_rate(body: bytes) -> tuple[int, int]:
    """(granule rate, pre-skip) of the stream whose first page body is ``body``."""
    if body[:7] == b"\x01vorbis" and len(body) >= 16:
        return struct.unpack_from("<I", body, 12)[0], 0
    if body[:8] == b"OpusHead" and len(body) >= 12:
        return 48000, struct.unpack_from("<H", body, 10)[0]
    return 0, 0


def ogg_damage(path: str) -> str:
    """One sentence about pages failing their CRC, bytes between pages that are no page, or
    pages missing from a stream's sequence; ``""`` when every page is intact (or the file is
    not Ogg at all, or cannot be read: the decoder reports that)."""
    try:
        with open(path, "rb") as handle:
            size = os.fstat(handle.fileno()).st_size
            if size < _HEADER.size:
                return ""
            with mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ) as data:
                return _walk(data, size)
    except (OSError, ValueError):
        return ""


def _walk(data, size: int) -> str:
    pages = bad = junk = missing = 0
    first_bad_at: int | None = None
    first_bad_time: float | None = None
    streams: dict[int, list] = {}  # serial -> [next sequence, rate, pre-skip, last granule]
    offset = 0
    while offset + _HEADER.size <= size:
        if data[offset : offset + 4] != _CAPTURE:
            found = data.find(_CAPTURE, offset + 1)
            end = size if found < 0 else found
            junk += end - offset
            if first_bad_at is None:
                first_bad_at = offset
            if found < 0:
                break
            offset = found
            continue
        _, version, _flags, granule, serial, sequence, crc, n_segments = _HEADER.unpack_from(
            data, offset
        )
        table_end = offset + _HEADER.size + n_segments
        if version != 0 or table_end > size:
            junk += 4  # a capture pattern inside damaged data: look further
            first_bad_at = offset if first_bad_at is None else first_bad_at
            offset += 4
            continue
        length = _HEADER.size + n_segments + sum(data[offset + _HEADER.size : table_end])
        if offset + length > size:
            break  # the last page cut short: the end-of-stream check reports it
        page = bytearray(data[offset : offset + length])
        page[22:26] = b"\0\0\0\0"
        pages += 1
        stream = streams.setdefault(serial, [sequence, 0, 0, None])
        if sequence == 0 and stream[1] == 0:
            stream[1], stream[2] = _codec_rate(bytes(page[_HEADER.size + n_segments :]))
        if ogg_crc(bytes(page)) != crc:
            bad += 1
            if first_bad_at is None:
                first_bad_at = offset
                if stream[1] and stream[3] is not None:
                    first_bad_time = max(stream[3] - stream[2], 0) / stream[1]
            stream[0] = None  # its sequence number may be damaged too
        else:
            if stream[0] is not None and sequence > stream[0]:
                missing += sequence - stream[0]
            stream[0] = sequence + 1
            if granule >= 0:
                stream[3] = granule
        offset += length
    if not (bad or junk or missing):
        return ""
    parts = []
    if bad:
        parts.append(f"{bad} of {pages} Ogg pages fail their CRC check")
    if junk:
        parts.append(f"{junk} bytes between Ogg pages are not Ogg data")
    if missing:
        parts.append(f"{missing} Ogg page(s) missing from the sequence")
    where = f"; the first damage at byte {first_bad_at}" if first_bad_at is not None else ""
    when = f" (about {first_bad_time:.2f} s in)" if first_bad_time is not None else ""
    return "; ".join(parts) + where + when + "; the decoder skips or misreads damaged pages"
