"""The cache repairs itself: an entry that cannot be read is recomputed and replaced, with one
line saying so; the next run reads the new entry silently."""

import json

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.timeline.cache import read_entry

from conftest import musical_signal

RATE = 8000


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def damage_truncate(path):
    path.write_bytes(path.read_bytes()[:100])


def damage_empty(path):
    path.write_bytes(b"")


def damage_shape(path):
    # The head line promises one frame more than the series hold.
    magic, head, body = path.read_bytes().split(b"\n", 2)
    meta = json.loads(head)
    meta["frames"] += 1
    path.write_bytes(magic + b"\n" + json.dumps(meta).encode() + b"\n" + body)


def damage_garbage(path):
    path.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 4)


def damage_head(path):
    magic, _head, body = path.read_bytes().split(b"\n", 2)
    path.write_bytes(magic + b"\n{not json\n" + body)


@pytest.mark.parametrize(
    "damage", [damage_truncate, damage_empty, damage_shape, damage_garbage, damage_head]
)
def test_unreadable_entry_is_recomputed_and_replaced(tmp_path, capsys, damage):
    for i in range(2):
        y = musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5
        soundfile.write(tmp_path / f"s{i}.wav", y.astype(np.float32), RATE)
    (tmp_path / "songs.csv").write_text("path,year\ns0.wav,1990\ns1.wav,1991\n")
    cache, out = tmp_path / "cache", tmp_path / "t.ply"
    argv = ["timeline", "--manifest", tmp_path / "songs.csv", "-o", out, "--cache-dir", cache]
    argv += ["--n-fft", 256, "--hop", 128, "--jobs", 1]
    assert run(argv, capsys)[0] == 0
    first = out.read_bytes()
    entry = sorted(cache.iterdir())[0]
    damage(entry)
    assert read_entry(str(entry))[0] is None

    status, err = run(argv, capsys)
    assert status == 0, err
    notes = [line for line in err.splitlines() if "cache entry" in line]
    assert len(notes) == 1 and "recomputed and replaced" in notes[0] and entry.name in notes[0]
    assert "1 from cache" in err and out.read_bytes() == first
    assert read_entry(str(entry))[0] is not None

    status, err = run(argv, capsys)
    assert status == 0 and "cache entry" not in err and "2 from cache" in err
