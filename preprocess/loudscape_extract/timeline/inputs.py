"""Timeline inputs: audio files found in folders, their tags, and manifests (CSV)."""

from __future__ import annotations

import csv
import datetime
import io
import os
import re
import stat
from collections.abc import Sequence
from dataclasses import dataclass

from loudscape_extract.audio import SUPPORTED_EXTENSIONS
from loudscape_extract.errors import ExtractError
from loudscape_extract.messages import shorten
from loudscape_extract.paths import check_regular_input

__all__ = [
    "FIRST_YEAR",
    "SongEntry",
    "collect_entries",
    "discover_audio",
    "manifest_entries",
    "parse_year",
    "plausible_years",
    "read_manifest",
    "read_tags",
]

#: The earliest plausible release year (the first recordings of sound); the latest is next year.
FIRST_YEAR = 1860
_YEAR = re.compile(r"(?<!\d)(\d{4})(?!\d)")


@dataclass(frozen=True)
class SongEntry:
    """One song to place: its file, year (None only when placed by order) and (possibly
    empty) title and artist."""

    path: str
    year: int | None
    title: str = ""
    artist: str = ""


def discover_audio(inputs: Sequence[str], *, skipped: dict | None = None) -> list[str]:
    """Audio files among ``inputs`` (files as given; folders searched recursively), sorted.

    In a folder, a name with an audio extension that is not a regular file (a broken symbolic
    link, a FIFO, which would block its reader forever, a device) is passed over and,
    when ``skipped`` is given, put there with the reason (path -> reason)."""
    found: list[str] = []
    for item in inputs:
        if os.path.isdir(item):
            for root, dirs, files in os.walk(item):
                dirs.sort()
                for name in sorted(files):
                    full = os.path.join(root, name)
                    if not _audio_name(name):
                        continue
                    reason = _not_regular(full)
                    if not reason:
                        found.append(full)
                    elif skipped is not None:
                        skipped[full] = reason
        elif os.path.exists(item):
            check_regular_input(item)
            found.append(item)
        else:
            raise ExtractError("no such file or folder", path=item)
    if not found:
        listed = ", ".join(inputs)
        passed = ""
        if skipped:
            first, why = next(iter(skipped.items()))
            passed = f"; {len(skipped)} passed over, first: {first}: {why}"
        raise ExtractError(
            f"no audio files found (looked for {', '.join(SUPPORTED_EXTENSIONS)}){passed}",
            path=listed,
        )
    return found


def _audio_name(name: str) -> bool:
    return os.path.splitext(name)[1].lower() in SUPPORTED_EXTENSIONS


def _not_regular(path: str) -> str:
    """Why ``path`` is not a regular file to read (``""`` when it is one)."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        if os.path.islink(path):
            try:
                target = os.readlink(path)
            except OSError:
                target = "?"
            return f"broken symbolic link (its target {shorten(target)} does not exist)"
        return "vanished while the folder was read"
    except OSError as exc:
        return f"cannot read file ({exc.strerror or exc})"
    if stat.S_ISREG(info.st_mode):
        return ""
    kind = (
        "a directory"
        if stat.S_ISDIR(info.st_mode)
        else "a FIFO (named pipe)"
        if stat.S_ISFIFO(info.st_mode)
        else "a device or socket"
    )
    return f"not a regular file: {kind}"


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


def plausible_years() -> tuple[int, int]:
    """The years a song may have: :data:`FIRST_YEAR` (recorded sound) to next year."""
    return FIRST_YEAR, datetime.date.today().year + 1


def _year_problem(year: int) -> str:
    low, high = plausible_years()
    if low <= year <= high:
        return ""
    return f"year {year} is outside the plausible {low}-{high}"


def read_manifest(path: str, *, need_year: bool = True) -> list[SongEntry]:
    """Songs from a CSV with columns ``path``, ``year`` and optionally ``title``, ``artist``.

    CSV as Python's csv module reads it (a comma inside a value needs double quotes). Paths are
    relative to the manifest's folder. Blank lines and empty trailing cells (a trailing comma)
    are ignored. Every problem raises :class:`ExtractError` naming the manifest, the line and
    the offending value; a line with more cells than the header (an unquoted comma) is one,
    and so is a quoted value that is never closed or runs over lines. A blank year is an
    error when ``need_year`` (``--x-by year``); otherwise (``--x-by order``) the song has no
    year and is placed after the dated ones.
    """
    return [entry for entry, _line in manifest_entries(path, need_year=need_year)]


def manifest_entries(path: str, *, need_year: bool = True) -> list[tuple[SongEntry, int]]:
    """:func:`read_manifest`'s entries with the line each came from."""
    check_regular_input(path, what="manifest file")
    folder = os.path.dirname(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            records = _csv_records(handle, path)
    except OSError as exc:
        raise ExtractError(f"cannot read manifest ({exc.strerror or exc})", path=path) from exc
    except UnicodeDecodeError as exc:
        raise ExtractError(
            f"manifest is not UTF-8 text (bad byte at offset {exc.start})", path=path
        ) from exc
    if not records:
        raise ExtractError("manifest is empty (expected a header line path,year)", path=path)
    header_line, header = records[0]
    columns = [cell.strip().lower() for cell in header]
    while columns and not columns[-1]:
        columns.pop()  # a trailing comma on the header line
    missing = {"path", "year"} - set(columns)
    if missing:
        raise ExtractError(
            f"line {header_line}: manifest needs columns path and year; missing "
            f"{', '.join(sorted(missing))} (has {shorten(','.join(columns), 120)})",
            path=path,
        )
    entries = []
    for line, cells in records[1:]:
        cells = [cell.strip() for cell in cells]
        while len(cells) > len(columns) and not cells[-1]:
            cells.pop()  # trailing commas
        if len(cells) > len(columns):
            raise ExtractError(
                f"line {line}: {len(cells)} values but the header has {len(columns)} columns "
                f'(an unquoted comma? quote such values: "Hello, World")',
                path=path,
            )
        row = dict(zip(columns, cells + [""] * (len(columns) - len(cells)), strict=True))
        if not row.get("path"):
            raise ExtractError(f"line {line}: empty path", path=path)
        song = os.path.join(folder, row["path"])
        if not os.path.exists(song):
            raise ExtractError(f"line {line}: no such file {shorten(song)}", path=path)
        if not os.path.isfile(song):
            raise ExtractError(f"line {line}: {shorten(song)} is not a regular file", path=path)
        if not row.get("year") and not need_year:
            entry = SongEntry(song, None, row.get("title", ""), row.get("artist", ""))
            entries.append((entry, line))
            continue
        if not row.get("year"):
            raise ExtractError(
                f"line {line}: no year for {shorten(row['path'])} (placing songs by year needs "
                "one; --x-by order places songs without one after the dated ones)",
                path=path,
            )
        try:
            year = int(row.get("year", ""))
        except ValueError:
            raise ExtractError(
                f"line {line}: year {shorten(row.get('year'), 40)} of {shorten(row['path'])} "
                "is not a whole number",
                path=path,
            ) from None
        problem = _year_problem(year)
        if problem:
            raise ExtractError(f"line {line}: {problem} ({shorten(row['path'])})", path=path)
        entries.append((SongEntry(song, year, row.get("title", ""), row.get("artist", "")), line))
    if not entries:
        raise ExtractError("manifest lists no songs", path=path)
    return entries


def _csv_records(handle, path: str) -> list[tuple[int, list[str]]]:
    """Non-blank CSV records, each with the line it starts on.

    Strict CSV: a double quote that is never closed, or a quoted value running over several
    lines (an unbalanced quote in a line above swallows the lines after it), is an error
    naming the line where the value starts, never a title holding the next rows."""
    text = handle.read()
    lines = text.splitlines()
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    records = []
    line = 1
    while True:
        try:
            cells = next(reader)
        except StopIteration:
            return records
        except csv.Error as exc:
            if "end of data" in str(exc):
                start = shorten(lines[line - 1] if line <= len(lines) else "", 60)
                raise ExtractError(
                    f"line {line}: a double quote in {start} is never closed (an unbalanced "
                    'quote; inside a quoted value write a quote as "")',
                    path=path,
                ) from None
            raise ExtractError(f"line {reader.line_num}: bad CSV ({exc})", path=path) from None
        if any("\n" in cell or "\r" in cell for cell in cells):
            raise ExtractError(
                f"line {line}: a quoted value runs over lines {line}-{reader.line_num} (an "
                "unbalanced double quote?); every manifest value must be on one line",
                path=path,
            )
        if any(cell.strip() for cell in cells):
            records.append((line, cells))
        line = reader.line_num + 1


def _drop_duplicates(entries, describe) -> tuple[list, list[str]]:
    """Keep the first of entries naming one file (same device and inode); messages for the rest."""
    seen: dict[tuple[int, int], object] = {}
    kept, notes = [], []
    for item in entries:
        entry = item[0] if isinstance(item, tuple) else item
        try:
            info = os.stat(entry.path)
            key = (info.st_dev, info.st_ino)
        except OSError:
            kept.append(item)
            continue
        if key in seen:
            notes.append(describe(item, seen[key]))
            continue
        seen[key] = item
        kept.append(item)
    return kept, notes


def collect_entries(
    inputs: Sequence[str], *, manifest: str | None = None, need_year: bool = True
) -> tuple[list[SongEntry], list[str], dict[str, str], list[str]]:
    """The songs to place, from ``manifest`` or from the tags of the files under ``inputs``.

    Returns
    -------
    entries : list of SongEntry
        Songs with a year, in discovery (or manifest) order.
    without_year : list of str
        Files whose tags have no year (left out when ``need_year``; with ``need_year=False``,
        for ``x_by="order"``, they are placed after the dated songs and this is empty).
    tag_failures : dict path -> reason
        Files whose tags could not be read or give an implausible year.
    duplicates : list of str
        One message per file listed again (another path, a link): it is kept once.

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
        numbered, notes = _drop_duplicates(
            manifest_entries(manifest, need_year=need_year),
            lambda item, first: (
                f"{manifest}: line {item[1]}: {item[0].path} is the same file "
                f"as line {first[1]} ({first[0].path}); kept once"
            ),
        )
        entries = [entry for entry, _line in numbered]
    else:
        if not inputs:
            raise ExtractError("no input: give folders or files, or --manifest songs.csv")
        found, notes = _drop_duplicates(
            [SongEntry(path, 0) for path in discover_audio(inputs, skipped=tag_failures)],
            lambda item, first: f"{item.path}: the same file as {first.path}; kept once",
        )
        entries = []
        for path in (entry.path for entry in found):
            tags = read_tags(path)
            year_problem = "" if tags["year"] is None else _year_problem(tags["year"])
            if tags["error"]:
                tag_failures[path] = tags["error"]
            elif year_problem:
                tag_failures[path] = (
                    f"{year_problem} (from its tags); fix the tag or use --manifest"
                )
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
    return entries, without_year, tag_failures, notes
