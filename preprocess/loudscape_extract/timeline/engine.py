"""Per-song work for a timeline: from the cache or computed, in a pool of worker processes."""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed

from loudscape_extract.errors import ExtractError
from loudscape_extract.timeline.cache import ENTRY_SUFFIX, cache_key, load_entry, save_entry
from loudscape_extract.timeline.frames import SongFrames, compute_song_frames
from loudscape_extract.timeline.layout import DEFAULT_Z_MEASURE, sample_song

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
        cache_key(path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz) + ENTRY_SUFFIX,
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


#: Tests only: a worker computing the song with this file name exits at once (a worker death).
_EXIT_HOOK = "LOUDSCAPE_TEST_WORKER_EXIT"


def _job(
    path: str,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    highpass_hz=None,
    frames_per_song: int | None = None,
    z_measure: str = DEFAULT_Z_MEASURE,
):
    """One song's work, a pure function of its arguments (and the file's content):
    (path, SampledSong or SongFrames or None, cached, error message or None).

    With ``frames_per_song`` the song is sampled here, so only its drawn frames travel back.
    """
    if os.environ.get(_EXIT_HOOK) and os.environ[_EXIT_HOOK] == os.path.basename(path):
        os._exit(70)
    try:
        song, cached = song_frames(
            path, n_fft=n_fft, hop_length=hop_length, cache_dir=cache_dir, highpass_hz=highpass_hz
        )
        if frames_per_song is not None:
            song = sample_song(song, frames_per_song=frames_per_song, z_measure=z_measure)
        return path, song, cached, None
    except ExtractError as exc:
        return path, None, False, exc.message
    except MemoryError:
        return path, None, False, "out of memory"
    except Exception as exc:  # noqa: BLE001 - one bad song must not stop the timeline
        return path, None, False, " ".join(str(exc).split()) or type(exc).__name__


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def compute_all(
    paths: Sequence[str],
    *,
    n_fft: int,
    hop_length: int,
    cache_dir: str | None,
    jobs: int,
    highpass_hz: float | None = None,
    on_done: Callable[[int, str], None] | None = None,
    frames_per_song: int | None = None,
    z_measure: str = DEFAULT_Z_MEASURE,
    scheduler: str | None = None,
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

    arguments = (n_fft, hop_length, cache_dir, highpass_hz, frames_per_song, z_measure)
    if scheduler is not None:
        for result in _dask_results(paths, arguments, scheduler=scheduler, jobs=jobs):
            collect(result)
    elif jobs <= 1 or len(paths) <= 1:
        for path in paths:
            collect(_job(path, *arguments))
    else:
        with ProcessPoolExecutor(max_workers=min(jobs, len(paths))) as pool:
            futures = {pool.submit(_job, p, *arguments): p for p in paths}
            for future in as_completed(futures):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. a worker killed for memory
                    result = (futures[future], None, False, f"worker failed ({_one_line(exc)})")
                collect(result)
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
                cluster = LocalCluster(
                    n_workers=max(1, jobs),
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
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
                        result = (path, None, False, f"worker failed ({reason})")
                    future.release()
                    yield result
    finally:
        if cluster is not None:
            cluster.close()
        quiet.setLevel(level)
