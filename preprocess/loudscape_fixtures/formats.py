"""The format fixtures: small files of both versions that readers of the format test against.

    python -m loudscape_fixtures.formats [--out-dir tests/fixtures/format]
    python -m loudscape_fixtures.formats --large --out-dir tests/output

writes, for each fixture ``NAME``, ``NAME.ply`` and ``NAME.expected.json`` (point count, first
and last three records, float64 column sums, the number of ``loudscape-meta-v2`` lines and the
metadata object exactly as its JSON text parses, ``_bytes_b64`` keys included):

- ``song_v1``, ``song_v2``: data/fixture_song.ply (the real extractor's output) in format
  versions 1 and 2; same points, same metadata but for ``format_version``.
- ``timeline_v1``, ``timeline_v2``: a three-song timeline, four points a song.
- ``song_v2_non_utf8``: the song with ``source.path`` the bytes ``data/caf\\xe9 \\xff.wav``
  (Latin-1, not UTF-8).
- ``timeline_v2_non_utf8``: the timeline with song 2's ``path`` and one ``skipped`` path not
  UTF-8.
- ``song_v2_warnings``: the song with a ``warnings`` array (a truncation and a DC offset).
- ``timeline_v2_warnings``: the three-song timeline with warnings on songs 1 and 3 (song 3's
  path not UTF-8), in their ``songs[i].warnings`` and, with ``path``, at the top level.
- with ``--large`` (not committed, about 5 MB): ``timeline_v2_10000_songs``, the metadata of a
  10,000-song timeline (about 490 bytes a song, as the extractor writes for real libraries),
  eight points a song.

Every value is computed, not random, so the files are the same bytes on every machine.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from loudscape_extract.notices import timeline_warnings
from loudscape_extract.ply import read_ply, write_ply

SONG_SOURCE = os.path.join(os.path.dirname(__file__), "..", "..", "data", "fixture_song.ply")
NON_UTF8_SONG_PATH = b"data/caf\xe9 \xff.wav"
NON_UTF8_TIMELINE_PATH = b"music/Bj\xf6rk/Debut/01 Human Behaviour.mp3"
NON_UTF8_SKIPPED_PATH = b"music/\xff\xfe broken name.wav"
SONG_WARNINGS = [
    {
        "kind": "truncated",
        "message": "truncated or corrupt audio: decoded 1.49 s of the 4.00 s the file promises "
        "(37.2 %)",
    },
    {
        "kind": "dc_offset",
        "message": "DC offset 0.300 of full scale (-10.5 dBFS) removed before level, crest, "
        "PSR and DR",
    },
]


def timeline_metadata(n_songs: int, *, points_per_song: int) -> dict:
    """Timeline metadata with every key the extractor writes, for ``n_songs`` songs.

    Paths, titles and artists have the lengths of a real library (a song entry is about
    490 bytes of JSON).
    """
    years = [1960 + (i * 60) // max(n_songs, 1) for i in range(n_songs)]
    first, last = years[0], years[-1] + 1
    span = 2.0 / (last - first)
    songs = []
    per_year: dict[int, int] = {}
    for year in years:
        per_year[year] = per_year.get(year, 0) + 1
    seen: dict[int, int] = {}
    for i, year in enumerate(years):
        k = seen.get(year, 0)
        seen[year] = k + 1
        x_min = -1.0 + (year - first) * span + span * k / per_year[year]
        artist = f"The Artist Called Number {i % 997:03d}"
        album = f"An Album Title Of Usual Length {i % 31:02d}"
        title = f"A Song Title Of Ordinary Length, Part {i:05d}"
        songs.append(
            {
                "path": f"Music/{artist}/{album}/{i % 12 + 1:02d} {title}.flac",
                "year": year,
                "title": title,
                "artist": artist,
                "x_min": round(x_min, 6),
                "x_max": round(x_min + span / per_year[year], 6),
                "point_offset": i * points_per_song,
                "point_count": points_per_song,
                "frames_non_silent": 10000 + i % 3000,
                "frames_total": 10010 + i % 3000,
                "metrics": {
                    "integrated_lufs": round(-20.0 + (i % 150) / 10.0, 4),
                    "lra_lu": round(3.0 + (i % 90) / 10.0, 4),
                    "sample_peak_dbfs": round(-3.0 + (i % 30) / 10.0, 4),
                    "true_peak_dbtp": round(-2.9 + (i % 30) / 10.0, 4),
                    "plr_db": round(17.1 - (i % 150) / 10.0, 4),
                    "crest_median_db": round(6.0 + (i % 70) / 10.0, 4),
                    "crest_p95_db": round(9.0 + (i % 70) / 10.0, 4),
                    "hp_mean": round(0.3 + (i % 60) / 100.0, 4),
                },
            }
        )
    ticks = [
        {"at": round(-1.0 + (year - first) * span, 6), "label": str(year)}
        for year in range(first, last)
        if year % 10 == 0
    ]
    return {
        "format_version": 2,
        "mode": "timeline",
        "point_count": n_songs * points_per_song,
        "axes": {
            "x": {
                "label": "year",
                "unit": "year",
                "min": first,
                "max": last,
                "scale": "linear",
                "ticks": ticks,
            },
            "y": {"label": "level", "unit": "dB", "min": -60.0, "max": 0.0, "scale": "linear"},
            "z": {
                "label": "crest factor",
                "unit": "dB",
                "min": 2.5,
                "max": 14.25,
                "scale": "linear",
            },
            "scalar": {
                "label": "A-weighted level",
                "unit": "dB",
                "min": -100.0,
                "max": 0.0,
                "scale": "linear",
            },
            "hp": {
                "label": "harmonic-percussive ratio",
                "unit": "",
                "min": 0.0,
                "max": 1.0,
                "scale": "linear",
            },
        },
        "extraction": {
            "x_by": "year",
            "frames_per_song": points_per_song,
            "n_fft": 2048,
            "hop_length": 1024,
            "level_range_dbfs": [-60.0, 0.0],
            "crest_percentiles": [1.0, 99.0],
            "skipped": [],
            "generator": "loudscape-extract 0.1.0",
        },
        "songs": songs,
    }


def timeline_points(metadata: dict) -> np.ndarray:
    """Points laid out as the timeline writer does (x by song span), values from formulas.

    Returns
    -------
    points : np.ndarray [shape=(n_points, 5), dtype=float32]
    """
    rows = []
    for i, song in enumerate(metadata["songs"]):
        m = song["point_count"]
        j = np.arange(m, dtype=np.float64)
        x = song["x_min"] + (song["x_max"] - song["x_min"]) * (j + 0.5) / m
        y = -1.0 + 2.0 * ((i * 7 + j * 3) % 11) / 10.0
        z = -1.0 + 2.0 * ((i * 5 + j * 2) % 13) / 12.0
        scalar = ((i * 3 + j) % 9) / 8.0
        hp = ((i + j * 5) % 17) / 16.0
        rows.append(np.stack([x, y, z, scalar, hp], axis=1))
    return np.concatenate(rows).astype(np.float32) if rows else np.zeros((0, 5), np.float32)


def expected_values(path: str) -> dict:
    """What a reader of ``path`` must find (see the module docs)."""
    with open(path, "rb") as handle:
        data = handle.read()
    end = data.index(b"\nend_header\n")
    lines = data[:end].split(b"\n")
    parts = [line.split(b" ") for line in lines if line.startswith(b"comment loudscape-meta-v2 ")]
    if parts:
        raw = json.loads(b"".join(part[3] for part in parts))
    else:
        (line,) = [line for line in lines if line.startswith(b"comment loudscape-meta ")]
        raw = json.loads(line[len(b"comment loudscape-meta ") :])
    points, _ = read_ply(path)
    return {
        "point_count": int(points.shape[0]),
        "header_bytes": end + len(b"\nend_header\n"),
        "meta_v2_lines": len(parts),
        "first_records": [[float(v) for v in row] for row in points[:3]],
        "last_records": [[float(v) for v in row] for row in points[-3:]],
        "column_sums": [float(v) for v in points.astype(np.float64).sum(axis=0)],
        "metadata": raw,
    }


def _write(out_dir: str, name: str, points, metadata, version: int) -> list[str]:
    ply = os.path.join(out_dir, name + ".ply")
    write_ply(ply, points=points, metadata=metadata, format_version=version)
    expected = os.path.join(out_dir, name + ".expected.json")
    with open(expected, "w", encoding="ascii") as handle:
        json.dump(expected_values(ply), handle, indent=1)
        handle.write("\n")
    return [ply, expected]


def write_format_fixtures(out_dir: str, *, large: bool = False) -> list[str]:
    """Write the fixtures into ``out_dir`` (which must exist); returns the paths written."""
    written = []
    if large:
        meta = timeline_metadata(10_000, points_per_song=8)
        return _write(out_dir, "timeline_v2_10000_songs", timeline_points(meta), meta, 2)
    song_points, song_meta = read_ply(SONG_SOURCE)
    for version in (1, 2):
        written += _write(out_dir, f"song_v{version}", song_points, song_meta, version)
    timeline = timeline_metadata(3, points_per_song=4)
    points = timeline_points(timeline)
    for version in (1, 2):
        written += _write(out_dir, f"timeline_v{version}", points, timeline, version)
    bad = {**song_meta, "source": {**song_meta["source"], "path": os.fsdecode(NON_UTF8_SONG_PATH)}}
    written += _write(out_dir, "song_v2_non_utf8", song_points, bad, 2)
    timeline["songs"][1]["path"] = os.fsdecode(NON_UTF8_TIMELINE_PATH)
    timeline["extraction"]["skipped"] = [
        {"path": os.fsdecode(NON_UTF8_SKIPPED_PATH), "reason": "no year in tags"}
    ]
    written += _write(out_dir, "timeline_v2_non_utf8", points, timeline, 2)
    warned = {**song_meta, "warnings": SONG_WARNINGS}
    written += _write(out_dir, "song_v2_warnings", song_points, warned, 2)
    timeline = timeline_metadata(3, points_per_song=4)
    timeline["songs"][2]["path"] = os.fsdecode(NON_UTF8_TIMELINE_PATH)
    timeline["songs"][0]["warnings"] = SONG_WARNINGS[:1]
    timeline["songs"][2]["warnings"] = SONG_WARNINGS
    timeline["warnings"] = timeline_warnings(timeline["songs"])
    written += _write(out_dir, "timeline_v2_warnings", points, timeline, 2)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default=os.path.join("tests", "fixtures", "format"))
    parser.add_argument(
        "--large", action="store_true", help="only the 10,000-song timeline (about 5 MB)"
    )
    args = parser.parse_args(argv)
    os.makedirs(args.out_dir, exist_ok=True)
    for path in write_format_fixtures(args.out_dir, large=args.large):
        print(path, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
