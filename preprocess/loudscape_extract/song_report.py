"""``loudscape-extract report SONG``: one song's loudness report, and a folder of them at once.

What a mastering engineer checks a master with, from an audio file (measured here through the
streamed pipeline, :func:`~loudscape_extract.stream.stream_track`) or a Song-mode cloud (its
``metrics`` and ``loudness`` curves, docs/FORMAT.md):

- the EBU Mode readings (integrated loudness, LRA, true peak, max momentary and short-term
  loudness where the metrics carry them), PLR, PSR median, DR;
- each streaming service's playback gain and the level as heard
  (:mod:`loudscape_extract.normalization`);
- a verdict against a delivery target: a normalization preset (:func:`preset_target`) or a
  loudness and true-peak ceiling of one's own.

:func:`summary_row` is the one row of numbers a song gets, the same in ``--csv`` and in a
folder's ``summary.csv``. The page itself is drawn by :mod:`loudscape_extract.report_pdf`.
Songs measured from audio are cached in the timeline's cache folder, keyed as its entries
are (content hash, parameters, :data:`CACHE_VERSION`), each a checksummed JSON file
(``.loudness``): the timeline's ``.frames`` entries keep per-frame series of the non-silent
frames only, without the 100 ms curves and true-peak overs a report draws.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import signal
import socket
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field

from loudscape_extract.csv_table import write_csv
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import MODE_SONG, MODE_TIMELINE, rounded
from loudscape_extract.interrupts import Terminated
from loudscape_extract.messages import shorten
from loudscape_extract.normalization import PRESETS, normalization_gain
from loudscape_extract.notices import track_warnings
from loudscape_extract.paths import check_output_path, check_regular_input, fsync_directory
from loudscape_extract.ply import read_ply_metadata
from loudscape_extract.report_pdf import PAGE_EXTENSIONS, draw_page, require_matplotlib
from loudscape_extract.stream import stream_track
from loudscape_extract.timeline.cache import cache_key, remove_temporaries
from loudscape_extract.timeline.engine import stop_pool, worker_start
from loudscape_extract.timeline.inputs import discover_audio

__all__ = [
    "DELIVERY_PEAK_DBTP",
    "ENTRY_SUFFIX",
    "SUMMARY_COLUMNS",
    "TARGET_CHOICES",
    "FolderReport",
    "SongLoudness",
    "Target",
    "Verdict",
    "check_target",
    "input_kind",
    "load_song",
    "preset_target",
    "song_loudness",
    "summary_row",
    "write_folder_report",
    "write_song_report",
]

#: The STFT the streamed pass runs with (it decides only the frame crest factors).
_N_FFT, _HOP = 2048, 1024
#: The true-peak ceiling a preset's delivery check uses where the preset has none of its own:
#: -1 dBTP (EBU R 128, and what Spotify and YouTube ask of masters), -2 dBTP for ATSC A/85.
DELIVERY_PEAK_DBTP = {"atsc_a85": -2.0}
_DEFAULT_PEAK_DBTP = -1.0
#: ``--target`` choices: the normalization presets' keys.
TARGET_CHOICES = tuple(PRESETS)
#: Cache entries of this module end with this (beside the timeline's ``.frames``).
ENTRY_SUFFIX = ".loudness"
_MAGIC = b"loudscape-loudness 1 "
_READINGS = (
    "integrated_lufs",
    "lra_lu",
    "true_peak_dbtp",
    "sample_peak_dbfs",
    "max_momentary_lufs",
    "max_momentary_s",
    "max_short_term_lufs",
    "max_short_term_s",
    "plr_db",
    "psr_median_db",
    "dr_db",
)
#: The columns of ``--csv`` and of a folder's ``summary.csv``, one row a song.
SUMMARY_COLUMNS = (
    ("song", "path", "duration_s")
    + _READINGS
    + ("overs_0dbtp_count", "overs_1dbtp_count")
    + tuple(f"{key}_{what}" for key in PRESETS for what in ("gain_db", "heard_lufs"))
    + ("target", "target_lufs", "target_max_true_peak_dbtp", "verdict", "warnings")
)
_CURVE_LISTS = ("momentary_lufs", "short_term_lufs", "psr_db")
_HOSTNAME = socket.gethostname()


@dataclass(frozen=True)
class SongLoudness:
    """What a report shows of one song.

    Attributes
    ----------
    name : str
        The song's file name (an audio file's, or the cloud's source).
    path : str
        The input as given.
    duration_s, sample_rate, channels
        Of the audio (None where a cloud does not say).
    metrics : dict
        The Song metrics (docs/FORMAT.md), finite numbers or None.
    curves : dict or None
        The ``loudness`` object (:func:`~loudscape_extract.curves.loudness_curves`); None for
        a cloud written before curves existed.
    warnings : list of str
        One line each: the decoder's and the signal's warnings.
    """

    name: str
    path: str
    duration_s: float | None
    sample_rate: int | None
    channels: int | None
    metrics: dict
    curves: dict | None
    warnings: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Target:
    """A delivery target: integrated loudness within ``tolerance_lu`` of ``lufs`` (when
    given) and the true peak at or below ``max_true_peak_dbtp``."""

    name: str
    lufs: float | None
    max_true_peak_dbtp: float
    tolerance_lu: float = 1.0


@dataclass(frozen=True)
class Verdict:
    """The check of a song against a :class:`Target`: ``passed`` and one line saying why."""

    passed: bool
    text: str


def preset_target(key: str, *, tolerance_lu: float = 1.0) -> Target:
    """The delivery target of a normalization preset: its loudness, and its true-peak ceiling
    (:data:`DELIVERY_PEAK_DBTP`, else the preset's own, else -1 dBTP).

    >>> preset_target("spotify")
    Target(name='Spotify (normal)', lufs=-14.0, max_true_peak_dbtp=-1.0, tolerance_lu=1.0)
    """
    if key not in PRESETS:
        raise ExtractError(f"--target must be one of {', '.join(PRESETS)}, got {key!r}")
    preset = PRESETS[key]
    peak = DELIVERY_PEAK_DBTP.get(key, preset.ceiling_dbtp)
    return Target(
        preset.name,
        preset.target_lufs,
        _DEFAULT_PEAK_DBTP if peak is None else peak,
        tolerance_lu,
    )


def _db(value: float, unit: str) -> str:
    return f"{value:+.1f} {unit}" if unit == "dBTP" else f"{value:.1f} {unit}"


def check_target(metrics: dict, target: Target) -> Verdict:
    """Pass when the integrated loudness is within the tolerance of the target's and the true
    peak at or below its ceiling; the text names each reading against its limit.

    >>> verdict = check_target(
    ...     {"integrated_lufs": -9.6, "true_peak_dbtp": 0.4}, preset_target("spotify")
    ... )
    >>> print(verdict.text)  # doctest: +NORMALIZE_WHITESPACE
    FAIL Spotify (normal): -9.6 LUFS is 4.4 LU above -14.0 LUFS (1.0 LU allowed);
    true peak +0.4 dBTP is over -1.0 dBTP
    """
    parts, passed = [], True
    integrated, peak = metrics.get("integrated_lufs"), metrics.get("true_peak_dbtp")
    if target.lufs is not None:
        if integrated is None:
            passed = False
            parts.append("no integrated loudness (silent or under 400 ms)")
        else:
            off = integrated - target.lufs
            if abs(off) <= target.tolerance_lu + 1e-9:
                parts.append(
                    f"{_db(integrated, 'LUFS')} is within {target.tolerance_lu:.1f} LU of "
                    f"{_db(target.lufs, 'LUFS')}"
                )
            else:
                passed = False
                side = "above" if off > 0 else "below"
                parts.append(
                    f"{_db(integrated, 'LUFS')} is {abs(off):.1f} LU {side} "
                    f"{_db(target.lufs, 'LUFS')} ({target.tolerance_lu:.1f} LU allowed)"
                )
    if peak is None:
        parts.append("no true peak (digital silence)")
    elif peak <= target.max_true_peak_dbtp + 1e-9:
        parts.append(
            f"true peak {_db(peak, 'dBTP')} is at or below {_db(target.max_true_peak_dbtp, 'dBTP')}"
        )
    else:
        passed = False
        parts.append(
            f"true peak {_db(peak, 'dBTP')} is over {_db(target.max_true_peak_dbtp, 'dBTP')}"
        )
    word = "PASS" if passed else "FAIL"
    return Verdict(passed, f"{word} {target.name}: " + "; ".join(parts))


def heard_levels(metrics: dict) -> dict[str, tuple[float | None, float | None]]:
    """``{preset key: (gain_db, heard_lufs)}`` for every normalization preset."""
    integrated = metrics.get("integrated_lufs")
    out = {}
    for key, preset in PRESETS.items():
        gain = normalization_gain(
            preset, integrated_lufs=integrated, true_peak_dbtp=metrics.get("true_peak_dbtp")
        )
        out[key] = (gain, None if gain is None or integrated is None else integrated + gain)
    return out


def summary_row(song: SongLoudness, target: Target | None = None) -> dict:
    """The song's row of :data:`SUMMARY_COLUMNS`."""
    metrics = song.metrics
    row = {"song": song.name, "path": song.path, "duration_s": song.duration_s}
    row.update({key: metrics.get(key) for key in _READINGS})
    curves = song.curves or {}
    for key in ("overs_0dbtp_count", "overs_1dbtp_count"):
        row[key] = curves.get(key)
    for key, (gain, heard) in heard_levels(metrics).items():
        row[f"{key}_gain_db"], row[f"{key}_heard_lufs"] = gain, heard
    if target is not None:
        verdict = check_target(metrics, target)
        row.update(
            target=target.name,
            target_lufs=target.lufs,
            target_max_true_peak_dbtp=target.max_true_peak_dbtp,
            verdict="pass" if verdict.passed else "fail",
        )
    row["warnings"] = "; ".join(song.warnings)
    return row


def input_kind(path: str) -> str:
    """``"folder"``, ``"timeline"`` (a timeline cloud: the per-year report), ``"cloud"`` (a
    Song-mode cloud) or ``"audio"``."""
    if os.path.isdir(path):
        return "folder"
    if os.path.splitext(path)[1].lower() != ".ply":
        return "audio"
    check_regular_input(path)
    mode = read_ply_metadata(path).get("mode")
    return "timeline" if mode == MODE_TIMELINE else "cloud"


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _curves_problem(curves: object) -> str:
    """Why ``curves`` is not a usable ``loudness`` object (``""`` when it is)."""
    if not isinstance(curves, dict):
        return "is not an object"
    rate = curves.get("rate_hz")
    if not _number(rate) or not 0 < rate <= 1000:
        return f"rate_hz is {shorten(rate, 20)}"
    for key in ("momentary_start_s", "short_term_start_s"):
        if not _number(curves.get(key)):
            return f"{key} is not a number"
    for key in _CURVE_LISTS:
        values = curves.get(key)
        if not isinstance(values, list) or any(v is not None and not _number(v) for v in values):
            return f"{key} is not a list of numbers and nulls"
    for key in ("overs_0dbtp", "overs_1dbtp"):
        spans = curves.get(key, [])
        ok = isinstance(spans, list) and all(
            isinstance(s, list) and len(s) == 2 and all(_number(v) for v in s) for s in spans
        )
        if not ok or not _number(curves.get(f"{key}_count", 0)):
            return f"{key} is not a list of [start_s, end_s] intervals"
    return ""


def _clean_metrics(metrics: object, path: str) -> dict:
    if not isinstance(metrics, dict):
        raise ExtractError("the cloud has no metrics object: not a song cloud", path=path)
    return {key: value if _number(value) else None for key, value in metrics.items()}


def song_from_cloud(path: str) -> SongLoudness:
    """A Song-mode cloud's metrics, curves and warnings (its metadata only is read).

    Raises
    ------
    ExtractError
        Not a readable PLY, not Song mode, no metrics, or malformed curves.
    """
    metadata = read_ply_metadata(path)
    if not isinstance(metadata, dict) or metadata.get("mode") != MODE_SONG:
        mode = metadata.get("mode") if isinstance(metadata, dict) else None
        raise ExtractError(
            f"not a song cloud (mode {shorten(mode, 40) if mode else 'missing'}); "
            "give an audio file, a song cloud or a timeline",
            path=path,
        )
    metrics = _clean_metrics(metadata.get("metrics"), path)
    curves = metadata.get("loudness")
    if curves is not None:
        problem = _curves_problem(curves)
        if problem:
            raise ExtractError(f"the cloud's loudness curves are malformed: {problem}", path=path)
    source = metadata.get("source") if isinstance(metadata.get("source"), dict) else {}
    source_path = source.get("path") if isinstance(source.get("path"), str) else ""
    items = metadata.get("warnings") if isinstance(metadata.get("warnings"), list) else []
    return SongLoudness(
        name=os.path.basename(source_path) or os.path.basename(path),
        path=path,
        duration_s=source.get("duration_s") if _number(source.get("duration_s")) else None,
        sample_rate=source.get("sample_rate") if _number(source.get("sample_rate")) else None,
        channels=source.get("channels") if _number(source.get("channels")) else None,
        metrics=metrics,
        curves=curves,
        warnings=[str(i.get("message")) for i in items if isinstance(i, dict)],
    )


def song_loudness(path: str, *, strict: bool = False) -> SongLoudness:
    """Measure an audio file: metrics and curves of the streamed pipeline (no points).

    Raises
    ------
    ExtractError
        As :func:`~loudscape_extract.stream.stream_track`.
    """
    track = stream_track(path, n_fft=_N_FFT, hop_length=_HOP, frame_hp=False, strict=strict)
    found = track_warnings(decode_warning=track.warning, metrics=track.metrics, signal=track.signal)
    return SongLoudness(
        name=os.path.basename(path),
        path=path,
        duration_s=round(track.duration_s, 6),
        sample_rate=track.sample_rate,
        channels=track.n_channels,
        metrics=rounded(track.metrics, 4),
        curves=track.curves,
        warnings=[item["message"] for item in found],
    )


def _entry_path(path: str, cache_dir: str) -> str:
    return os.path.join(cache_dir, cache_key(path, n_fft=_N_FFT, hop_length=_HOP) + ENTRY_SUFFIX)


def read_song_entry(entry: str, path: str) -> tuple[SongLoudness | None, str]:
    """A cached song, or ``(None, reason)``: missing, not an entry, damaged (checksum), or
    values no measurement gives."""
    try:
        with open(entry, "rb") as handle:
            data = handle.read()
    except FileNotFoundError:
        return None, "missing"
    except OSError as exc:
        return None, f"cannot be read ({exc.strerror or exc})"
    head, _, content = data.partition(b"\n")
    if not head.startswith(_MAGIC):
        return None, "not a loudscape-loudness entry"
    if head[len(_MAGIC) :] != hashlib.sha256(content).hexdigest().encode("ascii"):
        return None, "its content does not match its checksum (damaged or cut)"
    try:
        stored = json.loads(content)
    except (ValueError, RecursionError):
        return None, "not JSON"
    if not isinstance(stored, dict) or not isinstance(stored.get("metrics"), dict):
        return None, "no metrics"
    if any(v is not None and not _number(v) for v in stored["metrics"].values()):
        return None, "a metric that is not a number"
    curves = stored.get("curves")
    if curves is not None and _curves_problem(curves):
        return None, f"curves: {_curves_problem(curves)}"
    warnings = stored.get("warnings")
    if not isinstance(warnings, list) or not all(isinstance(w, str) for w in warnings):
        return None, "warnings are not a list of lines"
    for key in ("duration_s", "sample_rate", "channels"):
        if not _number(stored.get(key)) or stored[key] <= 0:
            return None, f"{key} is not a positive number"
    try:
        song = SongLoudness(
            name=os.path.basename(path),
            path=path,
            duration_s=stored["duration_s"],
            sample_rate=stored["sample_rate"],
            channels=stored["channels"],
            metrics=stored["metrics"],
            curves=curves,
            warnings=warnings,
        )
    except KeyError as exc:
        return None, f"lacks {exc.args[0]}"
    return song, ""


def _host() -> str:
    """This machine's name as one file-name component, as the timeline's cache spells it."""
    name = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "-" for c in _HOSTNAME)
    return name[:40] or "host"


def _save_song_entry(entry: str, song: SongLoudness) -> None:
    """Atomically, with a checksum line; a temporary unique to this process, removed on any
    error or interrupt."""
    os.makedirs(os.path.dirname(entry), exist_ok=True)
    stored = {k: v for k, v in asdict(song).items() if k not in ("name", "path")}
    content = json.dumps(stored, allow_nan=False).encode("utf-8")
    digest = hashlib.sha256(content).hexdigest().encode("ascii")
    # Named as the timeline's temporaries, so its clean-up of dead writers' leftovers
    # (:func:`remove_temporaries`, run here too) covers these.
    temporary = f"{entry}.{_host()}.{uuid.uuid4().hex[:12]}.{os.getpid()}.tmp"
    try:
        with open(temporary, "wb") as handle:
            handle.write(_MAGIC + digest + b"\n" + content)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, entry)
        fsync_directory(os.path.dirname(entry))
    finally:
        with contextlib.suppress(OSError):
            os.unlink(temporary)


def load_song(
    path: str,
    *,
    cache_dir: str | None = None,
    strict: bool = False,
    notes: list[str] | None = None,
) -> tuple[SongLoudness, bool]:
    """A song cloud's readings, or an audio file's from the cache or measured (and cached).

    An unusable entry is measured again and replaced, with a line in ``notes``; a cache that
    cannot be written costs only speed.

    Returns
    -------
    song : SongLoudness
    cached : bool
    """
    check_regular_input(path)
    if os.path.splitext(path)[1].lower() == ".ply":
        return song_from_cloud(path), False
    if cache_dir is None:
        return song_loudness(path, strict=strict), False
    entry = _entry_path(path, cache_dir)
    if os.path.exists(entry):
        song, problem = read_song_entry(entry, path)
        if song is not None and not (strict and song.warnings):
            return song, True
        if song is None and notes is not None:
            notes.append(f"{path}: its cache entry {entry} is unusable ({problem}); measured again")
    song = song_loudness(path, strict=strict)
    with contextlib.suppress(OSError):
        _save_song_entry(entry, song)
    return song, False


def write_song_report(
    path: str,
    output: str,
    *,
    csv_path: str | None = None,
    target: Target | None = None,
    cache_dir: str | None = None,
    strict: bool = False,
    notes: list[str] | None = None,
) -> tuple[SongLoudness, Verdict | None]:
    """One song's report page at ``output`` (``.pdf`` or ``.png``) and, with ``csv_path``,
    its :func:`summary_row` there; both written atomically, never over the input.

    Raises
    ------
    ExtractError
        Bad input (one line naming the file), an output that cannot be written, or no
        matplotlib.
    """
    check_regular_input(path)
    check_output_path(output, inputs=[path], extensions=PAGE_EXTENSIONS)
    if csv_path:
        check_output_path(csv_path, inputs=[path, output], extensions=(".csv",), flag="--csv")
    require_matplotlib()
    song, _ = load_song(path, cache_dir=cache_dir, strict=strict, notes=notes)
    if song.curves is None and notes is not None:
        notes.append(
            f"{path}: the cloud carries no loudness curves (written before they existed); "
            "the page shows its numbers only"
        )
    verdict = None if target is None else check_target(song.metrics, target)
    draw_page(song_page(song, target, verdict), output)
    if csv_path:
        write_csv(csv_path, SUMMARY_COLUMNS, [summary_row(song, target)])
    return song, verdict


def song_page(song: SongLoudness, target: Target | None, verdict: Verdict | None) -> dict:
    """What :func:`~loudscape_extract.report_pdf.draw_page` draws: the song, its gains, the
    target and verdict (plain data, so the drawing module needs nothing of this one)."""
    return {
        "song": asdict(song),
        "heard": {
            key: (PRESETS[key].name, PRESETS[key].target_lufs, gain, heard)
            for key, (gain, heard) in heard_levels(song.metrics).items()
        },
        "target": None if target is None else asdict(target),
        "verdict": None if verdict is None else asdict(verdict),
    }


@dataclass
class FolderReport:
    """What :func:`write_folder_report` did: the summary rows (in the songs' order), the
    pages written by song, the songs that failed (path -> reason), how many came from the
    cache, and notes (repaired cache entries, songs' warnings)."""

    rows: list[dict] = field(default_factory=list)
    pages: dict[str, str] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)
    cached: int = 0
    notes: list[str] = field(default_factory=list)
    summary: str = ""


def page_names(paths: Sequence[str], folder: str, extension: str) -> dict[str, str]:
    """Each song's page file name: its path under ``folder`` without the audio extension,
    folders joined with ``" - "``; where two songs would share a name, with the extension.

    >>> names = page_names(["a/x.flac", "a/sub/y.wav", "a/y.wav", "a/y.mp3"], "a", ".pdf")
    >>> list(names.values())
    ['x.pdf', 'sub - y.pdf', 'y.wav.pdf', 'y.mp3.pdf']
    """
    relative = {p: os.path.relpath(p, folder).replace(os.sep, " - ") for p in paths}
    stems = [os.path.splitext(r)[0] for r in relative.values()]
    names = {}
    for path, name in relative.items():
        stem = os.path.splitext(name)[0]
        names[path] = (stem if stems.count(stem) == 1 else name) + extension
    return names


def _report_job(path, page, target, cache_dir, strict):
    """Worker: one song's page and row; never raises for a bad song."""
    notes: list[str] = []
    try:
        song, cached = load_song(path, cache_dir=cache_dir, strict=strict, notes=notes)
        if strict and song.warnings:
            return path, None, False, notes, f"{song.warnings[0]} (--strict)"
        verdict = None if target is None else check_target(song.metrics, target)
        draw_page(song_page(song, target, verdict), page)
        notes += [f"warning: {path}: {line}" for line in song.warnings]
        return path, summary_row(song, target), cached, notes, None
    except ExtractError as exc:
        return path, None, False, notes, exc.message
    except MemoryError:
        return path, None, False, notes, "out of memory"
    except Exception as exc:  # noqa: BLE001 - one bad song must not stop the folder
        return path, None, False, notes, " ".join(str(exc).split()) or type(exc).__name__


def _terminated(signum, _frame):
    raise Terminated(f"received signal {signum}")


def _worker_job(*arguments):
    """:func:`_report_job` in a worker: SIGTERM while a song is being made removes its page's
    and cache entry's temporaries, then ends the worker; it ends an idle worker quietly."""
    signal.signal(signal.SIGTERM, _terminated)
    try:
        return _report_job(*arguments)
    except Terminated:
        # Its temporaries are gone (the ``finally`` blocks ran); exit instead of taking the
        # next song already queued to this worker.
        os._exit(143)
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def write_folder_report(
    folder: str,
    out_dir: str,
    *,
    extension: str = ".pdf",
    target: Target | None = None,
    jobs: int = 1,
    cache_dir: str | None = None,
    strict: bool = False,
    on_done: Callable[[int, int, str], None] | None = None,
) -> FolderReport:
    """A report page per audio file under ``folder`` (searched as the timeline searches) and
    ``summary.csv`` (one :func:`summary_row` a song, in the songs' order) in ``out_dir``,
    made if missing; ``jobs`` songs at a time in worker processes. A song that fails is left
    out and listed in :attr:`FolderReport.failed`.

    Raises
    ------
    ExtractError
        No audio under ``folder``, ``out_dir`` not a folder or inside nothing that exists, or
        no matplotlib.
    """
    if extension not in PAGE_EXTENSIONS:
        raise ExtractError(f"pages are {' or '.join(PAGE_EXTENSIONS)}, got {extension!r}")
    require_matplotlib()
    skipped: dict = {}
    paths = discover_audio([folder], skipped=skipped)
    result = FolderReport(failed=dict(skipped))
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ExtractError("the output of a folder's reports must be a folder", path=out_dir)
    parent = os.path.dirname(os.path.abspath(out_dir))
    if not os.path.isdir(parent):
        raise ExtractError(f"output folder's parent {parent!r} does not exist", path=out_dir)
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise ExtractError(f"cannot make the folder ({exc.strerror or exc})", path=out_dir) from exc
    names = page_names(paths, folder, extension)
    pages = {path: os.path.join(out_dir, name) for path, name in names.items()}
    result.summary = os.path.join(out_dir, "summary.csv")
    for page in [*pages.values(), result.summary]:
        check_output_path(page, inputs=paths, extensions=(*PAGE_EXTENSIONS, ".csv"))
    if cache_dir is not None:
        remove_temporaries(cache_dir)  # left by a run that was killed
    rows: dict[str, dict] = {}

    def collect(outcome):
        path, row, cached, notes, error = outcome
        result.notes += notes
        if error is None:
            rows[path] = row
            result.pages[path] = pages[path]
            result.cached += cached
        else:
            result.failed[path] = error
        if on_done:
            on_done(len(rows) + len(result.failed) - len(skipped), len(paths), path)

    arguments = (target, cache_dir, strict)
    if jobs <= 1 or len(paths) <= 1:
        for path in paths:
            collect(_report_job(path, pages[path], *arguments))
    else:
        pool = ProcessPoolExecutor(
            max_workers=min(jobs, len(paths)), initializer=worker_start, initargs=(os.getpid(),)
        )
        try:
            futures = {pool.submit(_worker_job, p, pages[p], *arguments): p for p in paths}
            for future in as_completed(futures):
                try:
                    outcome = future.result()
                except Exception as exc:  # noqa: BLE001 - a worker killed for memory
                    reason = " ".join(str(exc).split()) or type(exc).__name__
                    outcome = (futures[future], None, False, [], f"worker failed ({reason})")
                collect(outcome)
        except BaseException:
            # The workers catch SIGTERM to remove their temporaries: time to do so.
            stop_pool(pool, cache_dir, grace_s=5.0)
            raise
        pool.shutdown(wait=True)
    result.rows = [rows[p] for p in paths if p in rows]
    write_csv(result.summary, SUMMARY_COLUMNS, result.rows)
    return result
