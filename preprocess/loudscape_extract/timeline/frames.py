"""What the timeline keeps of one song (:class:`SongFrames`), computed by the Song pipeline."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from loudscape_extract.features import TrackFeatures
from loudscape_extract.stream import StreamedTrack, stream_track
from loudscape_extract.timeline.series import SERIES

__all__ = ["SongFrames", "compute_song_frames", "frames_of"]


@dataclass(frozen=True)
class SongFrames:
    """What the timeline keeps of one song: its non-silent frames and metrics. Its series are
    those of :data:`series.SERIES` (a new one: a row there and a field here).

    Attributes
    ----------
    rms_dbfs, crest_db, loudness_a_db, hp_mean, psr_db, crest_3s_db : np.ndarray [shape=(n_frames,)]
        :class:`FrameFeatures` series restricted to the non-silent frames, in time order
        (``psr_db`` and ``crest_3s_db`` of the 3 s window centred on each frame).
    momentary_lufs, short_term_lufs : np.ndarray [shape=(n_frames,)]
        BS.1770 loudness of the 400 ms block and of the 3 s window centred on each frame
        (the timeline's y measures ``momentary`` and ``short-term``); NaN where not measurable.
    n_frames_total : int
        All STFT frames, silent ones included.
    metrics : dict
        The Song metrics plus ``hp_mean`` (mean over non-silent frames of the frame hp).
    warning : str
        The decoder's note (:attr:`Audio.warning`): non-empty for a truncated or corrupt file.
    signal : tuple of dict
        Warnings about the signal found while decoding (:attr:`StreamedTrack.signal`:
        cancelling channels, clipping).
    """

    rms_dbfs: np.ndarray
    crest_db: np.ndarray
    loudness_a_db: np.ndarray
    hp_mean: np.ndarray
    n_frames_total: int
    metrics: dict = field(default_factory=dict)
    warning: str = ""
    psr_db: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    crest_3s_db: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    signal: tuple = ()
    momentary_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    short_term_lufs: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))


def compute_song_frames(
    path: str,
    *,
    n_fft: int,
    hop_length: int,
    highpass_hz: float | None = None,
    strict: bool = False,
) -> SongFrames:
    """Run the Song pipeline's per-frame features (streamed in bounded memory,
    :func:`stream_track`), keep frames and metrics. A truncated or corrupt file is used as far
    as it decodes, with :attr:`SongFrames.warning` saying so (``strict``: an error)."""
    features = stream_track(
        path, n_fft=n_fft, hop_length=hop_length, highpass_hz=highpass_hz, strict=strict
    )
    return frames_of(features, warning=features.warning)


def frames_of(features: TrackFeatures | StreamedTrack, *, warning: str = "") -> SongFrames:
    """What the timeline keeps of a track's features (also for audio that is not a file);
    ``warning`` is the decoder's note on a damaged file."""
    frames = features.frames
    keep = ~frames.silent
    kept = {
        series.name: _series(getattr(frames, series.name), keep)
        if series.optional
        else getattr(frames, series.name)[keep].astype(np.float32)
        for series in SERIES
    }
    metrics = dict(features.metrics)
    hp = frames.hp_mean[keep]  # the metric from the series as computed, not as kept (float32)
    finite = hp[np.isfinite(hp)]
    metrics["hp_mean"] = float(finite.mean()) if finite.size else None
    return SongFrames(
        **kept,
        n_frames_total=int(frames.silent.shape[0]),
        metrics=metrics,
        warning=warning,
        signal=tuple(getattr(features, "signal", ())),
    )


def _series(values: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """``values[keep]`` as float32, all NaN when the series was not computed (empty)."""
    if values.shape[0] != keep.shape[0]:
        return np.full(int(keep.sum()), np.nan, np.float32)
    return values[keep].astype(np.float32)
