"""Per-song work for a timeline: from the cache or computed, in a pool of worker processes.

Stopping: when the caller is interrupted (Ctrl+C, or SIGTERM turned into an exception by the
command line) the pending songs are cancelled and the running workers terminated at once,
their cache temporaries removed; entries already saved stay. Workers ignore SIGINT (the
parent decides) and exit by themselves when the parent process is gone.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.cache import (
    cache_key,
    read_entry,
    remove_temporaries,
    save_entry,
)
from loudscape_extract.timeline.frames import SongFrames, compute_song_frames

__all__ = ["SongOutcome", "compute_all", "song_frames"]


@dataclass
class SongOutcome:
    """What one song's job gives back."""

    path: str
    song: SongFrames | None = None
    cached: bool = False
    error: str | None = None
    notes: list[str] = field(default_factory=list)


def song_frames(
    path: str,
    *,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    strict: bool = False,
    notes: list[str] | None = None,
    highpass_hz: float | None = None,
) -> tuple[SongFrames, bool]:
    """One song's frames, from the cache when its content and parameters match.

    An entry that cannot be read (truncated, empty, wrong shapes) is recomputed and replaced,
    and a line saying so is appended to ``notes``.

    Returns
    -------
    song : SongFrames
    cached : bool
        True when read from the cache (no decoding).
    """
    if cache_dir is None:
        song = compute_song_frames(
            path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, strict=strict
        )
        return song, False
    entry = os.path.join(
        cache_dir,
        cache_key(path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz) + ".npz",
    )
    if os.path.exists(entry):
        song, problem = read_entry(entry)
        if song is not None:
            return song, True
        if notes is not None:
            notes.append(
                f"{path}: its cache entry {entry} could not be read ({problem}); "
                "recomputed and replaced"
            )
    song = compute_song_frames(
        path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, strict=strict
    )
    try:
        save_entry(entry, song)
    except OSError:
        pass  # a read-only cache only costs speed
    return song, False


def _job(
    path: str,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    strict: bool = False,
    highpass_hz: float | None = None,
):
    """Worker: one song's :class:`SongOutcome`; never raises for a bad song."""
    outcome = SongOutcome(path)
    try:
        song, cached = song_frames(
            path,
            n_fft=n_fft,
            hop_length=hop_length,
            cache_dir=cache_dir,
            strict=strict,
            highpass_hz=highpass_hz,
            notes=outcome.notes,
        )
        if strict and song.warning:
            outcome.error = f"{song.warning} (--strict)"
        else:
            outcome.song, outcome.cached = song, cached
    except ExtractError as exc:
        outcome.error = exc.message
    except MemoryError:
        outcome.error = "out of memory"
    except Exception as exc:  # noqa: BLE001 - one bad song must not stop the timeline
        outcome.error = " ".join(str(exc).split()) or type(exc).__name__
    return outcome


def _worker_start(parent: int) -> None:
    """Pool initializer: leave SIGINT to the parent, die on SIGTERM, and exit once the parent
    process is gone (SIGKILL, crash) instead of waiting forever for work."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch():
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="loudscape-parent-watch", daemon=True).start()


def _stop_pool(pool: ProcessPoolExecutor, cache_dir: str | None) -> None:
    """Cancel queued songs, terminate running workers, remove their cache temporaries."""
    # The executor has no public way to stop running calls: its worker processes are
    # terminated directly (``_processes``, present in CPython 3.10 to 3.14).
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    deadline = time.monotonic() + 2.0
    for process in processes:
        process.join(max(deadline - time.monotonic(), 0.0))
        if process.is_alive():
            process.kill()
            process.join(1.0)
    if cache_dir is not None:
        remove_temporaries(cache_dir, {p.pid for p in processes if p.pid is not None})


def compute_all(
    paths: Sequence[str],
    *,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    jobs: int,
    strict: bool = False,
    highpass_hz: float | None = None,
    on_done: Callable[[int, str], None] | None = None,
    notes: list[str] | None = None,
) -> tuple[dict[str, SongFrames], dict[str, str], int]:
    """Features of every path, ``jobs`` worker processes at a time.

    Parameters
    ----------
    notes : list of str, optional
        Receives one line per repaired cache entry.

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
    if cache_dir is not None:
        remove_temporaries(cache_dir)  # left by a run that was killed

    def collect(outcome: SongOutcome):
        nonlocal n_cached, done
        done += 1
        if notes is not None:
            notes.extend(outcome.notes)
        if outcome.error is None:
            songs[outcome.path] = outcome.song
            n_cached += outcome.cached
        else:
            failed[outcome.path] = outcome.error
        if on_done:
            on_done(done, outcome.path)

    if jobs <= 1 or len(paths) <= 1:
        for path in paths:
            collect(_job(path, n_fft, hop_length, cache_dir, strict, highpass_hz))
        return songs, failed, n_cached
    pool = ProcessPoolExecutor(
        max_workers=min(jobs, len(paths)), initializer=_worker_start, initargs=(os.getpid(),)
    )
    try:
        futures = {
            pool.submit(_job, p, n_fft, hop_length, cache_dir, strict, highpass_hz): p
            for p in paths
        }
        for future in as_completed(futures):
            try:
                outcome = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. a worker killed for memory
                reason = " ".join(str(exc).split()) or type(exc).__name__
                outcome = SongOutcome(futures[future], error=f"worker failed ({reason})")
            collect(outcome)
    except BaseException:
        _stop_pool(pool, cache_dir)
        raise
    pool.shutdown(wait=True)
    return songs, failed, n_cached
