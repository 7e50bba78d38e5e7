"""`loudscape compare`: the app's command over the extractor's comparison (docs/COMPARE.md).

The binary is ``$LOUDSCAPE_BIN`` (``make test-mesh`` sets ``target/debug/loudscape``); it finds
the extractor in the checkout's venv. A song cloud stands for its recorded source audio.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
import soundfile

ROOT = Path(__file__).resolve().parents[2]
CLOUD = ROOT / "data" / "demo_song.ply"
AUDIO = ROOT / "data" / "demo_song.flac"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape")).absolute()


def _run(*args, cwd=None):
    if not BINARY.is_file():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    return subprocess.run(
        [str(BINARY), "compare", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
        check=False,
    )


@pytest.fixture(scope="module")
def remaster(tmp_path_factory):
    """The demo song 0.3 s later and 5 dB quieter, in a file named like an option."""
    samples, rate = soundfile.read(AUDIO, always_2d=True)
    delay = int(0.3 * rate)
    later = np.concatenate([np.zeros((delay, samples.shape[1])), samples * 10 ** (-5 / 20)])
    path = tmp_path_factory.mktemp("compare") / "-remaster.wav"
    soundfile.write(path, later, rate)
    return path


def test_a_cloud_and_a_remaster_are_aligned_and_matched(remaster, tmp_path):
    table = tmp_path / "table.csv"
    done = _run(CLOUD, remaster, "--json", "--csv", table)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    a, b = summary["versions"]
    # The cloud stands for its source audio.
    assert Path(a["path"]).name == "demo_song.flac"
    assert Path(b["path"]).name == "-remaster.wav"
    assert b["offset_s"] == pytest.approx(0.3, abs=0.001)
    # B is 5 dB quieter: A is turned down by 5 dB to match it, B stays.
    assert a["match_gain_db"] == pytest.approx(-5.0, abs=0.05)
    assert b["match_gain_db"] == pytest.approx(0.0, abs=0.05)
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["version"] for r in rows] == ["A", "B"]
    assert float(rows[1]["integrated_lufs_diff"]) == pytest.approx(-5.0, abs=0.05)


def test_it_refuses_before_any_work(remaster, tmp_path):
    before = remaster.read_bytes()
    done = _run(CLOUD, remaster, "-o", remaster)
    assert done.returncode != 0
    assert remaster.read_bytes() == before
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "output" in lines[0], done.stderr
    done = _run(CLOUD, remaster)
    assert done.returncode != 0 and "say what to write" in done.stderr
    done = _run(CLOUD, tmp_path / "missing.wav", "--json")
    assert done.returncode != 0 and "missing.wav" in done.stderr and done.stdout == ""
