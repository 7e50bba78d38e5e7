"""Timeline mode: many songs -> one chronological point cloud (one point per sampled frame).

The per-song work is the Song pipeline's :func:`decode_audio` and :func:`track_features`; this
module keeps only each song's per-frame series and metrics (cached on disk by content hash),
orders the songs by year, samples a fixed number of frames per song and lays them out::

    x  song position (by order or by year)      y  frame RMS level, -60..0 dBFS
    z  frame crest factor (1st..99th pct)       scalar  A-weighted frame level   hp  frame hp
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import re
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

import numpy as np

from loudscape_extract.audio import SUPPORTED_EXTENSIONS
from loudscape_extract.errors import ExtractError

__all__ = [
    "SongEntry",
    "SongFrames",
    "build_timeline",
    "default_cache_dir",
    "discover_audio",
    "read_manifest",
    "read_tags",
    "sample_frames",
    "song_frames",
    "timeline_points",
]

CACHE_VERSION = 1
LEVEL_MIN_DBFS = -60.0
LEVEL_MAX_DBFS = 0.0
SCALAR_FLOOR_DB = -100.0
CREST_PERCENTILES = (1.0, 99.0)
X_BY = ("year", "order")
METRIC_KEYS = (
    "integrated_lufs",
    "lra_lu",
    "sample_peak_dbfs",
    "true_peak_dbtp",
    "plr_db",
    "crest_median_db",
    "crest_p95_db",
    "hp_mean",
)
_YEAR = re.compile(r"(?<!\d)(\d{4})(?!\d)")


@dataclass(frozen=True)
class SongEntry:
    """One song to place: its file, year and (possibly empty) title and artist."""

    path: str
    year: int
    title: str = ""
    artist: str = ""


@dataclass(frozen=True)
class SongFrames:
    """What the timeline keeps of one song: its non-silent frames and metrics.

    Attributes
    ----------
    rms_dbfs, crest_db, loudness_a_db, hp_mean : np.ndarray [shape=(n_frames,)]
        :class:`FrameFeatures` series restricted to the non-silent frames, in time order.
    n_frames_total : int
        All STFT frames, silent ones included.
    metrics : dict
        The Song metrics plus ``hp_mean`` (mean over non-silent frames of the frame hp).
    """

    rms_dbfs: np.ndarray
    crest_db: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    n_frames_total: int
    metrics: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
# Inputs: folders, tags, manifests


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


# ---------------------------------------------------------------------------------------------
# Per-song features, cached


def default_cache_dir() -> str:
    """``$XDG_CACHE_HOME/loudscape``, else ``~/.cache/loudscape``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "loudscape")


def file_sha256(path: str) -> str:
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
    except OSError as exc:
        raise ExtractError(f"cannot read file ({exc.strerror or exc})", path=path) from exc
    return digest.hexdigest()


def cache_key(path: str, *, n_fft: int, hop_length: int) -> str:
    """Content hash of the file plus everything the cached features depend on."""
    return f"{file_sha256(path)}-n{n_fft}-h{hop_length}-v{CACHE_VERSION}"


def _decode(path: str):
    from loudscape_extract.audio import decode_audio

    return decode_audio(path)


def compute_song_frames(path: str, *, n_fft: int, hop_length: int) -> SongFrames:
    """Decode and run :func:`track_features` (the Song pipeline), keep frames and metrics."""
    from loudscape_extract.features import track_features

    audio = _decode(path)
    features = track_features(audio, n_fft=n_fft, hop_length=hop_length)
    del audio
    frames = features.frames
    keep = ~frames.silent
    hp = frames.hp_mean[keep]
    metrics = dict(features.metrics)
    finite = hp[np.isfinite(hp)]
    metrics["hp_mean"] = float(finite.mean()) if finite.size else None
    return SongFrames(
        rms_dbfs=frames.rms_dbfs[keep].astype(np.float32),
        crest_db=frames.crest_db[keep].astype(np.float32),
        loudness_a_db=frames.loudness_a_db[keep].astype(np.float32),
        hp_mean=hp.astype(np.float32),
        n_frames_total=int(frames.silent.shape[0]),
        metrics=metrics,
    )


def _save(path: str, song: SongFrames) -> None:
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    temporary = f"{path}.{os.getpid()}.tmp.npz"
    np.savez(
        temporary,
        rms_dbfs=song.rms_dbfs,
        crest_db=song.crest_db,
        loudness_a_db=song.loudness_a_db,
        hp_mean=song.hp_mean,
        n_frames_total=np.array(song.n_frames_total),
        metrics=np.array(json.dumps(song.metrics)),
    )
    os.replace(temporary, path)


def _load(path: str) -> SongFrames | None:
    try:
        with np.load(path) as data:
            return SongFrames(
                rms_dbfs=data["rms_dbfs"],
                crest_db=data["crest_db"],
                loudness_a_db=data["loudness_a_db"],
                hp_mean=data["hp_mean"],
                n_frames_total=int(data["n_frames_total"]),
                metrics=json.loads(str(data["metrics"])),
            )
    except (OSError, KeyError, ValueError):
        return None  # missing or damaged cache entry: recompute


def song_frames(
    path: str, *, n_fft: int, hop_length: int, cache_dir: str | None
) -> tuple[SongFrames, bool]:
    """One song's frames, from the cache when its content and parameters match.

    Returns
    -------
    song : SongFrames
    cached : bool
        True when read from the cache (no decoding).
    """
    if cache_dir is None:
        return compute_song_frames(path, n_fft=n_fft, hop_length=hop_length), False
    entry = os.path.join(cache_dir, cache_key(path, n_fft=n_fft, hop_length=hop_length) + ".npz")
    song = _load(entry) if os.path.exists(entry) else None
    if song is not None:
        return song, True
    song = compute_song_frames(path, n_fft=n_fft, hop_length=hop_length)
    try:
        _save(entry, song)
    except OSError:
        pass  # a read-only cache only costs speed
    return song, False


def _job(path: str, n_fft: int, hop_length: int, cache_dir: str | None):
    """Worker: (path, SongFrames or None, cached, error message or None)."""
    try:
        song, cached = song_frames(path, n_fft=n_fft, hop_length=hop_length, cache_dir=cache_dir)
        return path, song, cached, None
    except ExtractError as exc:
        return path, None, False, exc.message
    except MemoryError:
        return path, None, False, "out of memory"
    except Exception as exc:  # noqa: BLE001 - one bad song must not stop the timeline
        return path, None, False, " ".join(str(exc).split()) or type(exc).__name__


def compute_all(
    paths: Sequence[str],
    *,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    jobs: int,
    on_done: Callable[[int, str], None] | None = None,
) -> tuple[dict[str, SongFrames], dict[str, str], int]:
    """Features of every path, ``jobs`` worker processes at a time.

    Returns
    -------
    songs : dict path -> SongFrames
    failed : dict path -> reason
    cached : int
        How many came from the cache.
    """
    songs: dict[str, SongFrames] = {}
    failed: dict[str, str] = {}
    n_cached = 0
    done = 0

    def collect(result):
        nonlocal n_cached, done
        path, song, cached, error = result
        done += 1
        if error is None:
            songs[path] = song
            n_cached += cached
        else:
            failed[path] = error
        if on_done:
            on_done(done, path)

    if jobs <= 1 or len(paths) <= 1:
        for path in paths:
            collect(_job(path, n_fft, hop_length, cache_dir))
    else:
        with ProcessPoolExecutor(max_workers=min(jobs, len(paths))) as pool:
            futures = {pool.submit(_job, p, n_fft, hop_length, cache_dir): p for p in paths}
            for future in as_completed(futures):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. a worker killed for memory
                    reason = " ".join(str(exc).split()) or type(exc).__name__
                    result = (futures[future], None, False, f"worker failed ({reason})")
                collect(result)
    return songs, failed, n_cached


# ---------------------------------------------------------------------------------------------
# Layout


def sample_frames(n_frames: int, count: int) -> np.ndarray:
    """Indices of ``count`` frames spread evenly over ``n_frames`` (all of them if fewer)."""
    if n_frames <= count:
        return np.arange(n_frames)
    return np.round(np.linspace(0, n_frames - 1, count)).astype(np.int64)


def sort_entries(entries: Sequence[SongEntry]) -> list[SongEntry]:
    """By year, then artist, then title (case-insensitive), then path."""
    return sorted(entries, key=lambda e: (e.year, e.artist.casefold(), e.title.casefold(), e.path))


def percentile_map(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """``[low, high] -> [-1, 1]``, clamped outside; 0 everywhere when ``low == high``."""
    if not high > low:
        return np.zeros_like(values, dtype=np.float64)
    return np.clip(2.0 * (values - low) / (high - low) - 1.0, -1.0, 1.0)


def song_spans(entries: Sequence[SongEntry], x_by: str) -> list[tuple[float, float]]:
    """Normalized ``(x_min, x_max)`` of each song (entries already sorted)."""
    n = len(entries)
    if x_by == "order":
        return [(2.0 * i / n - 1.0, 2.0 * (i + 1) / n - 1.0) for i in range(n)]
    first, last = entries[0].year, entries[-1].year
    width = last + 1 - first
    spans = []
    for i, entry in enumerate(entries):
        same = [e for e in entries if e.year == entry.year]
        k = sum(1 for e in entries[:i] if e.year == entry.year)
        start = entry.year - first + k / len(same)
        end = entry.year - first + (k + 1) / len(same)
        spans.append((2.0 * start / width - 1.0, 2.0 * end / width - 1.0))
    return spans


def _tick_years(first: int, last: int) -> list[int]:
    if last - first <= 12:
        return list(range(first, last + 1))
    step = 10 if last - first <= 80 else 20
    return [y for y in range(first - first % step, last + 1, step) if y >= first]


def x_axis(entries: Sequence[SongEntry], spans, x_by: str) -> dict:
    first, last = entries[0].year, entries[-1].year
    ticks = []
    if x_by == "year":
        years = _tick_years(first, last)
        width = last + 1 - first
        for year in years:
            ticks.append({"at": round(2.0 * (year - first) / width - 1.0, 6), "label": str(year)})
        return {
            "label": "year",
            "unit": "year",
            "min": first,
            "max": last + 1,
            "scale": "linear",
            "ticks": ticks,
        }
    # By order: a tick at the first song of each year (short ranges) or decade, where one is.
    step = 1 if last - first <= 12 else (10 if last - first <= 80 else 20)
    seen = set()
    for entry, span in zip(entries, spans, strict=True):
        group = entry.year - entry.year % step
        if group not in seen:
            seen.add(group)
            ticks.append({"at": round(span[0], 6), "label": str(max(group, first))})
    return {
        "label": "year",
        "unit": "year",
        "min": first,
        "max": last,
        "scale": "linear",
        "ticks": ticks,
    }


def _round(value, digits=4):
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


def timeline_points(
    entries: Sequence[SongEntry],
    songs: dict[str, SongFrames],
    *,
    frames_per_song: int,
    x_by: str = "year",
) -> tuple[np.ndarray, dict]:
    """Points and the ``axes`` / ``songs`` metadata for songs that all have features.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    layout : dict
        ``axes``, ``songs`` (one object per song, in order), ``crest_percentiles_db``.
    """
    if x_by not in X_BY:
        raise ExtractError(f"x_by must be one of {', '.join(X_BY)}, got {x_by!r}")
    entries = sort_entries(entries)
    all_crest = np.concatenate([songs[e.path].crest_db for e in entries]).astype(np.float64)
    all_crest = all_crest[np.isfinite(all_crest)]
    if all_crest.size:
        crest_low, crest_high = (float(v) for v in np.percentile(all_crest, CREST_PERCENTILES))
    else:
        crest_low = crest_high = 0.0
    spans = song_spans(entries, x_by)
    blocks, described = [], []
    offset = 0
    for entry, (x_min, x_max) in zip(entries, spans, strict=True):
        song = songs[entry.path]
        index = sample_frames(song.rms_dbfs.shape[0], frames_per_song)
        m = index.shape[0]
        x = x_min + (x_max - x_min) * (np.arange(m) + 0.5) / max(m, 1)
        rms = np.nan_to_num(song.rms_dbfs[index].astype(np.float64), nan=-200.0, neginf=-200.0)
        y = np.clip(
            2.0 * (rms - LEVEL_MIN_DBFS) / (LEVEL_MAX_DBFS - LEVEL_MIN_DBFS) - 1.0, -1.0, 1.0
        )
        crest = song.crest_db[index].astype(np.float64)
        z = percentile_map(np.nan_to_num(crest, nan=crest_low), crest_low, crest_high)
        la = np.nan_to_num(song.loudness_a_db[index].astype(np.float64), nan=-200.0, neginf=-200)
        scalar = np.clip((la - SCALAR_FLOOR_DB) / -SCALAR_FLOOR_DB, 0.0, 1.0)
        hp = np.clip(np.nan_to_num(song.hp_mean[index].astype(np.float64), nan=0.5), 0.0, 1.0)
        blocks.append(np.stack([x, y, z, scalar, hp], axis=1))
        described.append(
            {
                "path": entry.path,
                "year": entry.year,
                "title": entry.title,
                "artist": entry.artist,
                "x_min": round(x_min, 6),
                "x_max": round(x_max, 6),
                "point_offset": offset,
                "point_count": int(m),
                "frames_non_silent": int(song.rms_dbfs.shape[0]),
                "frames_total": int(song.n_frames_total),
                "metrics": {k: _round(song.metrics.get(k)) for k in METRIC_KEYS},
            }
        )
        offset += m
    points = np.concatenate(blocks).astype(np.float32) if blocks else np.zeros((0, 5), np.float32)
    axes = {
        "x": x_axis(entries, spans, x_by),
        "y": {
            "label": "level",
            "unit": "dB",
            "min": LEVEL_MIN_DBFS,
            "max": LEVEL_MAX_DBFS,
            "scale": "linear",
        },
        "z": {
            "label": "crest factor",
            "unit": "dB",
            "min": round(crest_low, 6),
            "max": round(crest_high, 6),
            "scale": "linear",
        },
        "scalar": {
            "label": "A-weighted level",
            "unit": "dB",
            "min": SCALAR_FLOOR_DB,
            "max": 0.0,
            "scale": "linear",
        },
        "hp": {
            "label": "harmonic-percussive ratio",
            "unit": "",
            "min": 0.0,
            "max": 1.0,
            "scale": "linear",
        },
    }
    return points, {"axes": axes, "songs": described}


# ---------------------------------------------------------------------------------------------
# End to end


@dataclass
class TimelineResult:
    metadata: dict
    written: int
    failed: dict
    without_year: list
    few_frames: list
    cached: int


def build_timeline(
    inputs: Sequence[str],
    output: str,
    *,
    manifest: str | None = None,
    x_by: str = "year",
    frames_per_song: int = 1024,
    n_fft: int = 2048,
    hop_length: int = 1024,
    cache_dir: str | None = None,
    jobs: int = 1,
    progress: Callable[[int, int, str], None] | None = None,
) -> TimelineResult:
    """Timeline mode end to end; writes ``output`` unless no song at all could be placed.

    Songs that fail to decode are skipped and listed in ``result.failed`` (and in the
    metadata's ``extraction.skipped``); songs without a year likewise in ``without_year``.

    Raises
    ------
    ExtractError
        Bad inputs (missing or empty folder, bad manifest, no years at all, output directory
        missing) or no song could be extracted.
    """
    from loudscape_extract import FORMAT_VERSION, __version__
    from loudscape_extract.cli import PROG, check_output_path
    from loudscape_extract.ply import write_ply

    if x_by not in X_BY:
        raise ExtractError(f"--x-by must be one of {', '.join(X_BY)}, got {x_by!r}")
    check_output_path(output)
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
            elif tags["year"] is None:
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
    paths = [e.path for e in entries]
    total = len(paths)

    def on_done(done, path):
        if progress:
            progress(done, total, path)

    songs, failed, n_cached = compute_all(
        paths,
        n_fft=n_fft,
        hop_length=hop_length,
        cache_dir=cache_dir,
        jobs=jobs,
        on_done=on_done,
    )
    failed.update(tag_failures)
    good = [e for e in entries if e.path in songs]
    if not good:
        first = next(iter(failed.items()))
        raise ExtractError(
            f"none of the {len(failed)} song(s) could be extracted (first: {first[0]}: {first[1]})"
        )
    points, layout = timeline_points(good, songs, frames_per_song=frames_per_song, x_by=x_by)
    few = [s["path"] for s in layout["songs"] if s["point_count"] < frames_per_song]
    metadata = {
        "format_version": FORMAT_VERSION,
        "mode": "timeline",
        "point_count": int(points.shape[0]),
        "axes": layout["axes"],
        "songs": layout["songs"],
        "extraction": {
            "x_by": x_by,
            "frames_per_song": frames_per_song,
            "n_fft": n_fft,
            "hop_length": hop_length,
            "level_range_dbfs": [LEVEL_MIN_DBFS, LEVEL_MAX_DBFS],
            "crest_percentiles": list(CREST_PERCENTILES),
            "skipped": [{"path": p, "reason": r} for p, r in sorted(failed.items())]
            + [{"path": p, "reason": "no year in tags"} for p in without_year],
            "generator": f"{PROG} {__version__}",
        },
    }
    write_ply(output, points=points, metadata=metadata)
    return TimelineResult(
        metadata=metadata,
        written=len(good),
        failed=failed,
        without_year=without_year,
        few_frames=few,
        cached=n_cached,
    )
