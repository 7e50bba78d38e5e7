"""Per-song work for a timeline: from the cache or computed, in a pool of worker processes."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.cache import cache_key, load_entry, save_entry
from loudscape_extract.timeline.frames import SongFrames, compute_song_frames

__all__ = ["compute_all", "song_frames"]


def song_frames(
    path: str,
    *,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    highpass_hz: float | None = None,
) -> tuple[SongFrames, bool]:
    """One song's frames, from the cache when its content and parameters match.

    Returns
    -------
    song : SongFrames
    cached : bool
        True when read from the cache (no decoding).
    """
    if cache_dir is None:
        return compute_song_frames(
            path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz
        ), False
    entry = os.path.join(
        cache_dir,
        cache_key(path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz) + ".npz",
    )
    song = load_entry(entry) if os.path.exists(entry) else None
    if song is not None:
        return song, True
    song = compute_song_frames(path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz)
    try:
        save_entry(entry, song)
    except OSError:
        pass  # a read-only cache only costs speed
    return song, False


def _job(path: str, n_fft: int, hop_length: int, cache_dir: str | None, highpass_hz=None):
    """Worker: (path, SongFrames or None, cached, error message or None)."""
    try:
        song, cached = song_frames(
            path, n_fft=n_fft, hop_length=hop_length, cache_dir=cache_dir, highpass_hz=highpass_hz
        )
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
    highpass_hz: float | None = None,
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
            collect(_job(path, n_fft, hop_length, cache_dir, highpass_hz))
    else:
        with ProcessPoolExecutor(max_workers=min(jobs, len(paths))) as pool:
            futures = {
                pool.submit(_job, p, n_fft, hop_length, cache_dir, highpass_hz): p for p in paths
            }
            for future in as_completed(futures):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. a worker killed for memory
                    reason = " ".join(str(exc).split()) or type(exc).__name__
                    result = (futures[future], None, False, f"worker failed ({reason})")
                collect(result)
    return songs, failed, n_cached
