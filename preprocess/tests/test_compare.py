"""Comparing releases (docs/COMPARE.md, "Alignment" and "Many versions").

From a real track (data/real-music, fetched by scripts/fetch-real-music.sh), versions are made
as releases differ: the same audio delayed by 0.731 s with 4 dB more gain through a limiter
(ffmpeg ``adelay``, ``volume``, ``alimiter`` with ``latency=1`` so the limiter's look-ahead does
not shift the audio), an EQ tilt, a version with 2 s cut out of the middle, and an unrelated
track. Loudness is checked against libebur128 (pyebur128).
"""

import csv
import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pyebur128
import pytest
import soundfile as sf

from loudscape_extract.align import align
from loudscape_extract.audio import decode_audio
from loudscape_extract.cli import main
from loudscape_extract.compare import THIRD_OCTAVE_HZ, compare_versions

REPO = pathlib.Path(__file__).resolve().parents[2]
MUSIC = pathlib.Path(os.environ.get("LOUDSCAPE_REAL_MUSIC", REPO / "data" / "real-music"))
TRACK = "torus-trooper-data/tt1.ogg"
OTHER = "torus-trooper-data/tt3.ogg"
DELAY_S = 0.731
CUT = (30.0, 32.0)


def _ffmpeg(*args):
    subprocess.run(["ffmpeg", "-v", "error", "-y", *args], check=True)


@pytest.fixture(scope="module")
def versions(tmp_path_factory):
    script = REPO / "scripts" / "fetch-real-music.sh"
    done = subprocess.run(
        ["bash", str(script), str(MUSIC)], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, f"{script.name} failed: {done.stderr.strip()}"
    assert shutil.which("ffmpeg"), "ffmpeg is needed (scripts/setup-system.sh installs it)"
    folder = tmp_path_factory.mktemp("versions")
    a = folder / "original.wav"
    _ffmpeg("-i", str(MUSIC / TRACK), str(a))
    paths = {"a": a}
    paths["louder"] = folder / "remaster.wav"
    _ffmpeg(
        "-i", str(a), "-af",
        f"adelay={int(DELAY_S * 1000)}:all=1,volume=4dB,alimiter=limit=0.8:latency=1",
        str(paths["louder"]),
    )  # fmt: skip
    paths["tilt"] = folder / "tilt.wav"
    _ffmpeg(
        "-i", str(a), "-af",
        "equalizer=f=100:t=o:w=2:g=6,equalizer=f=8000:t=o:w=2:g=-6",
        str(paths["tilt"]),
    )  # fmt: skip
    samples, rate = sf.read(a)
    cut = np.concatenate([samples[: int(CUT[0] * rate)], samples[int(CUT[1] * rate) :]])
    paths["cut"] = folder / "edit.wav"
    sf.write(paths["cut"], cut, rate)
    paths["other"] = folder / "other.wav"
    _ffmpeg("-i", str(MUSIC / OTHER), str(paths["other"]))
    return {key: str(path) for key, path in paths.items()}


@pytest.fixture(scope="module")
def compared(versions):
    audios = [decode_audio(versions[k]) for k in ("a", "louder", "tilt", "cut", "other")]
    return dict(zip(("a", "louder", "tilt", "cut", "other"), compare_versions(audios), strict=True))


def _integrated(samples, rate):
    meter = pyebur128.R128State(samples.shape[1], rate, pyebur128.MeasurementMode.MODE_I)
    meter.add_frames(np.ascontiguousarray(samples, dtype=np.float64).ravel(), samples.shape[0])
    return pyebur128.get_loudness_global(meter)


def test_a_delayed_limited_remaster_is_found_within_a_millisecond(compared):
    alignment = compared["louder"].alignment
    assert alignment.alignable
    assert abs(alignment.offset_s - DELAY_S) < 0.001, alignment.to_json()
    assert alignment.confidence > 0.6


def test_the_matching_gain_brings_each_version_to_the_quietest_libebur128(compared, versions):
    levels = {k: _integrated(*sf.read(versions[k], always_2d=True)) for k in compared}
    quietest = min(levels.values())
    for key, version in compared.items():
        # The gain is what takes libebur128's reading to the quietest version's.
        assert abs(version.match_gain_db - (quietest - levels[key])) < 0.2, key
    # The louder remaster is turned down by about the loudness it gained.
    assert compared["louder"].match_gain_db < compared["a"].match_gain_db - 0.5


def test_an_eq_tilt_is_aligned_at_zero_and_shows_as_tonal_balance(compared):
    tilt = compared["tilt"]
    assert abs(tilt.alignment.offset_s) < 0.001
    diff = dict(zip(THIRD_OCTAVE_HZ, tilt.spectrum_difference_db, strict=True))
    # +6 dB around 100 Hz, -6 dB around 8 kHz, at matched loudness: lows up against highs.
    assert diff[100] - diff[8000] > 6.0
    assert diff[8000] < -3.0
    # An untouched copy's balance is flat: the delayed remaster's bands stay within 1.5 dB.
    louder = compared["louder"].spectrum_difference_db
    mids = [i for i, f in enumerate(THIRD_OCTAVE_HZ) if 100 <= f <= 5000]
    assert np.nanmax(np.abs(louder[mids])) < 1.5


def test_a_cut_is_followed_by_the_time_map(compared):
    alignment = compared["cut"].alignment
    assert alignment.alignable
    length = CUT[1] - CUT[0]
    for t_a in np.arange(5.0, CUT[0] - 1.0, 3.0):
        assert abs(alignment.b_time(t_a) - t_a) < 0.05, (t_a, alignment.to_json())
    for t_a in np.arange(CUT[1] + 1.5, 56.0, 3.0):
        assert abs(alignment.b_time(t_a) - (t_a - length)) < 0.05, (t_a, alignment.to_json())
    # And back: B's clock after the cut maps onto A's.
    t_b = np.array([40.0, 50.0])
    assert np.allclose(alignment.a_time(t_b), t_b + length, atol=0.05)


def test_unrelated_music_is_said_and_not_shifted(compared):
    alignment = compared["other"].alignment
    assert not alignment.alignable
    assert alignment.offset_s == 0.0
    assert "share no music" in alignment.reason
    # Its curve stays on its own clock: the first 3 s window is heard at 3 s.
    assert compared["other"].short_term_times_s[0] == pytest.approx(3.0)


def test_integer_delays_of_noise_are_found_to_the_sample():
    rng = np.random.default_rng(3)
    rate = 44100
    a = rng.standard_normal(rate * 30) * np.repeat(rng.uniform(0.1, 1.0, 300), rate // 10)
    for delay in (1, 441, 12345):
        b = np.concatenate([np.zeros(delay), a])
        found = align(a, b, rate)
        assert found.alignable
        assert abs(found.offset_s * rate - delay) < 0.1, (delay, found.offset_s * rate)


def test_the_command_writes_sheet_csv_and_json(versions, tmp_path, capsys):
    sheet, table = tmp_path / "sheet.png", tmp_path / "table.csv"
    code = main(
        ["compare", versions["a"], versions["louder"], versions["other"],
         "-o", str(sheet), "--csv", str(table), "--json"]
    )  # fmt: skip
    captured = capsys.readouterr()
    assert code == 0, captured.err
    summary = json.loads(captured.out)
    paths = [v["path"] for v in summary["versions"]]
    assert paths == [versions["a"], versions["louder"], versions["other"]]
    b = summary["versions"][1]
    assert abs(b["offset_s"] - DELAY_S) < 0.001
    assert b["match_gain_db"] is not None and b["alignment"]["confidence"] > 0.5
    assert summary["versions"][2]["offset_s"] is None
    assert "not aligned" in captured.err and "other.wav" in captured.err
    assert sheet.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["version"] for r in rows] == ["A", "B", "C"]
    assert float(rows[1]["offset_s"]) == pytest.approx(DELAY_S, abs=0.001)
    assert float(rows[0]["integrated_lufs_diff"]) == 0.0
    assert rows[2]["alignable"] == "false"


def test_the_command_refuses_before_work(versions, tmp_path, capsys):
    before = pathlib.Path(versions["a"]).read_bytes()
    assert main(["compare", versions["a"], versions["tilt"], "-o", versions["a"]]) == 1
    assert "refusing to write over an input" in capsys.readouterr().err
    assert pathlib.Path(versions["a"]).read_bytes() == before
    assert main(["compare", versions["a"]]) == 1
    assert "2 to 8 versions" in capsys.readouterr().err
    assert main(["compare", versions["a"], versions["tilt"]]) == 1
    assert "say what to write" in capsys.readouterr().err


def test_a_truncated_version_s_warning_is_in_the_json_and_the_csv(versions, tmp_path, capsys):
    """The app runs ``compare --json -q`` and reads stdout only: a version decoded in part
    must say so in the JSON (and the CSV), not on stderr alone."""
    flac = tmp_path / "remaster.flac"
    _ffmpeg("-i", versions["louder"], str(flac))
    data = flac.read_bytes()
    half = tmp_path / "half.flac"
    half.write_bytes(data[: len(data) // 2])
    table = tmp_path / "table.csv"
    code = main(["compare", versions["a"], str(half), "--json", "-q", "--csv", str(table)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    summary = json.loads(captured.out)
    assert summary["versions"][0]["warnings"] == []
    (line,) = summary["versions"][1]["warnings"]
    assert "truncated" in line
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert rows[0]["warnings"] == "" and "truncated" in rows[1]["warnings"]
