"""Timeline inputs: audio files found in folders, their tags, and manifests (CSV)."""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass

from loudscape_extract.audio import SUPPORTED_EXTENSIONS
from loudscape_extract.errors import ExtractError

__all__ = [
    "SongEntry",
    "collect_entries",
    "discover_audio",
    "parse_year",
    "read_manifest",
    "read_tags",
]

_YEAR = re.compile(r"(?<!\d)(\d{4})(?!\d)")


@dataclass(frozen=True)
class SongEntry:
    """One song to place: its file, year (None only when placed by order) and (possibly
    empty) title and artist."""

    path: str
    year: int | None
    title: str = ""
    artist: str = ""


def discover_audio(inputs: Sequence[str]) -> list[str]:
    """Audio files among ``inputs`` (files as given; folders searched recursively), sorted."""
    found: list[str] = []
    for item in inputs:
        if os.path.isdir(item):
            for root, dirs, files in os.walk(item):
                dirs.sort()
                for name in sorted(files):
                    if os.path.splitext(name)[1].lower() in SUPPORTED_EXTENSIONS:
                        found.append(os.path.join(root, name))
        elif os.path.exists(item):
            found.append(item)
        else:
            raise ExtractError("no such file or folder", path=item)
    if not found:
        listed = ", ".join(inputs)
        raise ExtractError(
            f"no audio files found (looked for {', '.join(SUPPORTED_EXTENSIONS)})", path=listed
        )
    return found


def parse_year(text: object) -> int | None:
    """The first four-digit year in a tag value such as ``"1984-05-01"``; None if none."""
    if text is None:
        return None
    match = _YEAR.search(str(text))
    return int(match.group(1)) if match else None


def read_tags(path: str) -> dict:
    """Year, title and artist from the file's tags (mutagen); missing values are None / "".

    Reads ID3 (TDRC, or TYER in ID3v2.3, which mutagen upgrades to TDRC), Vorbis comments
    (ogg, opus, flac: DATE or YEAR) and MP4 (``\\xa9day``).
    """
    import mutagen

    result = {"year": None, "title": "", "artist": "", "error": None}
    try:
        tags = mutagen.File(path, easy=True)
    except Exception as exc:  # noqa: BLE001 - reported as this file's failure
        reason = " ".join(str(exc).split()) or type(exc).__name__
        result["error"] = f"cannot read tags, corrupt or unreadable ({reason})"
        return result
    if tags is None:
        result["error"] = "cannot read tags: not a recognised audio file (corrupt?)"
        return result
    if tags.tags is None:
        return result

    def first(*keys):
        for key in keys:
            try:
                values = tags.get(key)
            except (KeyError, ValueError):
                values = None
            if values:
                return str(values[0] if isinstance(values, list) else values)
        return None

    result["year"] = parse_year(first("date", "year", "originaldate"))
    result["title"] = first("title") or ""
    result["artist"] = first("artist", "albumartist") or ""
    return result


def read_manifest(path: str) -> list[SongEntry]:
    """Songs from a CSV with columns ``path``, ``year`` and optionally ``title``, ``artist``.

    Paths are relative to the manifest's folder. Every problem raises :class:`ExtractError`
    naming the manifest, the line and the offending value.
    """
    if not os.path.isfile(path):
        raise ExtractError("no such manifest file", path=path)
    folder = os.path.dirname(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            reader = csv.DictReader(handle)
            rows = list(reader)
            columns = [(c or "").strip().lower() for c in (reader.fieldnames or [])]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ExtractError(f"cannot read manifest ({exc})", path=path) from exc
    missing = {"path", "year"} - set(columns)
    if missing:
        raise ExtractError(
            f"manifest needs columns path and year; missing {', '.join(sorted(missing))} "
            f"(has {', '.join(columns) or 'none'})",
            path=path,
        )
    entries = []
    for line, row in enumerate(rows, start=2):
        row = {(k or "").strip().lower(): (v or "").strip() for k, v in row.items()}
        if not row.get("path"):
            raise ExtractError(f"line {line}: empty path", path=path)
        song = os.path.join(folder, row["path"])
        if not os.path.isfile(song):
            raise ExtractError(f"line {line}: no such file {song!r}", path=path)
        try:
            year = int(row.get("year", ""))
        except ValueError:
            raise ExtractError(
                f"line {line}: year {row.get('year')!r} of {row['path']!r} is not a whole number",
                path=path,
            ) from None
        if not 1000 <= year <= 9999:
            raise ExtractError(f"line {line}: year {year} is not a four-digit year", path=path)
        entries.append(SongEntry(song, year, row.get("title", ""), row.get("artist", "")))
    if not entries:
        raise ExtractError("manifest lists no songs", path=path)
    return entries


def collect_entries(
    inputs: Sequence[str], *, manifest: str | None = None, need_year: bool = True
) -> tuple[list[SongEntry], list[str], dict[str, str]]:
    """The songs to place, from ``manifest`` or from the tags of the files under ``inputs``.

    Returns
    -------
    entries : list of SongEntry
        Songs with a year, in discovery (or manifest) order.
    without_year : list of str
        Files whose tags have no year (left out when ``need_year``; with ``need_year=False``,
        for ``x_by="order"``, they are placed after the dated songs and this is empty).
    tag_failures : dict path -> reason
        Files whose tags could not be read.

    Raises
    ------
    ExtractError
        Both or neither of inputs and manifest, a bad manifest, or no usable song at all.
    """
    without_year: list[str] = []
    tag_failures: dict[str, str] = {}
    if manifest is not None:
        if inputs:
            raise ExtractError("give either folders/files or --manifest, not both")
        entries = read_manifest(manifest)
    else:
        if not inputs:
            raise ExtractError("no input: give folders or files, or --manifest songs.csv")
        entries = []
        for path in discover_audio(inputs):
            tags = read_tags(path)
            if tags["error"]:
                tag_failures[path] = tags["error"]
            elif tags["year"] is None and need_year:
                without_year.append(path)
            else:
                entries.append(SongEntry(path, tags["year"], tags["title"], tags["artist"]))
        if not entries and not without_year:
            first = next(iter(tag_failures.items()))
            raise ExtractError(
                f"none of the {len(tag_failures)} audio file(s) could be read "
                f"(first: {first[0]}: {first[1]})",
                path=", ".join(inputs),
            )
        if not entries:
            raise ExtractError(
                f"none of the {len(without_year)} audio file(s) has a year in its tags "
                f"(first: {without_year[0]}); tag them or use --manifest",
                path=", ".join(inputs),
            )
    return entries, without_year, tag_failures
