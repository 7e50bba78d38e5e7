"""loudscape-extract: audio -> loudscape point clouds (PLY) with loudness metrics.

Production runs one streamed pipeline (memory does not grow with the per-bin data)::

    song:     decode_track -> spectral_level_pass (silent frames, level range)
                 -> plan_song (the final axes) -> song_point_blocks (STFT + HPSS block by
                 block, appended to a body file, --progress json "points" lines)
                 -> signal_pass (loudness, dynamics, true peak) -> finish_track
                 -> song_metadata -> header + body written atomically          (song.py)
    timeline: per song stream_track (the same passes, no points; cached)
                 -> timeline_points -> write                       (timeline/)

``stream_track`` (stream.py) runs the passes in that order for both. The whole-track
functions are the reference the tests hold the streamed results equal to, and the API for
short audio in a notebook::

    decode_audio -> track_features (every per-bin array) -> song_points -> write_ply

Both share their rules: measures.py (frame series, metrics), song_cloud.py (the keep rule,
the row mapping, the axes, ``song_metadata``).
"""

from loudscape_extract.audio import Audio, decode_audio, mix_to_mono
from loudscape_extract.errors import ExtractError
from loudscape_extract.features import FrameFeatures, TrackFeatures, frame_features, track_features
from loudscape_extract.format import FORMAT_VERSION
from loudscape_extract.hpss import hp_ratio, hpss_masks, median_filter_axis
from loudscape_extract.loudness import (
    integrated_loudness,
    k_weighting_sos,
    loudness_metrics,
    loudness_range,
    sample_peak_dbfs,
    true_peak_dbtp,
)
from loudscape_extract.ply import read_ply, read_ply_metadata, write_ply
from loudscape_extract.points import SongCloud, song_metadata, song_points
from loudscape_extract.song import extract_song
from loudscape_extract.spectrogram import a_weighting_db, frame_signal, level_db, stft_magnitude
from loudscape_extract.timeline import build_timeline
from loudscape_extract.version import __version__

__all__ = [
    "FORMAT_VERSION",
    "Audio",
    "ExtractError",
    "FrameFeatures",
    "SongCloud",
    "TrackFeatures",
    "__version__",
    "a_weighting_db",
    "build_timeline",
    "decode_audio",
    "extract_song",
    "frame_features",
    "frame_signal",
    "hp_ratio",
    "hpss_masks",
    "integrated_loudness",
    "k_weighting_sos",
    "level_db",
    "loudness_metrics",
    "loudness_range",
    "median_filter_axis",
    "mix_to_mono",
    "read_ply",
    "read_ply_metadata",
    "sample_peak_dbfs",
    "song_metadata",
    "song_points",
    "stft_magnitude",
    "track_features",
    "true_peak_dbtp",
    "write_ply",
]
