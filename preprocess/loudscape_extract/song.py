"""Song mode end to end: decode, features, points, atomic PLY write."""

from __future__ import annotations

import warnings
from collections.abc import Callable

from loudscape_extract.audio import decode_audio
from loudscape_extract.contract import check_cloud
from loudscape_extract.dynamics import DC_WARN_THRESHOLD, dc_warning
from loudscape_extract.errors import ExtractError
from loudscape_extract.features import track_features
from loudscape_extract.paths import check_output_path
from loudscape_extract.ply import write_ply
from loudscape_extract.points import DEFAULT_FLOOR_DB, song_metadata, song_points
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
) -> dict:
    """Song mode end to end: decode, features, points, atomic PLY write.

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
        Called with a one-line warning about the input (a truncated or corrupt file, a large
        DC offset); default :func:`warnings.warn`.

    Returns
    -------
    metadata : dict
        What was written into the file's ``loudscape-meta`` comment.
    """
    say = progress or (lambda _message: None)
    floor = DEFAULT_FLOOR_DB if floor_db is None else floor_db
    check_output_path(output, inputs=[source])
    say(f"decoding {source}")
    audio = decode_audio(source, strict=strict)
    if audio.warning:
        (warn or (lambda text: warnings.warn(text, stacklevel=3)))(f"{source}: {audio.warning}")
    say(f"{audio.duration_s:.1f} s, {audio.sample_rate} Hz, {audio.n_channels} channel(s)")
    try:
        features = track_features(
            audio, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, progress=say
        )
        say("building points")
        cloud = song_points(features, floor_db=floor, freq_scale=freq_scale)
    except ExtractError as exc:
        if exc.path is None:
            exc.path = source
        raise
    offset = features.metrics.get("dc_offset") or 0.0
    if offset > DC_WARN_THRESHOLD:
        (warn or (lambda text: warnings.warn(text, stacklevel=3)))(dc_warning(source, offset))
    source_format = f"{audio.format}/{audio.subtype}"
    del audio
    metadata = song_metadata(features, cloud, generator=GENERATOR, source_format=source_format)
    check_cloud(cloud.points, metadata, path=output)
    say(f"writing {cloud.points.shape[0]} points to {output}")
    write_ply(output, points=cloud.points, metadata=metadata)
    say("done")
    return metadata
