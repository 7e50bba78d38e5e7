"""Signals and interrupts, with real processes: SIGTERM and Ctrl+C leave no temporaries and no
worker processes, stop a timeline within seconds and keep what is cached; workers whose
parent is killed exit by themselves."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import soundfile

from loudscape_extract.timeline.cache import read_entry

from conftest import musical_signal

RATE = 22050
SONGS = 8


def children(pid):
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    found = []
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                with open(f"/proc/{name}/stat") as handle:
                    fields = handle.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(name))
    return found


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def catches_sigterm(pid):
    """True once ``pid`` has a SIGTERM handler (bit 15 of SigCgt in /proc/PID/status)."""
    with open(f"/proc/{pid}/status") as handle:
        caught = next(line for line in handle if line.startswith("SigCgt:")).split()[1]
    return bool(int(caught, 16) & (1 << (signal.SIGTERM - 1)))


def wait_for(condition, timeout, what):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


@pytest.fixture
def collection(tmp_path):
    """Songs long enough (30 s each) that a timeline is still busy when it is signalled."""
    folder = tmp_path / "songs"
    folder.mkdir()
    lines = ["path,year"]
    for i in range(SONGS):
        y = musical_signal(sample_rate=RATE, duration_s=30.0, seed=i) * 0.4
        soundfile.write(folder / f"s{i}.flac", y.astype(np.float32), RATE)
        lines.append(f"s{i}.flac,{1980 + i}")
    (folder / "songs.csv").write_text("\n".join(lines) + "\n")
    return folder


def start_timeline(folder, out, cache, *extra):
    argv = [sys.executable, "-m", "loudscape_extract.cli", "timeline"]
    argv += ["--manifest", str(folder / "songs.csv"), "-o", str(out), "--cache-dir", str(cache)]
    return subprocess.Popen(
        [*argv, "--jobs", "2", *extra],
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a shell job would be
    )


def leftovers(*folders):
    return [
        name
        for folder in folders
        if folder.exists()
        for name in os.listdir(folder)
        if ".tmp" in name
    ]


@pytest.mark.parametrize(
    ("how", "status", "word"),
    [("SIGTERM to the process", 143, "terminated"), ("Ctrl+C to the group", 130, "interrupted")],
)
def test_timeline_stops_fast_without_orphans_and_keeps_the_cache(
    tmp_path, collection, how, status, word
):
    out, cache = tmp_path / "t.ply", tmp_path / "cache"
    process = start_timeline(collection, out, cache)
    try:
        wait_for(lambda: len(children(process.pid)) >= 2, 30, "two workers")
        workers = children(process.pid)
        wait_for(
            lambda: cache.exists() and any(n.endswith(".frames") for n in os.listdir(cache)),
            120,
            "a cached song",
        )
        sent = time.monotonic()
        if how.startswith("SIGTERM"):
            process.send_signal(signal.SIGTERM)
        else:
            os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=10)
        stopped = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == status, err
    assert stopped < 3.0, f"took {stopped:.1f} s"
    assert err.strip().splitlines()[-1].startswith(f"loudscape-extract: {word}; no file written")
    assert "Traceback" not in err
    wait_for(lambda: not any(alive(pid) for pid in workers), 5, "the workers to exit")
    assert not out.exists() and leftovers(tmp_path, cache) == []
    kept = [n for n in os.listdir(cache) if n.endswith(".frames")]
    assert 1 <= len(kept) < SONGS
    assert all(read_entry(str(cache / n))[0] is not None for n in kept)
    # The next run uses what was cached.
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "loudscape_extract.cli",
            "timeline",
            "--manifest",
            str(collection / "songs.csv"),
            "-o",
            str(out),
            "--cache-dir",
            str(cache),
            "--jobs",
            "2",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert f"{len(kept)} from cache" in result.stderr


def test_workers_exit_when_their_parent_is_killed(tmp_path, collection):
    process = start_timeline(collection, tmp_path / "t.ply", tmp_path / "cache")
    try:
        wait_for(lambda: len(children(process.pid)) >= 2, 30, "two workers")
        workers = children(process.pid)
        process.kill()
        process.wait(timeout=10)
    finally:
        if process.poll() is None:
            process.kill()
    wait_for(lambda: not any(alive(pid) for pid in workers), 5, "orphaned workers to exit")


WRITER = textwrap.dedent(
    """
    import os, sys, time
    import numpy as np
    from loudscape_extract.interrupts import sigterm_raises
    from loudscape_extract.paths import atomic_output
    from loudscape_extract.ply import write_ply, write_ply_blocks
    from loudscape_extract.timeline.cache import save_entry
    from loudscape_extract.timeline.frames import SongFrames

    def stall(*_args, **_kwargs):
        print("writing", flush=True)
        time.sleep(60)

    target, kind = sys.argv[1], sys.argv[2]
    with sigterm_raises():
        if kind == "ply":
            os.chmod = stall  # called once the temporary is written, before os.replace
            write_ply(target, points=np.zeros((3, 5)), metadata={"a": 1})
        elif kind == "blocks":
            def blocks():
                yield np.zeros((3, 5))
                stall()  # the header and a first block are in the temporary
                yield np.zeros((3, 5))
            write_ply_blocks(target, n_points=6, metadata={"a": 1}, blocks=blocks())
        elif kind == "png":
            with atomic_output(target) as temporary:
                open(temporary, "wb").write(b"partial")
                stall()
        else:
            os.replace = stall  # the cache entry's temporary is written, not yet renamed
            series = {k: np.zeros(3, np.float32) for k in ("psr_db", "crest_3s_db")}
            frames = SongFrames(
                *(np.zeros(3, np.float32) for _ in range(4)), n_frames_total=3, **series
            )
            save_entry(target, frames)
    """
)


@pytest.mark.parametrize(
    ("kind", "name"),
    [
        ("ply", "c.ply"),
        ("blocks", "s.ply"),
        ("png", "r.png"),
        ("frames", "e.frames"),
    ],
)
def test_sigterm_during_a_write_leaves_no_temporary(tmp_path, kind, name):
    script = tmp_path / "writer.py"
    script.write_text(WRITER)
    folder = tmp_path / "out"
    folder.mkdir()
    process = subprocess.Popen(
        [sys.executable, str(script), str(folder / name), kind],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline() == "writing\n"
        assert leftovers(folder), "the temporary should exist while writing"
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=10)
    finally:
        if process.poll() is None:
            process.kill()
    assert "Terminated" in err  # the exception SIGTERM became
    assert os.listdir(folder) == []


def test_sigterm_to_song_exits_143_and_writes_nothing(tmp_path):
    source = tmp_path / "long.wav"
    y = musical_signal(sample_rate=RATE, duration_s=600.0) * 0.4
    soundfile.write(source, y.astype(np.float32), RATE)
    process = subprocess.Popen(
        [sys.executable, "-m", "loudscape_extract.cli", "song", str(source)],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        # Signal once the command has installed its handler (before that, the default
        # action ends it, writing nothing either) and has begun writing: its points' body
        # file is beside the output.
        wait_for(lambda: catches_sigterm(process.pid), 60, "the SIGTERM handler")
        body = f".long.ply.points-{process.pid}"
        wait_for(lambda: body in os.listdir(tmp_path), 120, "the points' body file")
        assert process.poll() is None, "finished before the signal: make the song longer"
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=10)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 143
    assert err == "loudscape-extract: terminated; no file written\n"
    assert sorted(os.listdir(tmp_path)) == ["long.wav"]


def descendants(pid):
    found, queue = [], [pid]
    while queue:
        for child in children(queue.pop()):
            found.append(child)
            queue.append(child)
    return found


@pytest.mark.parametrize(
    ("how", "status", "word"),
    [("SIGTERM to the process", 143, "terminated"), ("Ctrl+C to the group", 130, "interrupted")],
)
def test_dask_timeline_stops_and_closes_its_local_cluster(tmp_path, collection, how, status, word):
    pytest.importorskip("dask.distributed")
    out, cache = tmp_path / "t.ply", tmp_path / "cache"
    process = start_timeline(collection, out, cache, "--dask")
    try:
        wait_for(
            lambda: cache.exists() and any(n.endswith(".frames") for n in os.listdir(cache)),
            120,
            "a cached song",
        )
        workers = descendants(process.pid)
        assert workers, "the local cluster's worker processes"
        sent = time.monotonic()
        if how.startswith("SIGTERM"):
            process.send_signal(signal.SIGTERM)
        else:
            os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=30)
        stopped = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == status, err
    assert stopped < 15.0, f"took {stopped:.1f} s"
    assert err.strip().splitlines()[-1].startswith(f"loudscape-extract: {word}; no file written")
    assert "Traceback" not in err, err
    wait_for(lambda: not any(alive(pid) for pid in workers), 10, "the cluster's processes to exit")
    assert not out.exists()
    kept = [n for n in os.listdir(cache) if n.endswith(".frames")]
    assert kept and all(read_entry(str(cache / n))[0] is not None for n in kept)
