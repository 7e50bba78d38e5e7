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


# -- entries of the right length whose content is wrong (issue: they were trusted) ---------


def _rewrite(path, head=None, body=None):
    """Rewrite an entry's head or body and give it a valid checksum, as a buggy or hostile
    writer would: only the value checks can refuse it."""
    import hashlib

    first, rest = path.read_bytes().split(b"\n", 1)
    old_head, old_body = rest.split(b"\n", 1)
    content = (head if head is not None else old_head) + b"\n"
    content += body if body is not None else old_body
    magic = first.rsplit(b" ", 1)[0]
    path.write_bytes(magic + b" " + hashlib.sha256(content).hexdigest().encode() + b"\n" + content)


def damage_random_bytes_same_length(path):
    data = path.read_bytes()
    first, rest = data.split(b"\n", 1)
    head, body = rest.split(b"\n", 1)
    noise = np.random.default_rng(5).integers(0, 256, len(body), dtype=np.uint8).tobytes()
    path.write_bytes(first + b"\n" + head + b"\n" + noise)  # the checksum no longer matches


def damage_random_series_resummed(path):
    body = path.read_bytes().split(b"\n", 2)[2]
    _rewrite(path, body=np.random.default_rng(6).integers(0, 256, len(body), np.uint8).tobytes())


def damage_nan_series(path):
    body = np.frombuffer(path.read_bytes().split(b"\n", 2)[2], "<f4").copy()
    body[: body.size // 6] = np.nan  # the whole rms_dbfs series
    _rewrite(path, body=body.tobytes())


def damage_empty_metrics(path):
    head = json.loads(path.read_bytes().split(b"\n", 2)[1])
    head["metrics"] = {}
    _rewrite(path, head=json.dumps(head).encode())


def damage_nan_metric(path):
    head = path.read_bytes().split(b"\n", 2)[1]
    _rewrite(path, head=head.replace(b'"integrated_lufs": ', b'"integrated_lufs": NaN, "x": '))


def damage_flipped_bit(path):
    data = bytearray(path.read_bytes())
    data[-7] ^= 0x10
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        (damage_random_bytes_same_length, "checksum"),
        (damage_flipped_bit, "checksum"),
        (damage_random_series_resummed, "series"),
        (damage_nan_series, "series rms_dbfs holds NaN"),
        (damage_empty_metrics, "metrics lack integrated_lufs"),
        (damage_nan_metric, "metric integrated_lufs is nan"),
    ],
)
def test_wrong_content_of_the_right_length_is_recomputed(tmp_path, capsys, damage, reason):
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
    size = entry.stat().st_size
    damage(entry)
    song, problem = read_entry(str(entry))
    assert song is None and reason in problem, problem
    status, err = run(argv, capsys)
    assert status == 0, err
    notes = [line for line in err.splitlines() if "cache entry" in line]
    assert len(notes) == 1 and reason in notes[0] and "recomputed and replaced" in notes[0]
    # The timeline is the one computed from the audio: z axis and metrics as before.
    assert out.read_bytes() == first
    assert entry.stat().st_size == size and read_entry(str(entry))[0] is not None


def test_entry_problem_checks_any_series_by_name():
    from loudscape_extract.timeline.cache import entry_problem
    from loudscape_extract.timeline.layout import METRIC_KEYS

    metrics = dict.fromkeys(METRIC_KEYS)
    assert entry_problem({"rms_dbfs": np.array([-20.0])}, metrics) == ""
    # A series this module does not know (added later) is still checked: finite or NaN.
    assert entry_problem({"momentary_lufs": np.array([np.nan, -14.0])}, metrics) == ""
    assert "infinite" in entry_problem({"momentary_lufs": np.array([np.inf])}, metrics)
    assert "outside" in entry_problem({"momentary_lufs": np.array([-6.8e14])}, metrics)
    assert "hp_mean" in entry_problem({"hp_mean": np.array([1.5])}, metrics)
