"""Timeline mode: many songs -> one chronological point cloud (one point per sampled frame).

The per-song work is the Song pipeline's :func:`decode_audio` and :func:`track_features`; this
package keeps only each song's per-frame series and metrics (cached on disk by content hash),
orders the songs by year, samples a fixed number of frames per song and lays them out::

    x  song position (by order or by year)      y  frame RMS level, -60..0 dBFS
    z  dynamics of the 3 s around the frame: PSR by default, or 3 s or frame crest factor
       (1st..99th pct over all songs)           scalar  A-weighted frame level   hp  frame hp

Modules, in data-flow order: ``inputs`` (discovery, tags, manifest), ``frames`` (what is kept
of one song), ``cache`` (keys, save/load), ``engine`` (cache-or-compute, worker pool),
``layout`` (spans, x axis, sampling, points), ``assembly`` (end to end, metadata, write).
"""

from loudscape_extract.timeline.assembly import TimelineResult, build_timeline
from loudscape_extract.timeline.cache import CACHE_VERSION, cache_key, default_cache_dir
from loudscape_extract.timeline.engine import compute_all, song_frames
from loudscape_extract.timeline.frames import SongFrames, compute_song_frames, frames_of
from loudscape_extract.timeline.inputs import (
    SongEntry,
    collect_entries,
    discover_audio,
    parse_year,
    read_manifest,
    read_tags,
)
from loudscape_extract.timeline.layout import (
    CREST_PERCENTILES,
    DEFAULT_MAX_POINTS,
    DEFAULT_Y_MEASURE,
    DEFAULT_Z_MEASURE,
    LEVEL_MAX_DBFS,
    LEVEL_MIN_DBFS,
    METRIC_KEYS,
    MIN_FRAMES_PER_SONG,
    SCALAR_FLOOR_DB,
    X_BY,
    Y_MEASURES,
    Z_MEASURES,
    SampledSong,
    frames_per_song_for,
    percentile_map,
    sample_frames,
    sample_song,
    song_spans,
    sort_entries,
    timeline_points,
    x_axis,
)

__all__ = [
    "CACHE_VERSION",
    "CREST_PERCENTILES",
    "DEFAULT_MAX_POINTS",
    "MIN_FRAMES_PER_SONG",
    "SampledSong",
    "frames_per_song_for",
    "sample_song",
    "DEFAULT_Y_MEASURE",
    "DEFAULT_Z_MEASURE",
    "Y_MEASURES",
    "LEVEL_MAX_DBFS",
    "LEVEL_MIN_DBFS",
    "METRIC_KEYS",
    "SCALAR_FLOOR_DB",
    "X_BY",
    "Z_MEASURES",
    "SongEntry",
    "SongFrames",
    "TimelineResult",
    "build_timeline",
    "cache_key",
    "collect_entries",
    "compute_all",
    "compute_song_frames",
    "default_cache_dir",
    "discover_audio",
    "frames_of",
    "parse_year",
    "percentile_map",
    "read_manifest",
    "read_tags",
    "sample_frames",
    "song_frames",
    "song_spans",
    "sort_entries",
    "timeline_points",
    "x_axis",
]
