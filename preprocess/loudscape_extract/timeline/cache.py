"""The per-song feature cache: one ``.frames`` file per song, keyed by content hash and
parameters."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import socket
import uuid

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.frames import SongFrames

__all__ = [
    "CACHE_VERSION",
    "ENTRY_SUFFIX",
    "cache_key",
    "default_cache_dir",
    "file_sha256",
    "load_entry",
    "read_entry",
    "remove_temporaries",
    "save_entry",
]

#: Bump when what is cached (or how it is computed) changes: old entries are then ignored.
CACHE_VERSION = 5
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


_MAGIC = b"loudscape-frames 1\n"
_SERIES = (
    "rms_dbfs",
    "crest_db",
    "loudness_a_db",
    "hp_mean",
    "psr_db",
    "crest_3s_db",
    "momentary_lufs",
    "short_term_lufs",
)
#: File name ending of an entry.
ENTRY_SUFFIX = ".frames"
_HOSTNAME = socket.gethostname()


def save_entry(path: str, song: SongFrames) -> None:
    """Write one entry atomically: a magic line, one JSON line (frame count, metrics, the
    decoder's warning), then the float32 series back to back (little endian). One read and
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
    }
    temporary = f"{path}.{_host()}.{uuid.uuid4().hex[:12]}.{os.getpid()}{TEMPORARY_SUFFIX}"
    try:
        with open(temporary, "wb") as handle:
            handle.write(_MAGIC)
            handle.write(json.dumps(head, allow_nan=False).encode("ascii") + b"\n")
            handle.write(np.concatenate(series).tobytes())
        os.replace(temporary, path)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(temporary)


def read_entry(path: str) -> tuple[SongFrames | None, str]:
    """One cache entry, or ``(None, reason)`` when it cannot be used (missing, truncated,
    empty, not an entry, a bad head line, or series of the wrong length)."""
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
        return None, "not a loudscape-frames entry"
    end = data.find(b"\n", len(_MAGIC))
    if end < 0:
        return None, "truncated in its head line"
    try:
        head = json.loads(data[len(_MAGIC) : end])
        n = int(head["frames"])
        n_frames_total = int(head["n_frames_total"])
        metrics = head["metrics"]
        warning = head.get("warning", "")
    except ValueError:
        return None, "its head line is not JSON"
    except (KeyError, TypeError, AttributeError):
        return None, "its head line lacks frame counts or metrics"
    body = data[end + 1 :]
    if n < 0 or len(body) != 4 * n * len(_SERIES):
        return None, f"{len(body)} bytes of series for {n} frames"
    if not isinstance(metrics, dict) or not isinstance(warning, str) or n > n_frames_total:
        return None, "inconsistent frame counts or metrics"
    values = np.frombuffer(body, dtype="<f4").astype(np.float32).reshape(len(_SERIES), n)
    series = dict(zip(_SERIES, values, strict=True))
    return SongFrames(**series, n_frames_total=n_frames_total, metrics=metrics, warning=warning), ""


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
