"""loudscape-extract: audio -> loudscape point clouds (PLY) with loudness metrics.

The pipeline is a chain of small pure functions that other commands reuse::

    decode_audio -> mix_to_mono -> stft_magnitude -> hpss_masks / a_weighting_db
        -> track_features (per-bin and per-frame features + whole-track metrics)
        -> song_points -> write_ply
    many files -> track_features (cached per song) -> timeline_points -> write_ply  (timeline)
"""

from loudscape_extract.audio import Audio, decode_audio, mix_to_mono
from loudscape_extract.errors import ExtractError
from loudscape_extract.features import FrameFeatures, TrackFeatures, frame_features, track_features
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
from loudscape_extract.spectrogram import a_weighting_db, frame_signal, level_db, stft_magnitude
from loudscape_extract.timeline import build_timeline

__version__ = "0.1.0"
FORMAT_VERSION = 2

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
