"""The report subcommand, the header-only metadata reader and the committed demo timeline."""

import csv
import os
import sys

import numpy as np
import pytest

from loudscape_extract.cli import main
from loudscape_extract.ply import read_ply, read_ply_metadata, write_ply
from loudscape_extract.report import _by_year, per_year, songs_csv_path

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DEMO = os.path.join(REPO, "data", "demo_timeline.ply")


def song(year, lufs, crest, lra=5.0, hp=0.5):
    metrics = {"integrated_lufs": lufs, "crest_median_db": crest, "lra_lu": lra, "hp_mean": hp}
    return {"year": year, "title": "", "artist": "", "path": "x", "metrics": metrics}


def timeline_file(path, songs):
    meta = {"format_version": 2, "mode": "timeline", "point_count": 1, "songs": songs}
    write_ply(path, points=np.zeros((1, 5), np.float32), metadata=meta)
    return meta


def test_read_ply_metadata_matches_read_ply(tmp_path):
    path = tmp_path / "t.ply"
    meta = timeline_file(path, [song(1980, -12.0, 8.0)])
    assert read_ply_metadata(path) == meta == read_ply(path)[1]


def test_per_year_statistics():
    songs = [song(1980, -14.0, 10.0), song(1980, -12.0, 6.0, lra=None), song(1990, -8.0, 4.0)]
    rows = per_year({"songs": songs})
    assert [r["year"] for r in rows] == [1980, 1990]
    first = rows[0]
    assert first["songs"] == 2 and first["integrated_lufs_median"] == -13.0
    assert first["crest_median_db"] == 8.0
    # Two songs make no percentile band: none is drawn or written.
    assert first["crest_p5_db"] is None and first["crest_p95_db"] is None
    assert first["lra_lu_median"] == 5.0


def test_percentile_band_from_five_songs_a_year():
    songs = [song(1980, -14.0, 5.0 + i) for i in range(5)]
    for s, psr in zip(songs, (8.0, 9.0, 10.0, 11.0, 12.0), strict=True):
        s["metrics"]["psr_median_db"] = psr
    row = per_year({"songs": songs})[0]
    assert row["psr_db_median"] == 10.0
    assert row["psr_p5_db"] == pytest.approx(8.2) and row["psr_p95_db"] == pytest.approx(11.8)
    assert row["crest_p5_db"] == pytest.approx(5.2)


def test_lines_break_at_missing_years():
    rows = per_year(
        {"songs": [song(1980, -14.0, 8.0), song(1981, -13.0, 8.0), song(1990, -8.0, 4.0)]}
    )
    years, values = _by_year(rows, "integrated_lufs_median")
    assert years.tolist()[:2] == [1980, 1981] and np.isnan(values[2]) and years[3] == 1990


def test_report_png_and_csv(tmp_path, capsys):
    path = tmp_path / "t.ply"
    timeline_file(path, [song(1975, -16.0, 9.0), song(2005, -7.0, 4.0), song(2005, -6.0, 3.0)])
    png, table = tmp_path / "r.png", tmp_path / "r.csv"
    assert main(["report", str(path), "-o", str(png), "--csv", str(table)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(table) as handle:
        rows = list(csv.DictReader(handle))
    assert [r["year"] for r in rows] == ["1975", "2005"]
    assert float(rows[1]["integrated_lufs_median"]) == -6.5
    assert rows[1]["crest_p5_db"] == ""  # two songs: no percentiles
    with open(songs_csv_path(str(table))) as handle:
        per_song = list(csv.DictReader(handle))
    assert [(r["year"], r["integrated_lufs"]) for r in per_song] == [
        ("1975", "-16.0"),
        ("2005", "-7.0"),
        ("2005", "-6.0"),
    ]
    assert "dr_db" in per_song[0] and "psr_median_db" in per_song[0]


def test_report_as_heard_after_normalization(tmp_path, capsys):
    path = tmp_path / "t.ply"
    songs = [song(1975, -16.0, 9.0), song(2005, -7.0, 4.0), song(2005, -6.0, 3.0)]
    for s in songs:
        s["metrics"]["true_peak_dbtp"] = -0.5
    timeline_file(path, songs)
    png, table = tmp_path / "r.png", tmp_path / "r.csv"
    args = ["report", str(path), "-o", str(png), "--csv", str(table), "--normalize", "youtube"]
    assert main(args) == 0
    with open(table) as handle:
        rows = list(csv.DictReader(handle))
    assert rows[0]["normalize"] == "youtube"
    assert float(rows[0]["heard_integrated_lufs_median"]) == -16.0  # never turned up
    assert float(rows[1]["heard_integrated_lufs_median"]) == -14.0
    assert float(rows[1]["youtube_penalty_db_median"]) == 7.5
    with open(songs_csv_path(str(table))) as handle:
        heard = [float(r["heard_integrated_lufs"]) for r in csv.DictReader(handle)]
    assert heard == [-16.0, -14.0, -14.0]
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["report", str(path), "-o", str(png), "--normalize", "tidal"])
    assert "tidal" in capsys.readouterr().err


def test_report_bad_inputs(tmp_path, capsys):
    song_mode = tmp_path / "song.ply"
    write_ply(song_mode, points=np.zeros((1, 5)), metadata={"mode": "song"})
    other_mode = tmp_path / "other.ply"
    write_ply(other_mode, points=np.zeros((1, 5)), metadata={"mode": "galaxy"})
    for source, needle in [
        (tmp_path / "missing.ply", "no such file"),
        (song_mode, "no metrics object: not a song cloud"),
        (other_mode, "not a song cloud (mode 'galaxy')"),
    ]:
        out = tmp_path / "r.png"
        assert main(["report", str(source), "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and needle in err and str(source) in err
        assert not out.exists()


def test_demo_timeline_shows_the_loudness_war():
    points, meta = read_ply(DEMO)
    assert os.path.getsize(DEMO) <= 3_000_000
    assert meta["mode"] == "timeline" and meta["point_count"] == points.shape[0]
    decades = [s["year"] // 10 * 10 for s in meta["songs"]]
    assert all(decades.count(d) >= 2 for d in range(1970, 2020, 10))
    assert all(not s["path"].startswith("/") for s in meta["songs"])
    rows = per_year(meta)
    lufs = [r["integrated_lufs_median"] for r in rows]
    crest = [r["crest_median_db"] for r in rows]
    assert lufs[-1] > lufs[0] + 6 and crest[-1] < crest[0] - 3
    # The new dynamics metrics are in the shipped demo, and fall with the loudness war.
    psr = [r["psr_db_median"] for r in rows]
    dr = [r["dr_db_median"] for r in rows]
    assert psr[-1] < psr[0] - 3 and dr[-1] < dr[0] - 3
    assert meta["axes"]["z"]["measure"] == "psr"
    assert np.all(np.abs(points[:, :3]) <= 1)


def test_report_without_matplotlib_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    path = tmp_path / "t.ply"
    timeline_file(path, [song(1975, -16.0, 9.0)])
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert main(["report", str(path), "-o", str(tmp_path / "r.png")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'loudscape-extract[report]'" in err, err
    assert "internal error" not in err and not (tmp_path / "r.png").exists()
