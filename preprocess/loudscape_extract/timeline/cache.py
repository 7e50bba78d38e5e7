"""The per-song feature cache: one ``.frames`` file per song, keyed by content hash and
parameters."""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import socket
import uuid

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.messages import shorten
from loudscape_extract.notices import warnings_problem
from loudscape_extract.paths import fsync_directory
from loudscape_extract.timeline.frames import SongFrames
from loudscape_extract.timeline.layout import METRIC_KEYS
from loudscape_extract.timeline.series import SERIES

__all__ = [
    "CACHE_VERSION",
    "ENTRY_SUFFIX",
    "cache_key",
    "default_cache_dir",
    "entry_problem",
    "file_sha256",
    "load_entry",
    "read_entry",
    "remove_temporaries",
    "save_entry",
]

#: Bump when what is cached (or how it is computed) changes: old entries are then ignored.
CACHE_VERSION = 7
#: Temporaries are named ``ENTRY.HOST.UNIQUE.PID`` + this; see :func:`remove_temporaries`.
TEMPORARY_SUFFIX = ".tmp"


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


def cache_key(path: str, *, n_fft: int, hop_length: int, highpass_hz: float | None = None) -> str:
    """Content hash of the file plus everything the cached features depend on."""
    highpass = "" if highpass_hz is None else f"-hp{highpass_hz:g}"
    return f"{file_sha256(path)}-n{n_fft}-h{hop_length}{highpass}-v{CACHE_VERSION}"


#: The first line: this, the sha256 of everything after the line in hex, a newline.
_MAGIC = b"loudscape-frames 2 "
_OLD_MAGIC = b"loudscape-frames "
#: The series of an entry's body, in order, and what each may hold: (lowest, highest, NaN
#: allowed), from the one table of them (:data:`series.SERIES`).
_SERIES = tuple(series.name for series in SERIES)
_SERIES_RANGES = {series.name: (series.low, series.high, series.nan_allowed) for series in SERIES}
#: A series not in the table (none today) gets this: NaN or a finite |value| <= 1e4.
_DEFAULT_RANGE = (-1e4, 1e4, True)
#: Metrics every entry carries (the ones the timeline shows); each a finite number or null.
_REQUIRED_METRICS = METRIC_KEYS
#: File name ending of an entry.
ENTRY_SUFFIX = ".frames"
_HOSTNAME = socket.gethostname()


def save_entry(path: str, song: SongFrames) -> None:
    """Write one entry atomically: a magic line with the sha256 of the rest, one JSON line
    (frame count, metrics, the decoder's and the signal's warnings), then the float32 series
    back to back (little endian). The data is synced to the disk before the rename. One read and
    no parsing beyond a short JSON line bring it back (an ``.npz`` took about 10 ms a song: a
    zip directory and eight array headers), which is what a warm rebuild of 10,000 songs spends
    its time on.

    The temporary beside ``path`` is named after this host and process (and is unique across
    the processes and machines sharing the folder, e.g. Dask workers); ``os.replace`` makes the
    entry appear whole or not at all, and the temporary is removed on any error or interrupt.
    """
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    n = int(song.rms_dbfs.shape[0])
    series = [np.asarray(getattr(song, name), dtype="<f4") for name in _SERIES]
    # the loudness series of a song built without them (empty) are stored as unknown (NaN)
    series = [np.full(n, np.nan, "<f4") if s.shape == (0,) else s for s in series]
    if any(s.shape != (n,) for s in series):
        raise ValueError(f"series of unequal lengths {[s.shape for s in series]}")
    head = {
        "frames": n,
        "n_frames_total": int(song.n_frames_total),
        "metrics": song.metrics,
        "warning": song.warning,
        "signal": [dict(item) for item in song.signal],
    }
    temporary = f"{path}.{_host()}.{uuid.uuid4().hex[:12]}.{os.getpid()}{TEMPORARY_SUFFIX}"
    content = json.dumps(head, allow_nan=False).encode("ascii") + b"\n"
    content += np.concatenate(series).tobytes()
    digest = hashlib.sha256(content).hexdigest().encode("ascii")
    try:
        with open(temporary, "wb") as handle:
            handle.write(_MAGIC + digest + b"\n")
            handle.write(content)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
        fsync_directory(directory)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(temporary)


def read_entry(path: str) -> tuple[SongFrames | None, str]:
    """One cache entry, or ``(None, reason)`` when it cannot be used: missing, empty, not an
    entry, its content not matching its checksum (truncated, overwritten, flipped bits), a bad
    head line, series of the wrong length, or values no extraction gives
    (:func:`entry_problem`: non-finite or out-of-range series, missing or non-finite
    metrics)."""
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except FileNotFoundError:
        return None, "missing"
    except OSError as exc:
        return None, " ".join(str(exc).split())[:120] or type(exc).__name__
    if not data:
        return None, "empty file"
    if not data.startswith(_MAGIC):
        if data.startswith(_OLD_MAGIC):
            return None, "an entry of an older layout"
        return None, "not a loudscape-frames entry"
    digest_end = data.find(b"\n", len(_MAGIC))
    if digest_end < 0:
        return None, "truncated in its first line"
    content = data[digest_end + 1 :]
    digest = hashlib.sha256(content).hexdigest().encode("ascii")
    if data[len(_MAGIC) : digest_end] != digest:
        return None, "its content does not match its checksum (damaged or cut)"
    data = content
    end = data.find(b"\n")
    if end < 0:
        return None, "truncated in its head line"
    try:
        head = json.loads(data[:end])
        n = int(head["frames"])
        n_frames_total = int(head["n_frames_total"])
        metrics = head["metrics"]
        warning = head.get("warning", "")
        signal = head.get("signal", [])
    except (ValueError, RecursionError):
        return None, "its head line is not JSON (or nested too deeply)"
    except (KeyError, TypeError, AttributeError):
        return None, "its head line lacks frame counts or metrics"
    body = data[end + 1 :]
    if n < 0 or len(body) != 4 * n * len(_SERIES):
        return None, f"{len(body)} bytes of series for {n} frames"
    if not isinstance(metrics, dict) or not isinstance(warning, str) or n > n_frames_total:
        return None, "inconsistent frame counts or metrics"
    if warnings_problem(signal):
        return None, "its signal warnings are not a list of warnings"
    values = np.frombuffer(body, dtype="<f4").astype(np.float32).reshape(len(_SERIES), n)
    series = dict(zip(_SERIES, values, strict=True))
    problem = entry_problem(series, metrics)
    if problem:
        return None, problem
    song = SongFrames(
        **series,
        n_frames_total=n_frames_total,
        metrics=metrics,
        warning=warning,
        signal=tuple(signal),
    )
    return song, ""


def entry_problem(series: dict, metrics: dict) -> str:
    """Why an entry's values are not what an extraction gives (``""`` when they are): each
    series checked against its range in ``_SERIES_RANGES`` (any series, named there or not),
    every metric in ``_REQUIRED_METRICS`` present, each metric a finite number or null."""
    for name, values in series.items():
        low, high, nan_ok = _SERIES_RANGES.get(name, _DEFAULT_RANGE)
        values = np.asarray(values, dtype=np.float64)
        nan = np.isnan(values)
        if nan.any() and not nan_ok:
            return f"series {name} holds NaN"
        finite = values[~nan]
        if not np.isfinite(finite).all():
            return f"series {name} holds an infinite value"
        if finite.size and (finite.min() < low or finite.max() > high):
            return (
                f"series {name} spans {finite.min():.4g}..{finite.max():.4g}, outside the "
                f"plausible {low:g}..{high:g}"
            )
    missing = [key for key in _REQUIRED_METRICS if key not in metrics]
    if missing:
        more = f" and {len(missing) - 1} more" if len(missing) > 1 else ""
        return f"metrics lack {missing[0]}{more}"
    for key, value in metrics.items():
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"metric {key} is not a number ({shorten(value, 40)})"
        if not math.isfinite(value) or abs(value) > 1e6:
            return f"metric {key} is {value!r}"
    return ""


def load_entry(path: str) -> SongFrames | None:
    """:func:`read_entry` without the reason: None when it is missing or damaged."""
    return read_entry(path)[0]


def remove_temporaries(cache_dir: str, pids=None) -> None:
    """Remove temporaries left by writers on this host that are gone: those of ``pids``
    (workers just stopped), or, when ``pids`` is None, of every process id no longer running.
    Temporaries of other hosts (a shared folder under Dask) are left alone."""
    try:
        names = os.listdir(cache_dir)
    except OSError:
        return
    host = _host()
    for name in names:
        if not name.endswith(TEMPORARY_SUFFIX):
            continue
        parts = name[: -len(TEMPORARY_SUFFIX)].rsplit(".", 3)
        if len(parts) != 4 or parts[1] != host or not parts[3].isdigit():
            continue
        pid = int(parts[3])
        if (pid in pids) if pids is not None else not _running(pid):
            with contextlib.suppress(OSError):
                os.unlink(os.path.join(cache_dir, name))


def _host() -> str:
    """This machine's name as one file-name component (no dots, separators or odd bytes)."""
    name = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "-" for c in _HOSTNAME)
    return name[:40] or "host"


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True
