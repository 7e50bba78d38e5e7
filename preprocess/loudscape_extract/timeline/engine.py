"""Per-song work for a timeline: from the cache or computed, in a pool of worker processes.

Stopping: when the caller is interrupted (Ctrl+C, or SIGTERM turned into an exception by the
command line) the pending songs are cancelled and the running workers terminated at once,
their cache temporaries removed; entries already saved stay. Workers ignore SIGINT (the
parent decides) and exit by themselves when the parent process is gone.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.cache import (
    ENTRY_SUFFIX,
    cache_key,
    read_entry,
    remove_temporaries,
    save_entry,
)
from loudscape_extract.timeline.frames import SongFrames, compute_song_frames
from loudscape_extract.timeline.layout import DEFAULT_Z_MEASURE, sample_song

__all__ = ["SongOutcome", "compute_all", "song_frames", "stop_pool", "worker_start"]


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

    An entry that cannot be used (:func:`read_entry`: checksum, shapes, values) is recomputed
    and replaced, and a line saying so is appended to ``notes``.

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
        cache_key(path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz) + ENTRY_SUFFIX,
    )
    if os.path.exists(entry):
        song, problem = read_entry(entry)
        if song is not None:
            return song, True
        if notes is not None:
            # What was done comes before why: a long path cut at the message limit loses the
            # end of the problem's details, not the outcome.
            notes.append(
                f"{path}: its cache entry was unusable, recomputed and replaced: "
                f"{os.path.basename(entry)} ({problem})"
            )
    song = compute_song_frames(
        path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, strict=strict
    )
    try:
        save_entry(entry, song)
    except OSError:
        pass  # a read-only cache only costs speed
    return song, False


#: Tests only: a worker computing the song with this file name exits at once (a worker death).
_EXIT_HOOK = "LOUDSCAPE_TEST_WORKER_EXIT"


def _job(
    path: str,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    strict: bool = False,
    highpass_hz: float | None = None,
    frames_per_song: int | None = None,
    z_measure: str = DEFAULT_Z_MEASURE,
):
    """Worker: one song's :class:`SongOutcome`, a pure function of its arguments (and the
    file's content); never raises for a bad song.

    With ``frames_per_song`` the song is sampled here (``outcome.song`` is a
    :class:`SampledSong`), so only its drawn frames travel back.
    """
    if os.environ.get(_EXIT_HOOK) and os.environ[_EXIT_HOOK] == os.path.basename(path):
        os._exit(70)
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
            if frames_per_song is not None:
                song = sample_song(song, frames_per_song=frames_per_song, z_measure=z_measure)
            outcome.song, outcome.cached = song, cached
    except ExtractError as exc:
        outcome.error = exc.message
    except MemoryError:
        outcome.error = "out of memory"
    except Exception as exc:  # noqa: BLE001 - one bad song must not stop the timeline
        outcome.error = " ".join(str(exc).split()) or type(exc).__name__
    return outcome


def worker_start(parent: int) -> None:
    """Pool initializer: leave SIGINT to the parent, die on SIGTERM, and exit once the parent
    process is gone (SIGKILL, crash) instead of waiting forever for work. The timeline's and
    the folder report's pools (:mod:`loudscape_extract.song_report`) both start with it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch():
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="loudscape-parent-watch", daemon=True).start()


def stop_pool(pool: ProcessPoolExecutor, cache_dir: str | None, *, grace_s: float = 2.0) -> None:
    """Cancel queued songs, terminate running workers (killed after ``grace_s`` seconds),
    remove their cache temporaries."""
    # The executor has no public way to stop running calls: its worker processes are
    # terminated directly (``_processes``, present in CPython 3.10 to 3.14).
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    deadline = time.monotonic() + grace_s
    for process in processes:
        process.join(max(deadline - time.monotonic(), 0.0))
        if process.is_alive():
            process.kill()
            process.join(1.0)
    if cache_dir is not None:
        remove_temporaries(cache_dir, {p.pid for p in processes if p.pid is not None})


@contextlib.contextmanager
def _sigint_blocked():
    """Hold SIGINT in this thread for the block; one that arrives meanwhile is delivered, as
    KeyboardInterrupt, when the block ends."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


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
    frames_per_song: int | None = None,
    z_measure: str = DEFAULT_Z_MEASURE,
    scheduler: str | None = None,
    notes: list[str] | None = None,
) -> tuple[dict, dict[str, str], int]:
    """Features of every path, ``jobs`` worker processes at a time, or on Dask.

    Parameters
    ----------
    frames_per_song, z_measure
        When given, each song is sampled where it is computed (:func:`sample_song`) and only
        its drawn frames come back: the results are :class:`SampledSong`, a few kilobytes a
        song, and are collected as they complete.
    scheduler : str, optional
        None: a local process pool (``jobs`` processes). ``"local"``: a Dask
        ``LocalCluster`` of ``jobs`` single-threaded worker processes. Anything else: the
        address of a running ``dask.distributed`` scheduler (``tcp://host:8786``); its
        workers must see the song paths and ``cache_dir`` (a shared folder).

    notes : list of str, optional
        Receives one line per repaired cache entry.

    Returns
    -------
    songs : dict path -> SongFrames or SampledSong
    failed : dict path -> reason
    cached : int
        How many came from the cache.
    """
    songs: dict = {}
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

    arguments = (n_fft, hop_length, cache_dir, strict, highpass_hz, frames_per_song, z_measure)
    if scheduler is not None:
        # Closed explicitly, so that an interrupt (Ctrl+C, SIGTERM) raised while a result is
        # being collected also shuts the local cluster down before the exception goes on.
        with contextlib.closing(
            _dask_results(paths, arguments, scheduler=scheduler, jobs=jobs)
        ) as results:
            for outcome in results:
                collect(outcome)
        return songs, failed, n_cached
    if jobs <= 1 or len(paths) <= 1:
        for path in paths:
            collect(_job(path, *arguments))
        return songs, failed, n_cached
    pool = ProcessPoolExecutor(
        max_workers=min(jobs, len(paths)), initializer=worker_start, initargs=(os.getpid(),)
    )
    try:
        futures = {pool.submit(_job, p, *arguments): p for p in paths}
        for future in as_completed(futures):
            try:
                outcome = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. a worker killed for memory
                outcome = SongOutcome(futures[future], error=f"worker failed ({_one_line(exc)})")
            collect(outcome)
    except BaseException:
        stop_pool(pool, cache_dir)
        raise
    pool.shutdown(wait=True)
    return songs, failed, n_cached


def _dask_results(paths: Sequence[str], arguments: tuple, *, scheduler: str, jobs: int):
    """Run :func:`_job` on every path on Dask; yield each result as it completes.

    Each song is one task, keyed by its arguments (a pure map). A task whose worker dies is
    that song's failure, reported like any other ("worker died"); the rest carry on. On a
    ``LocalCluster`` a task is not retried on another worker (a song that crashes its worker
    would crash the next one too) and each worker runs one task at a time, so a death takes
    no other song with it; a remote scheduler keeps its own ``allowed-failures`` setting.
    Results are released as they are read, so the client holds one at a time.
    """
    try:
        import dask
        from dask.distributed import Client, LocalCluster
        from dask.distributed import as_completed as dask_completed
    except ImportError as exc:
        raise ExtractError(
            "Dask is not installed: pip install 'loudscape-extract[dask]' "
            f"(needed by --dask and --scheduler; {exc})"
        ) from exc
    cluster = None
    # The in-process scheduler and nannies of a local cluster log a dead worker in several
    # lines of their own; the song's failure is reported once, in our words, instead.
    quiet = logging.getLogger("distributed")
    level = quiet.level
    if scheduler == "local":
        quiet.setLevel(logging.CRITICAL)
    settings = {
        "distributed.scheduler.allowed-failures": 0,
        "distributed.scheduler.worker-saturation": 1.0,
    }
    try:
        with dask.config.set(settings if scheduler == "local" else {}):
            if scheduler == "local":
                # Ctrl+C goes to the whole process group: the cluster's workers ignore SIGINT
                # (a preload, run in every worker, a restarted one too), so the parent alone
                # decides, as with the pool, and closes the cluster on its way out. A Ctrl+C
                # while the cluster starts is held until ``cluster`` is set, so it is closed.
                with _sigint_blocked():
                    cluster = LocalCluster(
                        n_workers=max(1, jobs),
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                        preload=["loudscape_extract.timeline.dask_worker"],
                    )
                client = Client(cluster)
            else:
                try:
                    client = Client(scheduler, timeout="5s")
                except (OSError, TimeoutError, ValueError) as exc:
                    raise ExtractError(
                        f"cannot reach the Dask scheduler at {scheduler!r} ({_one_line(exc)})"
                    ) from exc
            with client:
                futures = client.map(_job, list(paths), *[[a] * len(paths) for a in arguments])
                where = {future.key: path for future, path in zip(futures, paths, strict=True)}
                completed = dask_completed(futures)
                del futures
                for future in completed:
                    path = where[future.key]
                    try:
                        result = future.result()
                    except Exception as exc:  # noqa: BLE001 - KilledWorker, lost data, ...
                        name = type(exc).__name__
                        reason = "worker died" if name == "KilledWorker" else _one_line(exc)
                        result = SongOutcome(path, error=f"worker failed ({reason})")
                    future.release()
                    yield result
    finally:
        if cluster is not None:
            cluster.close()
        quiet.setLevel(level)
