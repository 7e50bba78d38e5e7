"""The per-song feature cache: one ``.npz`` per song, keyed by content hash and parameters."""

from __future__ import annotations

import hashlib
import json
import os
import uuid

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.frames import SongFrames

__all__ = [
    "CACHE_VERSION",
    "cache_key",
    "default_cache_dir",
    "file_sha256",
    "load_entry",
    "save_entry",
]

#: Bump when what is cached (or how it is computed) changes: old entries are then ignored.
CACHE_VERSION = 2


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
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    # Unique across the processes and machines sharing the folder (Dask workers); os.replace
    # makes the entry appear whole or not at all.
    temporary = f"{path}.{uuid.uuid4().hex}.tmp.npz"
    np.savez(
        temporary,
        rms_dbfs=song.rms_dbfs,
        crest_db=song.crest_db,
        loudness_a_db=song.loudness_a_db,
        hp_mean=song.hp_mean,
        psr_db=song.psr_db,
        crest_3s_db=song.crest_3s_db,
        n_frames_total=np.array(song.n_frames_total),
        metrics=np.array(json.dumps(song.metrics)),
    )
    os.replace(temporary, path)


def load_entry(path: str) -> SongFrames | None:
    try:
        with np.load(path) as data:
            return SongFrames(
                rms_dbfs=data["rms_dbfs"],
                crest_db=data["crest_db"],
                loudness_a_db=data["loudness_a_db"],
                hp_mean=data["hp_mean"],
                psr_db=data["psr_db"],
                crest_3s_db=data["crest_3s_db"],
                n_frames_total=int(data["n_frames_total"]),
                metrics=json.loads(str(data["metrics"])),
            )
    except (OSError, KeyError, ValueError):
        return None  # missing or damaged cache entry: recompute
