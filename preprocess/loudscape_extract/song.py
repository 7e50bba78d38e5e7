"""Song mode end to end: decode, features, points, atomic PLY write."""

from __future__ import annotations

import warnings
from collections.abc import Callable

from loudscape_extract.contract import checked_blocks
from loudscape_extract.errors import ExtractError
from loudscape_extract.notices import track_warnings
from loudscape_extract.paths import check_output_path
from loudscape_extract.ply import write_ply_blocks
from loudscape_extract.points import DEFAULT_FLOOR_DB, song_metadata
from loudscape_extract.stream import DEFAULT_BLOCK_FRAMES, DEFAULT_BLOCK_SAMPLES, stream_track
from loudscape_extract.stream_points import song_point_blocks
from loudscape_extract.version import GENERATOR

__all__ = ["extract_song"]


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
    block_samples: int = DEFAULT_BLOCK_SAMPLES,
    block_frames: int = DEFAULT_BLOCK_FRAMES,
) -> dict:
    """Song mode end to end: decode, features, points, atomic PLY write, streamed in blocks.

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
    say(f"decoding {source}")
    try:
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
        )
        say(f"{track.duration_s:.1f} s, {track.sample_rate} Hz, {track.n_channels} channel(s)")
        say("building points: counting those above the floor")
        cloud, blocks = song_point_blocks(track, floor_db=floor, freq_scale=freq_scale)
    except ExtractError as exc:
        if exc.path is None:
            exc.path = source
        raise
    found = track_warnings(decode_warning=track.warning, metrics=track.metrics, signal=track.signal)
    for item in found:
        _warn(warn, f"{source}: {item['message']}")
    metadata = song_metadata(track, cloud, generator=GENERATOR, source_format=track.source_format)
    if found:  # absent: nothing to say (docs/FORMAT.md, "Warnings")
        metadata["warnings"] = found
    say("harmonic-percussive separation and the points, block by block")

    def produced():
        yield from checked_blocks(blocks(), metadata, n_points=cloud.point_count, path=output)
        say(f"writing {cloud.point_count} points to {output}")  # the last block is in

    try:
        # The contract (check_cloud's rules) runs on the metadata first and on each block
        # before it is written; the file is put in place only after the last block.
        write_ply_blocks(
            output,
            n_points=cloud.point_count,
            metadata=metadata,
            blocks=produced(),
        )
    except ExtractError as exc:
        if exc.path is None:
            exc.path = source
        raise
    say("done")
    return metadata


def _warn(warn: Callable[[str], None] | None, text: str) -> None:
    (warn or (lambda line: warnings.warn(line, stacklevel=4)))(text)
