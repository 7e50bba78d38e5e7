"""The per-song feature cache: one ``.npz`` per song, keyed by content hash and parameters."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.frames import SongFrames

__all__ = [
    "CACHE_VERSION",
    "cache_key",
    "default_cache_dir",
    "file_sha256",
    "load_entry",
    "read_entry",
    "remove_temporaries",
    "save_entry",
]

#: Bump when what is cached (or how it is computed) changes: old entries are then ignored.
CACHE_VERSION = 2
TEMPORARY_SUFFIX = ".tmp.npz"
_SERIES = ("rms_dbfs", "crest_db", "loudness_a_db", "hp_mean", "psr_db", "crest_3s_db")


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


def save_entry(path: str, song: SongFrames) -> None:
    """Write one entry atomically: a temporary file named with this process's id, then
    ``os.replace``; the temporary is removed on any error or interrupt."""
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    temporary = f"{path}.{os.getpid()}{TEMPORARY_SUFFIX}"
    try:
        np.savez(
            temporary,
            **{key: getattr(song, key) for key in _SERIES},
            n_frames_total=np.array(song.n_frames_total),
            metrics=np.array(json.dumps(song.metrics)),
            warning=np.array(song.warning),
        )
        os.replace(temporary, path)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(temporary)


def read_entry(path: str) -> tuple[SongFrames | None, str]:
    """One cache entry, or ``(None, reason)`` when it cannot be used (missing, truncated,
    empty, not an archive, or arrays of the wrong kind or shape)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            series = {key: np.asarray(data[key]) for key in _SERIES}
            n_frames_total = int(data["n_frames_total"])
            metrics = json.loads(str(data["metrics"]))
            warning = str(data["warning"]) if "warning" in data.files else ""
    except FileNotFoundError:
        return None, "missing"
    except Exception as exc:  # noqa: BLE001 - zipfile, pickle, JSON, key and OS errors alike
        return None, " ".join(str(exc).split())[:120] or type(exc).__name__
    lengths = {array.shape for array in series.values()}
    if len(lengths) != 1 or len(next(iter(lengths))) != 1:
        return None, f"series of mismatched shapes {sorted(lengths)}"
    if any(array.dtype.kind != "f" for array in series.values()):
        return None, "series are not floating point"
    if not isinstance(metrics, dict) or not 0 <= series["rms_dbfs"].shape[0] <= n_frames_total:
        return None, "inconsistent frame counts or metrics"
    return SongFrames(**series, n_frames_total=n_frames_total, metrics=metrics, warning=warning), ""


def load_entry(path: str) -> SongFrames | None:
    """:func:`read_entry` without the reason."""
    return read_entry(path)[0]


def remove_temporaries(cache_dir: str, pids=None) -> None:
    """Remove temporaries left by writers that are gone: those of ``pids`` (workers just
    stopped), or, when ``pids`` is None, of every process id no longer running."""
    try:
        names = os.listdir(cache_dir)
    except OSError:
        return
    for name in names:
        if not name.endswith(TEMPORARY_SUFFIX):
            continue
        pid_text = name[: -len(TEMPORARY_SUFFIX)].rpartition(".")[2]
        if not pid_text.isdigit():
            continue
        pid = int(pid_text)
        if (pid in pids) if pids is not None else not _running(pid):
            with contextlib.suppress(OSError):
                os.unlink(os.path.join(cache_dir, name))


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True
