"""Writers sync the data to the disk before the rename (a power cut cannot leave a renamed file
whose data never arrived) and the folder after it; a full disk reads as a full disk."""

import errno
import os

import numpy as np
import pytest

from loudscape_extract import paths
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import read_ply, write_ply
from loudscape_extract.timeline import cache
from loudscape_extract.timeline.frames import SongFrames
from loudscape_extract.timeline.layout import METRIC_KEYS

AXES = {n: {"min": 0.0, "max": 1.0} for n in ("x", "y", "z", "scalar", "hp")}


@pytest.fixture
def calls(monkeypatch):
    """Every fsync (of a file or a folder) and rename, in order."""
    seen = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        kind = "fsync-dir" if os.path.isdir(f"/proc/self/fd/{fd}") else "fsync"
        seen.append((kind, os.path.basename(os.readlink(f"/proc/self/fd/{fd}"))))
        real_fsync(fd)

    def replace(a, b):
        seen.append(("replace", os.path.basename(b)))
        real_replace(a, b)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    return seen


def assert_synced_then_renamed(seen, name, folder):
    kinds = [kind for kind, _ in seen]
    assert kinds == ["fsync", "replace", "fsync-dir"], seen
    assert seen[1] == ("replace", name) and seen[2][1] == os.path.basename(folder)
    assert seen[0][1] != name  # the temporary was synced, before it got the name


def test_write_ply_syncs_before_the_rename(tmp_path, calls):
    out = tmp_path / "a.ply"
    points = np.full((4, 5), 0.5, np.float32)
    write_ply(out, points=points, metadata={"point_count": 4, "axes": AXES})
    assert_synced_then_renamed(calls, "a.ply", tmp_path)
    assert np.array_equal(read_ply(out)[0], points)


def test_cache_entry_syncs_before_the_rename(tmp_path, calls):
    n = 3
    song = SongFrames(
        rms_dbfs=np.full(n, -20, np.float32),
        crest_db=np.full(n, 10, np.float32),
        loudness_a_db=np.full(n, -25, np.float32),
        hp_mean=np.full(n, 0.5, np.float32),
        psr_db=np.full(n, 9, np.float32),
        crest_3s_db=np.full(n, 12, np.float32),
        n_frames_total=n,
        metrics=dict.fromkeys(METRIC_KEYS),
    )
    entry = tmp_path / "e.frames"
    cache.save_entry(str(entry), song)
    assert_synced_then_renamed(calls, "e.frames", tmp_path)
    assert cache.read_entry(str(entry))[1] == ""


def test_atomic_output_syncs_before_the_rename(tmp_path, calls):
    out = tmp_path / "a.vtp"
    with paths.atomic_output(str(out)) as temporary:
        with open(temporary, "w") as handle:
            handle.write("x")
    assert_synced_then_renamed(calls, "a.vtp", tmp_path)


@pytest.mark.parametrize(
    "error",
    [
        OSError(errno.ENOSPC, "No space left on device"),
        OSError("868970 requested and 785814 written"),  # numpy's tofile
    ],
)
def test_a_full_disk_reads_as_a_full_disk(tmp_path, monkeypatch, error):
    import loudscape_extract.ply as ply

    real_open = ply.tempfile.NamedTemporaryFile

    class Full:
        def __init__(self, handle):
            self.handle, self.name = handle, handle.name

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.close()

        def write(self, data):
            raise error

        def __getattr__(self, name):
            return getattr(self.handle, name)

    monkeypatch.setattr(ply.tempfile, "NamedTemporaryFile", lambda **kw: Full(real_open(**kw)))
    out = tmp_path / "a.ply"
    with pytest.raises(ExtractError) as caught:
        write_ply(out, points=np.zeros((2, 5), np.float32), metadata={"axes": AXES})
    message = str(caught.value)
    assert f"no space left on the device of {str(tmp_path)!r}" in message
    assert "bytes free" in message and "requested" not in message
    assert os.listdir(tmp_path) == []  # no temporary left


def test_other_write_errors_keep_their_reason():
    reason = paths.write_failure(OSError(errno.EACCES, "Permission denied"), directory="/x")
    assert reason == "cannot write file (Permission denied)"
