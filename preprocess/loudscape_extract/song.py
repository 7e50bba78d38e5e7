"""Song mode end to end: decode, level pass, points (streamed to a body file), signal pass,
atomic PLY write."""

from __future__ import annotations

import contextlib
import os
import re
import time
import warnings
from collections.abc import Callable, Iterator
from typing import BinaryIO

import numpy as np

from loudscape_extract.contract import check_metadata, check_points
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import rounded
from loudscape_extract.notices import track_warnings
from loudscape_extract.paths import check_output_path, write_failure
from loudscape_extract.ply import encode_header, write_atomically
from loudscape_extract.progress import PointsSoFar
from loudscape_extract.song_cloud import DEFAULT_FLOOR_DB, song_metadata
from loudscape_extract.stream import DEFAULT_BLOCK_FRAMES, SpectralLevels, stream_track
from loudscape_extract.stream_decode import DEFAULT_BLOCK_SAMPLES, DecodedMono
from loudscape_extract.stream_points import SongPlan, plan_song, song_point_blocks
from loudscape_extract.timeline.inputs import read_tags
from loudscape_extract.version import GENERATOR

__all__ = [
    "POINTS_BLOCK_FRAMES",
    "POINTS_EVERY_S",
    "ROW_BYTES",
    "body_file_path",
    "extract_song",
    "remove_stale_body_files",
]

#: Bytes of one point in the PLY body and the body file: 5 little-endian float32.
ROW_BYTES = 20
#: The least time between two ``points`` progress reports (the last block always reports).
POINTS_EVERY_S = 0.2
#: STFT frames per block of the points pass at most (about 6 s at 44.1 kHz, hop 1024): the
#: first points reach a reader soon; the points do not depend on it.
POINTS_BLOCK_FRAMES = 256


def body_file_path(output: str) -> str:
    """The hidden file beside ``output`` that holds the points while they are made:
    ``.<output name>.points-<pid>`` (docs/FORMAT.md, "Points while extracting")."""
    folder, name = os.path.split(os.path.abspath(output))
    return os.path.join(folder, f".{name}.points-{os.getpid()}")


#: A body file's name (:func:`body_file_path`): the output's name (a ``.ply``) and a PID.
_BODY_NAME = re.compile(r"\.(.+\.ply)\.points-([1-9][0-9]{0,9})", re.IGNORECASE)


def _process_is_gone(pid: int) -> bool:
    """True only when no process ``pid`` exists (one of another user's counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError, OSError):
        return False
    return False


def remove_stale_body_files(folder: str) -> list[str]:
    """Remove the body files (:func:`body_file_path`) in ``folder`` that an extraction killed
    without a chance to clean up (SIGKILL, a power cut) left behind: those whose process is
    gone. A running extraction's file (its PID alive, or this process's own) is never touched,
    and nothing but regular files named as body files is.

    Returns
    -------
    list of str
        The paths removed.
    """
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = _BODY_NAME.fullmatch(entry.name)
        if match is None:
            continue
        pid = int(match.group(2))
        if pid == os.getpid() or not _process_is_gone(pid):
            continue
        with contextlib.suppress(OSError):
            if entry.is_file(follow_symlinks=False):
                os.unlink(entry.path)
                removed.append(entry.path)
    return removed


def extract_song(
    source: str,
    output: str,
    *,
    n_fft: int = 2048,
    hop_length: int = 1024,
    floor_db: float | None = None,
    freq_scale: str = "linear",
    strict: bool = False,
    highpass_hz: float | None = None,
    progress: Callable[[str], None] | None = None,
    warn: Callable[[str], None] | None = None,
    points: Callable[[PointsSoFar], None] | None = None,
    block_samples: int = DEFAULT_BLOCK_SAMPLES,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
) -> dict:
    """Song mode end to end, streamed in blocks.

    The passes in order: decode (the mono mix); the spectrogram level pass, which fixes the
    cloud's axes; the points (HPSS block by block, on the level pass's spectrogram when the
    track is short enough to keep it), each block appended to the body file
    (:func:`body_file_path`) as it is made; the signal pass (loudness, dynamics, true peak:
    on the decoded blocks kept by the first pass, or a second decode of a long track); then
    the PLY, header and the body file's bytes, written atomically.
    The body file is removed on every exit path that Python sees (errors, Ctrl+C, SIGTERM
    under :func:`~loudscape_extract.interrupts.sigterm_raises`); those of extractions killed
    outright (SIGKILL) are removed by the next extraction into the folder
    (:func:`remove_stale_body_files`).

    Parameters
    ----------
    source : str
        Audio file; recorded in the metadata exactly as given.
    output : str
        PLY file to write.
    n_fft, hop_length : int
        STFT parameters.
    floor_db : float, optional
        Noise floor below the peak bin (default :data:`DEFAULT_FLOOR_DB`); 0 disables it.
    freq_scale : {"linear", "log"}
    strict : bool
        Refuse a truncated or corrupt file instead of extracting what decodes.
    highpass_hz : float, optional
        High-pass (e.g. 20 Hz) the DC-free signal before frame level, crest, DR and PSR.
    progress : callable, optional
        Called with a short message before each stage.
    warn : callable, optional
        Called with a one-line warning about the input, ``"<source>: <message>"`` (a truncated
        or corrupt file, a large DC offset, cancelling channels, clipping); default
        :func:`warnings.warn`. The same warnings go into the metadata's ``warnings``.
    points : callable, optional
        Called with a :class:`~loudscape_extract.progress.PointsSoFar` after a block of points
        is in the body file (at most every :data:`POINTS_EVERY_S`, and after the last block).
    block_samples, block_frames : int
        Decoding and STFT block sizes (:mod:`loudscape_extract.stream`): memory is bounded by
        them and by the decoded mono mix, whatever the track's length; the output does not
        depend on them.

    Returns
    -------
    metadata : dict
        What was written into the file's ``loudscape-meta`` comment.
    """
    say = progress or (lambda _message: None)
    floor = DEFAULT_FLOOR_DB if floor_db is None else floor_db
    check_output_path(output, inputs=[source])
    body = body_file_path(output)
    remove_stale_body_files(os.path.dirname(body))
    try:
        made = {}

        def make_points(decoded: DecodedMono, levels: SpectralLevels) -> None:
            info = decoded.info
            say(
                f"{decoded.n_samples / info.sample_rate:.1f} s, {info.sample_rate} Hz, "
                f"{info.n_channels} channel(s)"
            )
            say("building points: the axes from the level range")
            made["plan"] = plan = plan_song(
                levels,
                sample_rate=info.sample_rate,
                hop_length=hop_length,
                floor_db=floor,
                freq_scale=freq_scale,
            )
            say("harmonic-percussive separation and the points, block by block")
            blocks = song_point_blocks(
                decoded.mono,
                plan,
                n_fft=n_fft,
                hop_length=hop_length,
                block_frames=min(block_frames, POINTS_BLOCK_FRAMES),
                magnitude=levels.magnitude,
                hpss_frames=block_frames,
            )
            made["rows"] = _write_body(body, blocks, plan=plan, output=output, points=points)

        try:
            say(f"decoding {source}")
            track = stream_track(
                source,
                n_fft=n_fft,
                hop_length=hop_length,
                highpass_hz=highpass_hz,
                frame_hp=False,
                block_samples=block_samples,
                block_frames=block_frames,
                strict=strict,
                progress=say,
                after_levels=make_points,
            )
        except ExtractError as exc:
            if exc.path is None:
                exc.path = source
            raise
        found = track_warnings(
            decode_warning=track.warning, metrics=track.metrics, signal=track.signal
        )
        for item in found:
            _warn(warn, f"{source}: {item['message']}")
        plan, rows = made["plan"], made["rows"]
        metadata = song_metadata(
            track, plan.cloud(rows), generator=GENERATOR, source_format=track.source_format
        )
        if found:  # absent: nothing to say (docs/FORMAT.md, "Warnings")
            metadata["warnings"] = found
        _add_tags(metadata["source"], source)
        # The contract (check_cloud's rules): each block was checked as it went into the body
        # file, the metadata is checked now; the file is put in place only after both.
        check_metadata(metadata, n_points=rows, path=output)
        say(f"writing {rows} points to {output}")
        header = encode_header(n_points=rows, metadata=metadata)
        with _opened_body(body, rows=rows, output=output) as handle:
            write_atomically(output, [header, handle])
    finally:
        with contextlib.suppress(OSError):  # already gone, or not ours (a folder)
            os.unlink(body)
    say("done")
    return metadata


def _add_tags(described: dict, path: str) -> None:
    """The song's title and artist from its tags into ``source`` (as the timeline names its
    songs), when it has them; a file without tags, or whose tags cannot be read, adds nothing."""
    tags = read_tags(path)
    for key in ("title", "artist"):
        value = " ".join(str(tags.get(key) or "").split())
        if value:
            described[key] = value[:200]


def _write_body(
    body: str,
    blocks: Iterator[tuple[int, object]],
    *,
    plan: SongPlan,
    output: str,
    points: Callable[[PointsSoFar], None] | None,
) -> int:
    """Append each block's rows to ``body`` (created or emptied); the number of rows."""
    axes = rounded(plan.axes, 6)  # as the metadata will hold them
    rows = reported = 0
    last = -float("inf")
    share = 0.0

    def report() -> None:
        nonlocal reported, last
        points(
            PointsSoFar(
                path=body, rows=rows, axes=axes, freq_scale=plan.mapping.freq_scale, share=share
            )
        )
        reported, last = rows, time.monotonic()

    directory = os.path.dirname(body)
    try:
        with open(body, "wb") as handle:
            for frames_done, block in blocks:
                check_points(block, path=output)
                # The rows' bytes as they lie in memory (no bytes copy of the block first).
                handle.write(
                    np.ascontiguousarray(block, dtype="<f4").reshape(-1).view(np.uint8).data
                )
                handle.flush()
                rows += block.shape[0]
                share = frames_done / plan.frames_total
                if points is not None and time.monotonic() - last >= POINTS_EVERY_S:
                    report()
    except OSError as exc:
        raise ExtractError(write_failure(exc, directory=directory), path=output) from exc
    if points is not None and reported != rows:
        share = 1.0
        report()
    return rows


def _opened_body(body: str, *, rows: int, output: str) -> BinaryIO:
    """The body file, open for reading, after checking its length (the caller closes it)."""
    try:
        handle = open(body, "rb")  # noqa: SIM115 - the caller's with-block closes it
    except OSError as exc:
        raise ExtractError(f"cannot read the points back ({exc.strerror})", path=output) from exc
    size = os.fstat(handle.fileno()).st_size
    if size != rows * ROW_BYTES:
        handle.close()
        raise ExtractError(
            f"the points file holds {size} bytes, not {rows} rows of {ROW_BYTES}",
            path=output,
        )
    return handle


def _warn(warn: Callable[[str], None] | None, text: str) -> None:
    (warn or (lambda line: warnings.warn(line, stacklevel=4)))(text)
