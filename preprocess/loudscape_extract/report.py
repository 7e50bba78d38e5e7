"""``loudscape-extract report``: per-year loudness metrics of a timeline PLY, as PNG and CSV.

Reads only the file's metadata (:func:`read_ply_metadata`): each song's ``year`` and
``metrics``. Per year, over the songs of that year:

- integrated loudness (LUFS): median, and each song as a dot;
- crest factor (dB): median of the songs' median frame crest factor, with the band from the
  5th to the 95th percentile of those per-song values;
- loudness range (LU): median;
- hp mean: median of the songs' frame-level hp means.
"""

from __future__ import annotations

import csv
import os

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.messages import shorten
from loudscape_extract.paths import atomic_output, check_output_path, check_regular_input
from loudscape_extract.ply import read_ply_metadata

__all__ = ["REPORT_COLUMNS", "per_year", "write_report"]

REPORT_COLUMNS = (
    "year",
    "songs",
    "integrated_lufs_median",
    "crest_median_db",
    "crest_p5_db",
    "crest_p95_db",
    "lra_lu_median",
    "hp_mean_median",
)


def _values(songs, key):
    return np.array([s["metrics"].get(key) for s in songs if s["metrics"].get(key) is not None])


def _stat(values, function, *args):
    return float(function(values, *args)) if values.size else None


def per_year(metadata: dict) -> list[dict]:
    """One row per year (ascending) with the columns of :data:`REPORT_COLUMNS`."""
    songs = metadata.get("songs") or []
    rows = []
    for year in sorted({s["year"] for s in songs}):
        group = [s for s in songs if s["year"] == year]
        crest = _values(group, "crest_median_db")
        rows.append(
            {
                "year": year,
                "songs": len(group),
                "integrated_lufs_median": _stat(_values(group, "integrated_lufs"), np.median),
                "crest_median_db": _stat(crest, np.median),
                "crest_p5_db": _stat(crest, np.percentile, 5.0),
                "crest_p95_db": _stat(crest, np.percentile, 95.0),
                "lra_lu_median": _stat(_values(group, "lra_lu"), np.median),
                "hp_mean_median": _stat(_values(group, "hp_mean"), np.median),
            }
        )
    return rows


def _checked_songs(metadata, path: str) -> list[dict]:
    """The metadata's songs, each with an int year and a metrics object, or a clear error."""
    if not isinstance(metadata, dict):
        raise ExtractError("loudscape-meta is not a JSON object", path=path)
    mode = metadata.get("mode")
    if mode != "timeline":
        raise ExtractError(
            f"not a timeline file (mode {shorten(mode, 40) if mode else 'missing'}); "
            "write one with loudscape-extract timeline",
            path=path,
        )
    songs = metadata.get("songs")
    if not isinstance(songs, list) or not songs:
        raise ExtractError("the timeline lists no songs", path=path)
    checked = []
    for index, song in enumerate(songs):
        year = song.get("year") if isinstance(song, dict) else None
        metrics = song.get("metrics") if isinstance(song, dict) else None
        if isinstance(year, bool) or not isinstance(year, int) or not isinstance(metrics, dict):
            raise ExtractError(
                f"songs[{index}] needs an integer year and a metrics object", path=path
            )
        clean = {
            key: value
            for key, value in metrics.items()
            if isinstance(value, int | float) and not isinstance(value, bool) and np.isfinite(value)
        }
        checked.append({**song, "metrics": clean})
    return checked


def _column(rows, key):
    return np.array([np.nan if r[key] is None else r[key] for r in rows], dtype=float)


def write_report(path: str, output: str, *, csv_path: str | None = None) -> list[dict]:
    """Plot the per-year metrics of the timeline at ``path`` into ``output`` (PNG).

    Raises
    ------
    ExtractError
        Not a readable PLY, not a timeline, no songs, or an output directory that is missing.
    """
    check_regular_input(path)
    check_output_path(output, inputs=[path], extensions=(".png",))
    if csv_path:
        check_output_path(csv_path, inputs=[path, output], extensions=(".csv",), flag="--csv")
    metadata = read_ply_metadata(path)
    songs = _checked_songs(metadata, path)
    rows = per_year({"songs": songs})
    with atomic_output(output) as temporary:
        _plot(rows, songs, temporary, title=os.path.basename(path))
    if csv_path:
        with (
            atomic_output(csv_path) as temporary,
            open(temporary, "w", newline="", encoding="utf-8") as handle,
        ):
            writer = csv.DictWriter(handle, fieldnames=REPORT_COLUMNS)
            writer.writeheader()
            for row in rows:
                writer.writerow({k: "" if v is None else round(v, 4) for k, v in row.items()})
    return rows


def _plot(rows, songs, output, *, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    years = _column(rows, "year")
    fig, axes = plt.subplots(4, 1, figsize=(9, 11), sharex=True, constrained_layout=True)
    fig.suptitle(f"Loudness by year - {title} ({len(songs)} songs)", fontsize=13)

    ax = axes[0]
    measured = [s for s in songs if s["metrics"].get("integrated_lufs") is not None]
    song_years = [s["year"] for s in measured]
    song_lufs = [s["metrics"]["integrated_lufs"] for s in measured]
    ax.scatter(song_years, song_lufs, s=14, color="0.6", label="songs", zorder=2)
    ax.plot(years, _column(rows, "integrated_lufs_median"), "o-", color="C3", label="median")
    ax.set_ylabel("integrated loudness\n(LUFS)")
    ax.legend(loc="upper left", fontsize=9)

    ax = axes[1]
    ax.fill_between(
        years,
        _column(rows, "crest_p5_db"),
        _column(rows, "crest_p95_db"),
        color="C0",
        alpha=0.25,
        label="5th-95th percentile of songs",
    )
    ax.plot(years, _column(rows, "crest_median_db"), "o-", color="C0", label="median")
    ax.set_ylabel("crest factor\n(dB, song median)")
    ax.legend(loc="upper right", fontsize=9)

    axes[2].plot(years, _column(rows, "lra_lu_median"), "o-", color="C2")
    axes[2].set_ylabel("loudness range\n(LU)")
    axes[3].plot(years, _column(rows, "hp_mean_median"), "o-", color="C4")
    axes[3].set_ylabel("hp mean\n(0 percussive - 1 tonal)")
    axes[3].set_xlabel("year")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    try:
        fig.savefig(output, dpi=110, format="png")  # OSError: atomic_output names the file
    finally:
        plt.close(fig)
