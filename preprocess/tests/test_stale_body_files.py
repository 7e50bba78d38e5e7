"""An extraction killed outright (SIGKILL) leaves its hidden body file ``.NAME.ply.points-PID``
beside the output; the next extraction into that folder removes it, and never the body file
of an extraction that is still running."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import soundfile

from loudscape_extract.song import extract_song, remove_stale_body_files

from conftest import musical_signal

HERE = os.path.dirname(os.path.abspath(__file__))
SR = 8000


def _dead_pid() -> int:
    """The PID of a process that has exited and been reaped."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def _song(path, seconds: float) -> str:
    soundfile.write(path, musical_signal(sample_rate=SR, duration_s=seconds) * 0.5, SR)
    return str(path)


def test_a_sigkilled_extraction_leaves_a_body_file_the_next_one_removes(tmp_path):
    source = _song(tmp_path / "long.wav", 60.0)
    env = {**os.environ, "PYTHONPATH": os.path.dirname(HERE), "OPENBLAS_NUM_THREADS": "1"}
    argv = [sys.executable, "-m", "loudscape_extract.cli", "song", source]
    argv += ["-o", str(tmp_path / "killed.ply"), "--n-fft", "256", "--hop", "128"]
    child = subprocess.Popen(
        [*argv, "--progress", "json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    )
    body = None
    deadline = time.monotonic() + 120
    try:
        for line in child.stdout:  # wait for the event: the first points are in the body file
            record = json.loads(line)
            if "points" in record:
                body = record["points"]["path"]
                break
            assert time.monotonic() < deadline, "no points line in 120 s"
        assert body is not None, child.stderr.read().decode()
        child.send_signal(signal.SIGKILL)
    finally:
        child.kill()
        child.wait()
    assert os.path.basename(body) == f".killed.ply.points-{child.pid}"
    assert os.path.isfile(body), "SIGKILL left no body file: the test proves nothing"
    # A running extraction's body file: a live process stands in for it.
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        running = tmp_path / f".other.ply.points-{sleeper.pid}"
        running.write_bytes(b"\0" * 20)
        keep = tmp_path / f".keep.ply.points-{os.getppid()}"
        keep.write_bytes(b"\0" * 20)
        extract_song(_song(tmp_path / "short.wav", 1.0), str(tmp_path / "next.ply"))
    finally:
        sleeper.kill()
        sleeper.wait()
    assert not os.path.exists(body), "the dead extraction's body file is still there"
    assert running.exists() and keep.exists(), "a live process's body file was removed"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == sorted(
        [running.name, keep.name]
    )


def test_only_dead_processes_body_files_go(tmp_path):
    dead = _dead_pid()
    stale = tmp_path / f".song.ply.points-{dead}"
    stale_upper = tmp_path / f".SONG.PLY.points-{dead}"
    alive = tmp_path / f".song.ply.points-{os.getppid()}"
    unrelated = [
        tmp_path / f"song.ply.points-{dead}",  # not hidden: not a body file
        tmp_path / f".song.txt.points-{dead}",  # not a cloud's
        tmp_path / f".song.ply.points-{dead}x",
        tmp_path / ".song.ply.points-0",
    ]
    for path in [stale, stale_upper, alive, *unrelated]:
        path.write_bytes(b"x")
    folder_named_so = tmp_path / f".dir.ply.points-{dead}"
    folder_named_so.mkdir()
    removed = remove_stale_body_files(str(tmp_path))
    assert sorted(removed) == sorted([str(stale), str(stale_upper)])
    assert not stale.exists() and not stale_upper.exists()
    assert alive.exists() and folder_named_so.is_dir()
    assert all(path.exists() for path in unrelated)


def test_a_folder_that_cannot_be_listed_is_no_error(tmp_path):
    assert remove_stale_body_files(str(tmp_path / "missing")) == []
