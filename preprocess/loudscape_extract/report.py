"""``loudscape-extract report``: per-year loudness and dynamics of a timeline PLY, as PNG and CSV.

Reads only the file's metadata (:func:`read_ply_metadata`): each song's ``year`` and
``metrics``. One panel per quantity, each song a dot and the year's median a line (broken
where years are missing, never drawn across them):

- integrated loudness (LUFS), with the loudness targets of streaming services and broadcast;
  with ``normalize`` a preset (``--normalize``), also each song and the year's median as heard
  after that preset's playback gain (docs/DYNAMICS.md, "Streaming normalization");
- the penalty: per year, the median number of dB each service and standard takes off
  (negative: turns up);
- PLR (true peak minus integrated loudness) and the TT DR value (dB);
- PSR (median over the song of true peak minus short-term loudness, 3 s), with the 5th-95th
  percentile band of the year's songs only where a year has at least five songs;
- loudness range (LU); hp mean (0 percussive .. 1 tonal, on a 0-1 axis); songs per year.

Songs far from their year's median are named. The CSV has one row per year; a second CSV
beside it (``<name>-songs.csv``) has one row per song.
"""

from __future__ import annotations

import os

import numpy as np

from loudscape_extract.csv_table import write_csv
from loudscape_extract.errors import ExtractError
from loudscape_extract.format import METRIC_KEYS
from loudscape_extract.messages import shorten
from loudscape_extract.normalization import (
    NORMALIZE_CHOICES,
    PRESETS,
    SERVICES,
    preset_gain,
    streaming_gains,
)
from loudscape_extract.paths import atomic_output, check_output_path, check_regular_input
from loudscape_extract.ply import read_ply_metadata
from loudscape_extract.report_pdf import require_matplotlib

__all__ = [
    "BAND_MIN_SONGS",
    "REPORT_COLUMNS",
    "SONG_COLUMNS",
    "STREAMING_TARGETS_LUFS",
    "per_song",
    "per_year",
    "songs_csv_path",
    "write_report",
]

#: A year's percentile band is drawn (and its percentiles written) only from this many songs.
BAND_MIN_SONGS = 5
#: Reference lines on the loudness panel: playback normalization targets.
STREAMING_TARGETS_LUFS = (
    (-11.0, "-11 LUFS: Spotify (loud)"),
    (-14.0, "-14 LUFS: Spotify (normal), YouTube"),
    (-16.0, "-16 LUFS: AES TD1008 (track)"),
    (-19.0, "-19 LUFS: Spotify (quiet)"),
    (-23.0, "-23 LUFS: EBU R 128 broadcast"),
)
_MEDIANS = (
    ("integrated_lufs", "integrated_lufs_median"),
    ("plr_db", "plr_db_median"),
    ("dr_db", "dr_db_median"),
    ("psr_median_db", "psr_db_median"),
    ("lra_lu", "lra_lu_median"),
    ("hp_mean", "hp_mean_median"),
)
REPORT_COLUMNS = (
    "year",
    "songs",
    "integrated_lufs_median",
    "plr_db_median",
    "dr_db_median",
    "psr_db_median",
    "psr_p5_db",
    "psr_p95_db",
    "crest_median_db",
    "crest_p5_db",
    "crest_p95_db",
    "lra_lu_median",
    "hp_mean_median",
    "normalize",
    "heard_integrated_lufs_median",
) + tuple(f"{key}_penalty_db_median" for key in PRESETS)
SONG_COLUMNS = (
    ("year", "artist", "title", "path")
    + METRIC_KEYS
    + tuple(f"{service.key}_gain_db" for service in SERVICES)
    + ("normalize", "heard_integrated_lufs")
)


#: The per-song columns read from the song's metrics as they are (the timeline's metric keys).
METRIC_COLUMNS = METRIC_KEYS


def _values(songs, key):
    return np.array(
        [s["metrics"].get(key) for s in songs if s["metrics"].get(key) is not None], dtype=float
    )


def _stat(values, function, *args):
    return float(function(values, *args)) if values.size else None


def _band(values, q):
    return float(np.percentile(values, q)) if values.size >= BAND_MIN_SONGS else None


def heard_lufs(metrics: dict, normalize: str) -> float | None:
    """A song's integrated loudness as heard after the ``normalize`` preset's gain."""
    integrated = metrics.get("integrated_lufs")
    gain = preset_gain(normalize, metrics)
    return None if integrated is None or gain is None else integrated + gain


def per_year(metadata: dict, *, normalize: str = "none") -> list[dict]:
    """One row per year that has songs (ascending), with the columns of :data:`REPORT_COLUMNS`.

    Percentiles are None for years with fewer than :data:`BAND_MIN_SONGS` songs. Songs
    without a year (a timeline laid out by order) are left out. ``<preset>_penalty_db_median``
    is the median over the year's songs of the dB the preset takes off (``-gain``: negative
    where it turns songs up); ``heard_integrated_lufs_median`` the median loudness after the
    ``normalize`` preset's gain (None for ``"none"``).
    """
    songs = [s for s in metadata.get("songs") or [] if s.get("year") is not None]
    rows = []
    for year in sorted({s["year"] for s in songs}):
        group = [s for s in songs if s["year"] == year]
        row = {"year": year, "songs": len(group)}
        for key, column in _MEDIANS:
            row[column] = _stat(_values(group, key), np.median)
        psr, crest = _values(group, "psr_median_db"), _values(group, "crest_median_db")
        row.update(
            psr_p5_db=_band(psr, 5.0),
            psr_p95_db=_band(psr, 95.0),
            crest_median_db=_stat(crest, np.median),
            crest_p5_db=_band(crest, 5.0),
            crest_p95_db=_band(crest, 95.0),
            normalize=normalize,
        )
        if normalize != "none":
            heard = [heard_lufs(song["metrics"], normalize) for song in group]
            row["heard_integrated_lufs_median"] = _stat(
                np.array([h for h in heard if h is not None], dtype=float), np.median
            )
        for key in PRESETS:
            taken = [preset_gain(key, song["metrics"]) for song in group]
            row[f"{key}_penalty_db_median"] = _stat(
                -np.array([t for t in taken if t is not None], dtype=float), np.median
            )
        rows.append({column: row.get(column) for column in REPORT_COLUMNS})
    return rows


def _checked_songs(metadata, path: str) -> list[dict]:
    """The metadata's songs, each a dict with an int (or absent: ``None``) year and a metrics
    object of finite numbers, or a clear error."""
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
        bad_year = year is not None and (isinstance(year, bool) or not isinstance(year, int))
        if bad_year or not isinstance(metrics, dict):
            raise ExtractError(
                f"songs[{index}] needs an integer (or null) year and a metrics object", path=path
            )
        clean = {
            key: value
            for key, value in metrics.items()
            if isinstance(value, int | float) and not isinstance(value, bool) and np.isfinite(value)
        }
        checked.append({**song, "metrics": clean})
    return checked


def per_song(metadata: dict, *, normalize: str = "none") -> list[dict]:
    """One row per song, in the file's order, with the columns of :data:`SONG_COLUMNS`
    (``heard_integrated_lufs``: after the ``normalize`` preset's gain)."""
    rows = []
    for song in metadata.get("songs") or []:
        metrics = song.get("metrics") or {}
        row = {k: song.get(k, "") for k in ("year", "artist", "title", "path")}
        row.update({k: metrics.get(k) for k in SONG_COLUMNS[4:] if k in METRIC_COLUMNS})
        gains = streaming_gains(metrics)
        row.update(
            {f"{key}_gain_db": None if g is None else round(g, 2) for key, g in gains.items()}
        )
        row["normalize"] = normalize
        row["heard_integrated_lufs"] = heard_lufs(metrics, normalize)
        rows.append(row)
    return rows


def songs_csv_path(csv_path: str) -> str:
    """Where the per-song CSV goes: ``table.csv`` -> ``table-songs.csv``."""
    stem, extension = os.path.splitext(csv_path)
    return f"{stem}-songs{extension or '.csv'}"


def write_report(
    path: str, output: str, *, csv_path: str | None = None, normalize: str = "none"
) -> list[dict]:
    """Plot the per-year metrics of the timeline at ``path`` into ``output`` (PNG).

    With ``csv_path``, also the per-year table there and the per-song table beside it
    (:func:`songs_csv_path`). ``normalize`` (one of :data:`NORMALIZE_CHOICES`) adds the
    loudness as heard after that preset's playback gain.

    Raises
    ------
    ExtractError
        Not a readable PLY, not a timeline, no songs, or an output directory that is missing.
    """
    if normalize not in NORMALIZE_CHOICES:
        raise ExtractError(
            f"--normalize must be one of {', '.join(NORMALIZE_CHOICES)}, got {normalize!r}"
        )
    check_regular_input(path)
    check_output_path(output, inputs=[path], extensions=(".png",))
    if csv_path:
        check_output_path(csv_path, inputs=[path, output], extensions=(".csv",), flag="--csv")
    require_matplotlib()
    metadata = read_ply_metadata(path)
    songs = _checked_songs(metadata, path)
    if csv_path:
        check_output_path(
            songs_csv_path(csv_path),
            inputs=[path, output, csv_path],
            extensions=(".csv",),
            flag="--csv",
        )
    rows = per_year({"songs": songs}, normalize=normalize)
    dated = [s for s in songs if s.get("year") is not None]
    if not dated:
        raise ExtractError("no song of the timeline has a year: nothing to plot by year", path=path)
    with atomic_output(output) as temporary:
        _plot(rows, dated, temporary, title=os.path.basename(path), normalize=normalize)
    if csv_path:
        write_csv(csv_path, REPORT_COLUMNS, rows)
        write_csv(
            songs_csv_path(csv_path),
            SONG_COLUMNS,
            per_song({"songs": songs}, normalize=normalize),
        )
    return rows


def _by_year(rows, column):
    """Years and values with NaN inserted at missing years, so lines break there."""
    years, values = [], []
    for i, row in enumerate(rows):
        if i and row["year"] != rows[i - 1]["year"] + 1:
            years.append(rows[i - 1]["year"] + 0.5)
            values.append(np.nan)
        years.append(row["year"])
        values.append(np.nan if row[column] is None else row[column])
    return np.array(years, dtype=float), np.array(values, dtype=float)


def _name(song):
    title = song.get("title") or os.path.splitext(os.path.basename(song.get("path") or "?"))[0]
    return f"{song['artist']}: {title}" if song.get("artist") else title


def _outliers(songs, rows, key, column, *, limit=6):
    """Songs whose value is far from their year's median (over 2.5 median absolute
    deviations of all songs' distances, and at least 1 unit), largest first."""
    median = {r["year"]: r[column] for r in rows}
    found = []
    for song in songs:
        value, centre = song["metrics"].get(key), median.get(song["year"])
        if value is not None and centre is not None:
            found.append((abs(value - centre), song, value))
    if len(found) < 3:
        return []
    spread = float(np.median([d for d, _, _ in found]))
    cut = max(2.5 * spread, 1.0)
    far = sorted((f for f in found if f[0] > cut), key=lambda f: -f[0])
    return [(song, value) for _, song, value in far[:limit]]


def _song_panel(ax, songs, rows, key, column, *, color, label, band=None):
    present = [s for s in songs if s["metrics"].get(key) is not None]
    ax.scatter(
        [s["year"] for s in present],
        [s["metrics"][key] for s in present],
        s=14,
        color="0.55",
        label="songs",
        zorder=2,
    )
    if band and any(r[band[0]] is not None for r in rows):
        low_years, low = _by_year(rows, band[0])
        _, high = _by_year(rows, band[1])
        ax.fill_between(
            low_years,
            low,
            high,
            color=color,
            alpha=0.2,
            label=f"5th-95th percentile (years with {BAND_MIN_SONGS}+ songs)",
        )
    years, values = _by_year(rows, column)
    ax.plot(years, values, "o-", color=color, label="median of the year", zorder=3)
    for song, value in _outliers(present, rows, key, column):
        ax.annotate(
            _name(song)[:28],
            (song["year"], value),
            xytext=(4, 4),
            textcoords="offset points",
            fontsize=7,
            color="0.25",
        )
    ax.set_ylabel(label)


def _heard_panel(ax, songs, rows, normalize):
    """The songs and the year's median as heard after ``normalize``'s gain, over the files'."""
    name = PRESETS[normalize].name
    present = [(s["year"], heard_lufs(s["metrics"], normalize)) for s in songs]
    present = [(y, h) for y, h in present if h is not None]
    ax.scatter(
        [y for y, _ in present],
        [h for _, h in present],
        s=14,
        facecolors="none",
        edgecolors="C9",
        label=f"songs as heard on {name}",
        zorder=2,
    )
    years, values = _by_year(rows, "heard_integrated_lufs_median")
    ax.plot(years, values, "s-", color="C9", label=f"median as heard on {name}", zorder=3)


def _penalty_panel(ax, rows, normalize):
    """Per year, the median dB each preset takes off (negative: turns up)."""
    for i, (key, service) in enumerate(PRESETS.items()):
        years, values = _by_year(rows, f"{key}_penalty_db_median")
        chosen = key == normalize
        ax.plot(
            years,
            values,
            "o-" if chosen else ".-",
            color=f"C{i}",
            linewidth=2.2 if chosen else 1.0,
            label=service.name,
            zorder=3 if chosen else 2,
        )
    ax.axhline(0.0, color="0.35", linewidth=0.8)
    ax.set_ylabel("penalty (dB taken off,\nmedian of the year)")
    ax.legend(loc="upper left", fontsize=7, ncol=2)


def _plot(rows, songs, output, *, title, normalize="none"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(8, 1, figsize=(10, 21.5), sharex=True, constrained_layout=True)
    heard = "" if normalize == "none" else f", as heard on {PRESETS[normalize].name}"
    fig.suptitle(
        f"Loudness and dynamics by year - {title} ({len(songs)} songs){heard}", fontsize=13
    )

    ax = axes[0]
    _song_panel(
        ax, songs, rows, "integrated_lufs", "integrated_lufs_median", color="C3",
        label="integrated loudness\n(BS.1770, LUFS)",
    )  # fmt: skip
    if normalize != "none":
        _heard_panel(ax, songs, rows, normalize)
    for level, text in STREAMING_TARGETS_LUFS:
        ax.axhline(level, color="0.35", linewidth=0.8, linestyle="--", zorder=1)
        ax.annotate(
            text,
            (0.005, level),
            xycoords=("axes fraction", "data"),
            xytext=(0, 2),
            textcoords="offset points",
            fontsize=7,
            color="0.3",
        )
    ax.legend(loc="lower right", fontsize=8)
    _penalty_panel(axes[1], rows, normalize)
    axes = axes[1:]
    _song_panel(
        axes[1], songs, rows, "plr_db", "plr_db_median", color="C1",
        label="PLR (dB)\ntrue peak - integrated",
    )  # fmt: skip
    _song_panel(
        axes[2], songs, rows, "dr_db", "dr_db_median", color="C5",
        label="DR (dB)\nTT Dynamic Range",
    )  # fmt: skip
    _song_panel(
        axes[3], songs, rows, "psr_median_db", "psr_db_median", color="C0",
        label="PSR (dB, song median)\ntrue peak - short-term, 3 s",
        band=("psr_p5_db", "psr_p95_db"),
    )  # fmt: skip
    axes[3].legend(loc="upper right", fontsize=8)
    _song_panel(
        axes[4], songs, rows, "lra_lu", "lra_lu_median", color="C2", label="loudness range\n(LU)"
    )
    _song_panel(
        axes[5], songs, rows, "hp_mean", "hp_mean_median", color="C4",
        label="hp mean\n(0 percussive - 1 tonal)",
    )  # fmt: skip
    axes[5].set_ylim(0.0, 1.0)
    counts = axes[6]
    counts.bar([r["year"] for r in rows], [r["songs"] for r in rows], color="0.5", width=0.8)
    counts.set_ylabel("songs per year")
    counts.axhline(BAND_MIN_SONGS, color="C0", linewidth=0.8, linestyle=":")
    counts.set_xlabel("year")
    for ax in fig.axes:
        ax.grid(True, alpha=0.3)
    try:
        fig.savefig(output, dpi=100, format="png")  # OSError: atomic_output names the file
    finally:
        plt.close(fig)
