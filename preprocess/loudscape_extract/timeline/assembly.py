"""Timeline mode end to end: inputs -> per-song frames -> layout -> one PLY."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from loudscape_extract.contract import check_cloud
from loudscape_extract.dynamics import DC_WARN_THRESHOLD
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import FORMAT_VERSION, MODE_TIMELINE
from loudscape_extract.notices import timeline_warnings
from loudscape_extract.paths import check_output_path
from loudscape_extract.ply import write_ply
from loudscape_extract.timeline.engine import compute_all
from loudscape_extract.timeline.inputs import collect_entries
from loudscape_extract.timeline.layout import (
    CREST_PERCENTILES,
    DEFAULT_MAX_POINTS,
    DEFAULT_Y_MEASURE,
    DEFAULT_Z_MEASURE,
    LEVEL_MAX_DBFS,
    LEVEL_MIN_DBFS,
    X_BY,
    frames_per_song_for,
    timeline_points,
)
from loudscape_extract.timeline.series import y_measure_of, z_measure_of
from loudscape_extract.version import GENERATOR

__all__ = ["TimelineResult", "build_timeline"]


@dataclass
class TimelineResult:
    metadata: dict
    written: int
    failed: dict
    without_year: list
    few_frames: list
    cached: int
    #: Frames drawn per song (the request, lowered by the point cap).
    frames_per_song: int = 0
    #: One line each: repaired cache entries, files listed twice. The warnings about songs
    #: (truncated or corrupt, DC offset, ...) are in ``metadata["warnings"]``.
    notes: list = field(default_factory=list)
    #: (path, DC offset) of songs whose offset is over DC_WARN_THRESHOLD.
    dc_offsets: list = field(default_factory=list)


def build_timeline(
    inputs: Sequence[str],
    output: str,
    *,
    manifest: str | None = None,
    x_by: str = "year",
    frames_per_song: int = 1024,
    n_fft: int = 2048,
    hop_length: int = 1024,
    cache_dir: str | None = None,
    jobs: int = 1,
    strict: bool = False,
    z_measure: str = DEFAULT_Z_MEASURE,
    y_measure: str = DEFAULT_Y_MEASURE,
    highpass_hz: float | None = None,
    progress: Callable[[int, int, str], None] | None = None,
    max_points: int | None = DEFAULT_MAX_POINTS,
    scheduler: str | None = None,
) -> TimelineResult:
    """Timeline mode end to end; writes ``output`` unless no song at all could be placed.

    Songs that fail to decode are skipped and listed in ``result.failed`` (and in the
    metadata's ``extraction.skipped``); songs without a year likewise in ``without_year``
    (with ``x_by="order"`` they are placed after the dated songs instead). A truncated or
    corrupt song is used as far as it decodes, with a warning in its ``songs[i]["warnings"]``
    and the top-level ``warnings`` of the metadata (``strict``: it fails instead). The output
    is checked first: it must end with .ply and be none of the inputs (the songs, the
    manifest). ``z_measure`` is one of :data:`Z_MEASURES`, ``y_measure`` one of
    :data:`Y_MEASURES`;
    ``highpass_hz`` high-pass filters each song before its dynamics (see
    :func:`track_features`).

    ``frames_per_song`` is lowered for many songs so the cloud stays under ``max_points``
    (:func:`frames_per_song_for`; None or 0: no cap). ``scheduler`` runs the songs on Dask
    (:func:`compute_all`: ``"local"`` or a scheduler's address); each song is sampled where it
    is computed and only its drawn frames are kept here.

    Raises
    ------
    ExtractError
        Bad inputs (missing or empty folder, bad manifest, no years at all, output directory
        missing) or no song could be extracted.
    """
    if x_by not in X_BY:
        raise ExtractError(f"--x-by must be one of {', '.join(X_BY)}, got {x_by!r}")
    z_measure_of(z_measure, what="--z-measure")
    y_measure_of(y_measure, what="--y-measure")
    check_output_path(output)
    entries, without_year, tag_failures, notes = collect_entries(
        inputs, manifest=manifest, need_year=x_by == "year"
    )
    paths = [e.path for e in entries]
    sources = [*paths, *tag_failures, *without_year] + ([manifest] if manifest else [])
    check_output_path(output, inputs=sources)
    total = len(paths)

    def on_done(done, path):
        if progress:
            progress(done, total, path)

    drawn_per_song = frames_per_song_for(total, frames_per_song, max_points)
    songs, failed, n_cached = compute_all(
        paths,
        frames_per_song=drawn_per_song,
        z_measure=z_measure,
        scheduler=scheduler,
        n_fft=n_fft,
        hop_length=hop_length,
        cache_dir=cache_dir,
        jobs=jobs,
        strict=strict,
        highpass_hz=highpass_hz,
        on_done=on_done,
        notes=notes,
    )
    failed.update(tag_failures)
    good = [e for e in entries if e.path in songs]
    if not good:
        first = next(iter(failed.items()))
        raise ExtractError(
            f"none of the {len(failed)} song(s) could be extracted (first: {first[0]}: {first[1]})"
        )
    points, layout = timeline_points(
        good,
        songs,
        frames_per_song=drawn_per_song,
        x_by=x_by,
        z_measure=z_measure,
        y_measure=y_measure,
    )
    dc_offsets = [
        (s["path"], s["metrics"]["dc_offset"])
        for s in layout["songs"]
        if (s["metrics"].get("dc_offset") or 0.0) > DC_WARN_THRESHOLD
    ]
    few = [s["path"] for s in layout["songs"] if s["point_count"] < drawn_per_song]
    metadata = {
        "format_version": FORMAT_VERSION,
        "mode": MODE_TIMELINE,
        "point_count": int(points.shape[0]),
        "axes": layout["axes"],
        "songs": layout["songs"],
        "extraction": {
            "x_by": x_by,
            "frames_per_song": drawn_per_song,
            "frames_per_song_requested": frames_per_song,
            "max_points": max_points or None,
            "n_fft": n_fft,
            "hop_length": hop_length,
            "level_range_dbfs": [LEVEL_MIN_DBFS, LEVEL_MAX_DBFS],
            "crest_percentiles": list(CREST_PERCENTILES),
            "y_measure": y_measure,
            "z_measure": z_measure,
            "z_percentiles": list(CREST_PERCENTILES),
            "dc_removed": True,
            "highpass_hz": highpass_hz,
            "skipped": [{"path": p, "reason": r} for p, r in sorted(failed.items())]
            + [{"path": p, "reason": "no year in tags"} for p in without_year],
            "generator": GENERATOR,
        },
    }
    found = timeline_warnings(layout["songs"])
    if found:  # absent: nothing to say
        metadata["warnings"] = found
    check_cloud(points, metadata, path=output)
    write_ply(output, points=points, metadata=metadata)
    return TimelineResult(
        metadata=metadata,
        written=len(good),
        failed=failed,
        without_year=without_year,
        few_frames=few,
        cached=n_cached,
        frames_per_song=drawn_per_song,
        notes=notes,
        dc_offsets=dc_offsets,
    )
