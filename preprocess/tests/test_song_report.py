"""``report SONG`` and ``report FOLDER``: the page's text and the CSVs read back, the loudness
checked against libebur128 (pyebur128), the verdict, the cache, bad input."""

import csv
import hashlib
import json
import os
import re
import signal
import subprocess
import sys

import numpy as np
import pyebur128
import pytest
import soundfile as sf
from test_interrupts import alive, children, wait_for

from loudscape_extract.cli import main
from loudscape_extract.ply import read_ply_metadata, write_ply
from loudscape_extract.song_report import (
    ENTRY_SUFFIX,
    SUMMARY_COLUMNS,
    SongLoudness,
    Target,
    _save_song_entry,
    check_target,
    preset_target,
    read_song_entry,
)

RATE = 44100
#: The three titles of the CSV injection report (a file name cannot hold a slash).
ATTACKS = ("=HYPERLINK(1+1)", "+cmd|calc", "@SUM(1+1)")


def master(seconds=12.0, *, gain=1.0, seed=0):
    """A stereo 'song': a quiet verse, a loud chorus, a short burst that clips."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(RATE * seconds)) / RATE
    envelope = np.where(t < seconds / 3, 0.08, 0.3) * (1 + 0.3 * np.sin(2 * np.pi * 0.7 * t))
    tone = np.sin(2 * np.pi * 196 * t) + 0.4 * np.sin(2 * np.pi * 587 * t + 1.0)
    x = gain * envelope * (tone + 0.25 * rng.standard_normal(t.size))
    burst = slice(int(0.8 * seconds * RATE), int((0.8 * seconds + 0.15) * RATE))
    x[burst] *= 4.0
    x = np.clip(x, -1.0, 1.0)
    return np.stack([x, 0.7 * x + 0.05 * rng.standard_normal(t.size)], axis=1).astype(np.float32)


def write_song(path, samples):
    sf.write(path, samples, RATE, subtype="PCM_24" if str(path).endswith(".flac") else "FLOAT")
    return str(path)


def libebur128(samples):
    modes = pyebur128.MeasurementMode
    meter = pyebur128.R128State(samples.shape[1], RATE, modes.MODE_I | modes.MODE_LRA)
    meter.add_frames(np.ascontiguousarray(samples, dtype=np.float64).ravel(), samples.shape[0])
    return pyebur128.get_loudness_global(meter), pyebur128.get_loudness_range(meter)


def pdf_text(path):
    done = subprocess.run(
        ["pdftotext", "-layout", str(path), "-"], capture_output=True, text=True, check=True
    )
    return done.stdout


def reading(text, label, unit):
    found = re.search(rf"{re.escape(label)}\s+([-+]?\d+\.\d) {unit}", text)
    assert found, f"{label!r} not on the page:\n{text}"
    return float(found.group(1))


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_song_page_and_csv_agree_with_libebur128(tmp_path, capsys):
    samples = master()
    song = write_song(tmp_path / "master.wav", samples)
    page, table = tmp_path / "master.pdf", tmp_path / "master.csv"
    args = ["report", song, "-o", str(page), "--csv", str(table), "--target", "spotify"]
    assert main([*args, "--no-cache"]) == 0
    err = capsys.readouterr().err
    integrated, lra = libebur128(samples)
    text = pdf_text(page)
    assert "Loudness report" in text and "master.wav" in text
    assert reading(text, "Integrated loudness", "LUFS") == pytest.approx(integrated, abs=0.06)
    assert reading(text, "Loudness range (LRA)", "LU") == pytest.approx(lra, abs=0.3)
    (row,) = read_csv(table)
    assert list(row) == list(SUMMARY_COLUMNS)
    assert float(row["integrated_lufs"]) == pytest.approx(integrated, abs=0.01)
    assert float(row["lra_lu"]) == pytest.approx(lra, abs=0.25)
    # Spotify turns a master louder than -14 LUFS down to -14; the page says so per service.
    assert float(row["spotify_gain_db"]) == pytest.approx(-14.0 - integrated, abs=0.01)
    assert float(row["spotify_heard_lufs"]) == pytest.approx(-14.0)
    assert re.search(r"Spotify \(normal\)\s+-14\s+\S*\s*-\d+\.\d dB\s+-14\.0 LUFS", text), text
    # The true-peak overs of the clipped burst are counted, on the page and in the CSV.
    assert int(row["overs_0dbtp_count"]) >= 1
    assert f"{row['overs_0dbtp_count']} runs over 0 dBTP" in text
    # The verdict: the page, stderr and the CSV say the same.
    loud = integrated > -13.0
    assert row["verdict"] == ("fail" if loud else "pass")
    assert ("FAIL" if loud else "PASS") + " Spotify (normal)" in err
    assert ("FAIL" if loud else "PASS") in text.split("Readings")[0]
    for key, label in (
        ("max_momentary_lufs", "Max momentary"),
        ("max_short_term_lufs", "Max short-term"),
    ):
        if row[key]:  # the metrics carry the maxima: the page shows them as the CSV does
            assert reading(text, label + (" (400 ms)" if "momentary" in key else " (3 s)"),
                           "LUFS") == pytest.approx(float(row[key]), abs=0.051)  # fmt: skip
    assert "clipped" in text  # the signal's warning travels onto the page


def test_png_page_and_own_target(tmp_path, capsys):
    samples = master(gain=0.25)
    song = write_song(tmp_path / "quiet.flac", samples)
    page, table = tmp_path / "quiet.png", tmp_path / "quiet.csv"
    integrated, _ = libebur128(samples)
    lufs = f"{round(integrated):d}"
    args = ["report", song, "-o", str(page), "--csv", str(table), "--no-cache"]
    assert main([*args, "--target-lufs", lufs, "--max-true-peak", "-1"]) == 0
    assert page.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (row,) = read_csv(table)
    assert row["target_lufs"] == str(float(lufs)) and row["target_max_true_peak_dbtp"] == "-1.0"
    assert row["verdict"] == ("pass" if float(row["true_peak_dbtp"]) <= -1.0 else "fail")
    assert "wrote" in capsys.readouterr().err


def test_verdicts():
    spotify = preset_target("spotify")
    assert spotify.lufs == -14.0 and spotify.max_true_peak_dbtp == -1.0
    assert preset_target("atsc_a85").max_true_peak_dbtp == -2.0
    assert preset_target("youtube").max_true_peak_dbtp == -1.0
    ok = check_target({"integrated_lufs": -14.6, "true_peak_dbtp": -1.0}, spotify)
    assert ok.passed and ok.text.startswith("PASS Spotify (normal): -14.6 LUFS is within")
    quiet = check_target({"integrated_lufs": -15.2, "true_peak_dbtp": -3.0}, spotify)
    assert not quiet.passed and "1.2 LU below -14.0 LUFS" in quiet.text
    hot = check_target({"integrated_lufs": -14.0, "true_peak_dbtp": -0.9}, spotify)
    assert not hot.passed and "true peak -0.9 dBTP is over -1.0 dBTP" in hot.text
    silent = check_target({"integrated_lufs": None, "true_peak_dbtp": None}, spotify)
    assert not silent.passed and "no integrated loudness" in silent.text
    peak_only = Target("-2 dBTP", None, -2.0)
    assert check_target({"integrated_lufs": -5.0, "true_peak_dbtp": -2.5}, peak_only).passed


def test_report_of_a_song_cloud_with_and_without_curves(tmp_path, capsys):
    samples = master(seconds=8.0)
    song = write_song(tmp_path / "cloud.wav", samples)
    cloud = tmp_path / "cloud.ply"
    assert main(["song", song, "-o", str(cloud), "-q"]) == 0
    metadata = read_ply_metadata(cloud)
    page, table = tmp_path / "c.pdf", tmp_path / "c.csv"
    assert main(["report", str(cloud), "-o", str(page), "--csv", str(table)]) == 0
    (row,) = read_csv(table)
    assert float(row["integrated_lufs"]) == metadata["metrics"]["integrated_lufs"]
    assert int(row["overs_0dbtp_count"]) == metadata["loudness"]["overs_0dbtp_count"]
    text = pdf_text(page)
    assert "cloud.wav" in text and "no loudness curves" not in text
    # A cloud written before curves existed: the numbers, and one line saying what is missing.
    del metadata["loudness"]
    old = tmp_path / "old.ply"
    write_ply(old, points=np.zeros((1, 5), np.float32), metadata=metadata)
    capsys.readouterr()
    assert main(["report", str(old), "-o", str(page), "--csv", str(table)]) == 0
    assert f"{old}: the cloud carries no loudness curves" in capsys.readouterr().err
    text = pdf_text(page)
    assert "carries no loudness curves" in text
    assert reading(text, "Integrated loudness", "LUFS") == round(
        metadata["metrics"]["integrated_lufs"], 1
    )
    assert read_csv(table)[0]["overs_0dbtp_count"] == ""
    capsys.readouterr()


def test_folder_reports_in_parallel_cached_and_safe_in_spreadsheets(tmp_path, capsys):
    album = tmp_path / "album"
    (album / "disc 2").mkdir(parents=True)
    louder = {ATTACKS[0]: 1.0, ATTACKS[1]: 0.5, ATTACKS[2]: 0.25}
    songs = {}
    for i, (name, gain) in enumerate(louder.items()):
        folder = album / "disc 2" if i == 2 else album
        samples = master(seconds=6.0, gain=gain, seed=i)
        songs[name] = (write_song(folder / f"{name}.wav", samples), samples)
    (album / "broken.flac").write_bytes(b"not audio at all")
    out, cache = tmp_path / "out", tmp_path / "cache"
    args = ["report", str(album), "-o", str(out), "--cache-dir", str(cache), "-j", "2"]
    assert main([*args, "--target", "ebu_r128"]) == 1  # one song failed
    err = capsys.readouterr().err
    assert re.search(r"skipped: \S*broken\.flac: ", err)
    assert "3 song(s), 0 from cache" in err
    rows = read_csv(out / "summary.csv")
    assert sorted(r["song"] for r in rows) == sorted("'" + name + ".wav" for name in ATTACKS)
    for row in rows:
        path, samples = songs[row["song"][1:-4]]
        assert row["path"] == path
        assert float(row["integrated_lufs"]) == pytest.approx(libebur128(samples)[0], abs=0.01)
        assert row["verdict"] == "fail" and row["target"] == "EBU R 128 (broadcast)"
    pages = sorted(os.listdir(out))
    assert pages == sorted(
        [f"{ATTACKS[0]}.pdf", f"{ATTACKS[1]}.pdf", f"disc 2 - {ATTACKS[2]}.pdf", "summary.csv"]
    )
    for row in rows:
        name = row["song"][1:]
        page = next(p for p in pages if p.endswith(name[:-4] + ".pdf"))
        text = pdf_text(out / page)
        assert name in text
        assert reading(text, "Integrated loudness", "LUFS") == pytest.approx(
            float(row["integrated_lufs"]), abs=0.051
        )
    # Again: every song from the cache, the same numbers.
    assert main(args) == 1
    assert "3 song(s), 3 from cache" in capsys.readouterr().err
    assert [r["integrated_lufs"] for r in read_csv(out / "summary.csv")] == [
        r["integrated_lufs"] for r in rows
    ]
    # A damaged entry is measured again and replaced, with a line saying so.
    entries = sorted(cache.glob("*" + ENTRY_SUFFIX))
    assert len(entries) == 3
    data = bytearray(entries[0].read_bytes())
    data[-5] ^= 0x01
    entries[0].write_bytes(bytes(data))
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "unusable (its content does not match its checksum" in err
    assert "3 song(s), 2 from cache" in err
    assert [r["integrated_lufs"] for r in read_csv(out / "summary.csv")] == [
        r["integrated_lufs"] for r in rows
    ]
    assert not [n for n in os.listdir(cache) if n.endswith(".tmp")]
    assert not [n for n in os.listdir(out) if n.startswith(".")]  # no temporaries left


def test_bad_input_one_line_and_nothing_written(tmp_path, capsys, monkeypatch):
    song = write_song(tmp_path / "s.wav", master(seconds=4.0))
    junk = tmp_path / "junk.wav"
    junk.write_bytes(b"RIFF....WAVEjunk")
    page = tmp_path / "r.pdf"
    timeline = tmp_path / "t.ply"
    write_ply(
        timeline,
        points=np.zeros((1, 5), np.float32),
        metadata={"format_version": 2, "mode": "timeline", "point_count": 1, "songs": []},
    )
    bad_curves = tmp_path / "bad.ply"
    write_ply(
        bad_curves,
        points=np.zeros((1, 5), np.float32),
        metadata={
            "format_version": 2,
            "mode": "song",
            "point_count": 1,
            "metrics": {"integrated_lufs": -9.0},
            "loudness": {
                "rate_hz": 10,
                "momentary_start_s": 0.2,
                "short_term_start_s": 1.5,
                "momentary_lufs": ["loud"],
                "short_term_lufs": [],
                "psr_db": [],
            },
        },
    )
    cases = [
        (["report", str(junk), "-o", str(page)], str(junk)),
        (["report", str(bad_curves), "-o", str(page)], "momentary_lufs is not a list of numbers"),
        (["report", song, "-o", song], "refusing to write over an input"),
        (["report", song, "-o", str(tmp_path / "r.txt")], "must end with .pdf or .png"),
        (["report", song, "-o", str(tmp_path / "no" / "r.pdf")], "does not exist"),
        (["report", song, "-o", str(page), "--normalize", "spotify"], "--normalize is for"),
        (["report", str(timeline), "--target", "spotify"], "--target is for a song"),
        (["report", str(tmp_path), "-o", str(page / "x")], "parent"),
    ]
    for argv, needle in cases:
        assert main([*argv, "--no-cache"]) == 1, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and needle in err, (argv, err)
        assert not page.exists()
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert main(["report", song, "-o", str(page), "--no-cache"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'loudscape-extract[report]'" in err
    assert not page.exists()


def test_sigterm_stops_a_folder_without_temporaries_or_workers(tmp_path):
    album, out, cache = tmp_path / "album", tmp_path / "out", tmp_path / "cache"
    album.mkdir()
    for i in range(6):
        write_song(album / f"s{i}.wav", master(seconds=40.0, seed=i))
    argv = [sys.executable, "-m", "loudscape_extract.cli", "report", str(album)]
    process = subprocess.Popen(
        [*argv, "-o", str(out), "--cache-dir", str(cache), "-j", "2"],
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        wait_for(lambda: len(children(process.pid)) >= 2, 60, "two workers")
        workers = children(process.pid)
        wait_for(
            lambda: cache.exists() and any(n.endswith(ENTRY_SUFFIX) for n in os.listdir(cache)),
            120,
            "a measured song",
        )
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 143, err
    assert err.strip().splitlines()[-1] == (
        "loudscape-extract: terminated; the pages finished so far are kept, no summary.csv written"
    )
    assert "Traceback" not in err
    wait_for(lambda: not any(alive(pid) for pid in workers), 10, "the workers to exit")
    assert not (out / "summary.csv").exists()
    # No temporaries (".NAME.PID.tmp.pdf", "ENTRY.HOST.UNIQUE.PID.tmp"), nothing half made.
    assert [n for n in os.listdir(out) if n.startswith(".") or not n.endswith(".pdf")] == []
    assert [n for n in os.listdir(cache) if not n.endswith(ENTRY_SUFFIX)] == []
    for page in os.listdir(out):  # every page there is whole
        assert "Integrated loudness" in pdf_text(out / page)


def test_cache_entries_round_trip_and_odd_values_are_refused(tmp_path):
    song = SongLoudness(
        name="a.wav",
        path="a.wav",
        duration_s=12.5,
        sample_rate=44100,
        channels=2,
        metrics={"integrated_lufs": -9.5, "lra_lu": None},
        curves=None,
        warnings=["clipped"],
    )
    entry = tmp_path / ("k" + ENTRY_SUFFIX)
    _save_song_entry(str(entry), song)
    assert read_song_entry(str(entry), "a.wav") == (song, "")
    assert os.listdir(tmp_path) == [entry.name]

    def forged(**changes):  # a valid checksum over values no measurement gives
        stored = {
            "duration_s": 12.5,
            "sample_rate": 44100,
            "channels": 2,
            "curves": None,
            "metrics": {"integrated_lufs": -9.5},
            "warnings": [],
            **changes,
        }
        content = json.dumps(stored).encode()
        digest = hashlib.sha256(content).hexdigest().encode()
        entry.write_bytes(b"loudscape-loudness 1 " + digest + b"\n" + content)
        return read_song_entry(str(entry), "a.wav")

    assert forged()[0] is not None
    for changes, reason in (
        ({"duration_s": "long"}, "duration_s is not a positive number"),
        ({"channels": 0}, "channels is not a positive number"),
        ({"metrics": {"integrated_lufs": "loud"}}, "a metric that is not a number"),
        ({"curves": {"rate_hz": -1}}, "curves: rate_hz is '-1'"),
        ({"warnings": "clipped"}, "warnings are not a list of lines"),
    ):
        assert forged(**changes) == (None, reason)
