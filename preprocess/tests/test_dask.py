"""Timelines on Dask: a two-worker LocalCluster gives the pool's file; a dying worker fails
only its own song; the point cap on frames per song."""

from __future__ import annotations

import os

import numpy as np
import pytest
from test_timeline import FAST, cli_timeline, run, tagged_folder

from loudscape_extract.ply import read_ply
from loudscape_extract.timeline import MIN_FRAMES_PER_SONG, frames_per_song_for
from loudscape_extract.timeline.engine import _EXIT_HOOK

pytest.importorskip("dask.distributed")

DASK = [a if a != "1" else "2" for a in FAST] + ["--dask"]  # --jobs 2: two worker processes


def test_local_cluster_equals_process_pool_and_shares_the_cache(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990, 2000, 1980, 1995])
    pool, dask = tmp_path / "pool.ply", tmp_path / "dask.ply"
    argv = ["timeline", tmp_path / "m", "--no-cache", "--n-fft", 256, "--hop", 128]
    assert run([*argv, "-o", pool, "--jobs", 2], capsys)[0] == 0
    cache = tmp_path / "cache"
    argv = ["timeline", tmp_path / "m", "-o", dask, "--cache-dir", cache, *DASK]
    status, err = run(argv, capsys)
    assert status == 0 and ", 0 from cache, " in err
    assert dask.read_bytes() == pool.read_bytes()
    # Every worker wrote its songs' entries into the shared folder, atomically (no temp left).
    assert sorted(os.path.splitext(n)[1] for n in os.listdir(cache)) == [".frames"] * 4
    status, err = run(argv, capsys)
    assert status == 0 and ", 4 from cache, " in err
    assert dask.read_bytes() == pool.read_bytes()


def test_a_dying_worker_fails_only_its_song(tmp_path, capsys, monkeypatch):
    songs = tagged_folder(tmp_path / "m", [1990, 2000, 1980, 1995, 1985])
    monkeypatch.setenv(_EXIT_HOOK, "song1.flac")  # its task calls os._exit in the worker
    out = tmp_path / "t.ply"
    status, err = run(["timeline", tmp_path / "m", "-o", out, "--no-cache", *DASK], capsys)
    assert status == 1
    assert f"skipped: {songs[1]}: worker failed (worker died)" in err
    points, meta = read_ply(out)
    assert sorted(s["path"] for s in meta["songs"]) == sorted(
        str(p) for i, p in enumerate(songs) if i != 1
    )
    assert [s["path"] for s in meta["extraction"]["skipped"]] == [str(songs[1])]
    assert points.shape[0] == sum(s["point_count"] for s in meta["songs"]) > 0


def test_unreachable_scheduler_is_one_line(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990])
    argv = ["timeline", tmp_path / "m", "-o", tmp_path / "t.ply", "--no-cache"]
    status, err = run([*argv, "--scheduler", "tcp://127.0.0.1:9", *FAST], capsys)
    assert status == 1
    assert err.count("\n") == 1 and "cannot reach the Dask scheduler" in err
    assert not (tmp_path / "t.ply").exists()


def test_frames_per_song_rule():
    assert frames_per_song_for(100, 1024, 4_000_000) == 1024
    assert frames_per_song_for(10_000, 1024, 4_000_000) == 400
    assert frames_per_song_for(1_000_000, 1024, 4_000_000) == MIN_FRAMES_PER_SONG
    assert frames_per_song_for(1_000_000, 10, 4_000_000) == 10  # never above the request
    assert frames_per_song_for(10_000, 1024, 0) == 1024  # no cap
    assert frames_per_song_for(10_000, 1024, None) == 1024


def test_max_points_lowers_frames_per_song(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990, 2000])
    out = tmp_path / "t.ply"
    extra = ["--frames-per-song", 90, "--max-points", 150]
    status, err = cli_timeline([tmp_path / "m", *extra], out, capsys, tmp_path / "c")
    assert status == 0 and "75 frames per song (of 90)" in err
    points, meta = read_ply(out)
    assert [s["point_count"] for s in meta["songs"]] == [75, 75] and points.shape[0] == 150
    assert meta["extraction"]["frames_per_song"] == 75
    assert meta["extraction"]["frames_per_song_requested"] == 90
    assert meta["extraction"]["max_points"] == 150


def test_cache_entry_round_trip_and_damage(tmp_path):
    from loudscape_extract.timeline.cache import load_entry, save_entry
    from loudscape_extract.timeline.frames import SongFrames
    from loudscape_extract.timeline.layout import METRIC_KEYS

    n = 7
    series = {
        name: np.arange(n, dtype=np.float32) + i
        for i, name in enumerate(
            (
                "rms_dbfs",
                "crest_db",
                "loudness_a_db",
                "hp_mean",
                "psr_db",
                "crest_3s_db",
                "momentary_lufs",
                "short_term_lufs",
            )
        )
    }
    series["psr_db"][2] = np.nan
    series["hp_mean"] /= 10.0  # a ratio in [0, 1]
    metrics = {**dict.fromkeys(METRIC_KEYS), "dr_db": 8.5}  # an entry has them all
    song = SongFrames(**series, n_frames_total=9, metrics=metrics)
    path = str(tmp_path / "entry.frames")
    save_entry(path, song)
    assert os.listdir(tmp_path) == ["entry.frames"]
    back = load_entry(path)
    assert back.n_frames_total == 9 and back.metrics == song.metrics
    for name, values in series.items():
        assert np.array_equal(getattr(back, name), values, equal_nan=True), name
    data = open(path, "rb").read()
    open(path, "wb").write(data[:-3])  # truncated: recomputed, not misread
    assert load_entry(path) is None
    open(path, "wb").write(b"PK\x03\x04 an old npz")
    assert load_entry(path) is None
