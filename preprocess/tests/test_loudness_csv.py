"""``loudscape-extract loudness SONG --csv``: the curves every 100 ms and the summary, read back
with csv and checked against the cloud's metrics and libebur128."""

from __future__ import annotations

import csv
import os

import numpy as np
import pyebur128
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.loudness_csv import (
    CURVE_COLUMNS,
    SUMMARY_COLUMNS,
    audio_curves,
    file_curves,
    summary_path,
)
from loudscape_extract.ply import read_ply, write_ply

RATE = 48000


@pytest.fixture(scope="module")
def song(tmp_path_factory):
    """7.3 s of stereo: a swelling chord, a 400 ms burst 6 dB up that starts 30 ms off the
    100 ms grid, written as float WAV; and its Song cloud."""
    folder = tmp_path_factory.mktemp("loudness_csv")
    t = np.arange(int(7.3 * RATE)) / RATE
    y = sum(0.1 * np.sin(2 * np.pi * f * t) for f in (220.0, 277.2, 329.6))
    y *= 0.4 + 0.6 * np.sin(np.pi * t / 7.3) ** 2
    burst = slice(int(4.03 * RATE), int(4.43 * RATE))
    y[burst] *= 2.0
    stereo = np.stack([y, 0.7 * y], axis=1)
    wav = str(folder / "song.wav")
    soundfile.write(wav, stereo, RATE, subtype="FLOAT")
    cloud = str(folder / "song.ply")
    assert main(["song", wav, "-o", cloud, "-q", "--n-fft", "1024", "--hop", "512"]) == 0
    return wav, cloud, stereo


def _read(path: str) -> tuple[list[str], list[dict]]:
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        return list(reader.fieldnames or []), list(reader)


def _number(cell: str) -> float | None:
    return None if cell == "" else float(cell)


def _libebur128_series(stereo: np.ndarray) -> dict:
    """libebur128 fed 100 ms at a time: momentary and short-term after each block, and the
    whole track's integrated loudness and true peak."""
    modes = pyebur128.MeasurementMode
    state = pyebur128.R128State(2, RATE, modes.MODE_I | modes.MODE_S | modes.MODE_TRUE_PEAK)
    hop = RATE // 10
    momentary, short_term = [], []
    for start in range(0, stereo.shape[0] - hop + 1, hop):
        block = np.ascontiguousarray(stereo[start : start + hop], dtype=np.float64)
        state.add_frames(block.ravel(), hop)
        momentary.append(pyebur128.get_loudness_momentary(state))
        short_term.append(pyebur128.get_loudness_shortterm(state))
    peak = max(pyebur128.get_true_peak(state, c) for c in range(2))
    return {
        "momentary": np.array(momentary),
        "short_term": np.array(short_term),
        "integrated": pyebur128.get_loudness_global(state),
        "true_peak": 20 * np.log10(peak),
    }


def test_curves_and_summary_read_back(song, tmp_path, capsys):
    wav, cloud, stereo = song
    out = str(tmp_path / "curves.csv")
    assert main(["loudness", wav, "--csv", out]) == 0
    captured = capsys.readouterr()
    assert "max_momentary_lufs" in captured.out and "wrote" in captured.err
    header, rows = _read(out)
    assert header == list(CURVE_COLUMNS)
    assert len(rows) == 73  # one per complete 100 ms
    times = np.array([float(r["time_s"]) for r in rows])
    np.testing.assert_allclose(times, 0.1 * np.arange(1, 74), atol=1e-9)
    momentary = np.array([_number(r["momentary_lufs"]) or np.nan for r in rows])
    short_term = np.array([_number(r["short_term_lufs"]) or np.nan for r in rows])
    assert np.isnan(momentary[:3]).all() and np.isfinite(momentary[3:]).all()
    assert np.isnan(short_term[:29]).all() and np.isfinite(short_term[29:]).all()
    assert all(r["psr_db"] != "" for r in rows[29:])
    peaks = [float(r["true_peak_dbtp"]) for r in rows]

    # libebur128, read after every 100 ms, shows the same momentary and short-term values.
    theirs = _libebur128_series(stereo)
    np.testing.assert_allclose(momentary[3:], theirs["momentary"][3:], atol=0.02)
    np.testing.assert_allclose(short_term[29:], theirs["short_term"][29:], atol=0.02)
    assert max(peaks) == pytest.approx(theirs["true_peak"], abs=0.1)

    header, summary = _read(summary_path(out))
    assert header == list(SUMMARY_COLUMNS)
    readings = {r["reading"]: r for r in summary}
    assert float(readings["integrated_lufs"]["value"]) == pytest.approx(
        theirs["integrated"], abs=0.02
    )
    # The any-position maximum is the burst's whole 400 ms, above every 100 ms-grid reading
    # (the burst is 30 ms off the grid), and it is where the cloud's metrics say.
    max_momentary = float(readings["max_momentary_lufs"]["value"])
    assert max_momentary > np.nanmax(momentary) + 0.2
    assert float(readings["max_momentary_lufs"]["time_s"]) == pytest.approx(4.43, abs=0.002)
    assert float(readings["max_short_term_lufs"]["value"]) >= np.nanmax(short_term)
    metrics = read_ply(cloud)[1]["metrics"]
    for key in ("integrated_lufs", "lra_lu", "max_momentary_lufs", "max_short_term_lufs"):
        assert float(readings[key]["value"]) == pytest.approx(metrics[key], abs=1e-3), key
    for key in ("true_peak_dbtp", "plr_db", "psr_median_db"):
        assert float(readings[key]["value"]) == pytest.approx(metrics[key], abs=1e-3), key
    assert float(readings["max_short_term_lufs"]["time_s"]) == metrics["max_short_term_s"]


def test_a_song_cloud_gives_its_stored_curves(song, tmp_path):
    wav, cloud, _ = song
    from_audio, from_cloud = str(tmp_path / "audio.csv"), str(tmp_path / "cloud.csv")
    assert main(["loudness", wav, "--csv", from_audio, "-q"]) == 0
    assert main(["loudness", cloud, "--csv", from_cloud, "-q"]) == 0
    audio_rows = {r["time_s"]: r for r in _read(from_audio)[1]}
    _, cloud_rows = _read(from_cloud)
    assert len(cloud_rows) == len(audio_rows) - 3  # the cloud has no rows before 0.4 s
    for row in cloud_rows:
        reference = audio_rows[row["time_s"]]
        assert row["true_peak_dbtp"] == ""  # the cloud does not store it
        for column in ("momentary_lufs", "short_term_lufs", "psr_db"):
            if reference[column] == "":
                assert row[column] == "", (row["time_s"], column)
            else:
                assert float(row[column]) == pytest.approx(float(reference[column]), abs=0.051)
    audio_summary = _read(summary_path(from_audio))[1]
    cloud_summary = _read(summary_path(from_cloud))[1]
    for a, c in zip(audio_summary, cloud_summary, strict=True):
        assert a["reading"] == c["reading"]
        assert float(c["value"]) == pytest.approx(float(a["value"]), abs=1e-3)


def test_refuses_to_write_over_its_input(song, tmp_path, capsys):
    wav, cloud, _ = song
    before = open(wav, "rb").read()
    assert main(["loudness", wav, "--csv", wav]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "refusing to write over an input" in err and wav in err
    assert open(wav, "rb").read() == before
    # The summary's name may not be the input either; nothing is written then.
    victim = str(tmp_path / "x-summary.csv")
    with open(victim, "w") as handle:
        handle.write("keep me\n")
    assert main(["loudness", victim, "--csv", str(tmp_path / "x.csv")]) == 1
    assert "refusing to write over an input" in capsys.readouterr().err
    assert open(victim).read() == "keep me\n"
    assert not os.path.exists(tmp_path / "x.csv")


def test_a_cloud_without_curves_needs_the_audio(song, tmp_path, capsys):
    _, cloud, _ = song
    points, metadata = read_ply(cloud)
    del metadata["loudness"]
    old = str(tmp_path / "old.ply")
    write_ply(old, points=points, metadata=metadata)
    out = str(tmp_path / "never.csv")
    assert main(["loudness", old, "--csv", out]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and old in err and "give the song's audio file" in err
    assert not os.path.exists(out) and os.listdir(tmp_path) == ["old.ply"]
    timeline = os.path.join(os.path.dirname(__file__), "..", "..", "data", "demo_timeline.ply")
    assert main(["loudness", timeline]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "timeline cloud stores no loudness curves" in err


def test_warnings_travel_with_the_readings(song, tmp_path, capsys):
    """A large DC offset is removed and said, as the song command says it."""
    _, _, stereo = song
    shifted = str(tmp_path / "dc.wav")
    soundfile.write(shifted, stereo + 0.05, RATE, subtype="FLOAT")
    assert main(["loudness", shifted, "-q"]) == 0
    captured = capsys.readouterr()
    assert "warning:" in captured.err and "DC offset 0.050" in captured.err
    assert shifted in captured.err and "integrated_lufs" in captured.out


def test_the_file_is_streamed_and_reads_as_the_whole_track(song):
    """The command reads the file in the streamed passes (bounded memory); the in-memory
    function gives the same rows and readings."""
    wav, _, stereo = song
    rows, readings, warnings = file_curves(wav)
    whole_rows, whole_readings = audio_curves(stereo.astype(np.float32), sample_rate=RATE)
    assert warnings == [] and len(rows) == len(whole_rows)
    for a, b in zip(rows, whole_rows, strict=True):
        for column in CURVE_COLUMNS:
            if b[column] is None:
                assert a[column] is None, (b["time_s"], column)
            else:
                assert a[column] == pytest.approx(b[column], abs=1e-3), (b["time_s"], column)
    for key, value in whole_readings.items():
        assert readings[key] == pytest.approx(value, abs=1e-3), key
