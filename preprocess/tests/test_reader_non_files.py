"""The PLY readers (``read_ply``, ``map_ply``, ``read_ply_metadata``), ``loudscape.read_cloud``
and ``loudscape-extract export`` on things that are not clouds: a FIFO, a link to /dev/zero, a
directory, a 1 GiB file of zeros. Each is one clear ExtractError at once, never a hang, and the
memory used does not grow with the junk's size.

Every case runs in a child process with a timeout and an address-space limit, so a regression
fails (timeout, MemoryError) instead of hanging the run or taking the machine.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
PREPROCESS = os.path.dirname(HERE)

#: What one read may cost at most, with Python, numpy and the package imported (about 60 MB):
#: generous, and far below the 1.1 GB (read_cloud) and 2.2 GB (export) of a 1 GiB zero file
#: that read whole.
PEAK_LIMIT_MB = 300

_CHILD = r"""
import json, resource, sys
resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
from loudscape_extract.errors import ExtractError
reader, path = sys.argv[1], sys.argv[2]
if reader == "export":
    import contextlib, io
    from loudscape_extract import cli
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        status = cli.main(["export", path, "-o", sys.argv[3]])
    outcome = {"status": status, "message": err.getvalue()}
else:
    if reader == "read_cloud":
        from loudscape import read_cloud as call
    else:
        import loudscape_extract.ply as ply
        call = getattr(ply, reader)
    try:
        call(path)
        outcome = {"message": None}
    except ExtractError as exc:
        outcome = {"message": str(exc)}
# This process's own peak: VmHWM belongs to the address space exec made. (getrusage's
# ru_maxrss is kept across fork and exec on Linux: it would report the peak of the test run
# that started this child.)
try:
    with open("/proc/self/status") as status:
        line = next(l for l in status if l.startswith("VmHWM:"))
    outcome["peak_mb"] = int(line.split()[1]) / 1024
except (OSError, StopIteration):
    outcome["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(outcome))
"""

READERS = ["read_ply", "map_ply", "read_ply_metadata", "read_cloud", "export"]


def _read_in_child(reader: str, path, tmp_path, *, timeout: float = 60) -> dict:
    env = {**os.environ, "PYTHONPATH": PREPROCESS, "OPENBLAS_NUM_THREADS": "1"}
    argv = [sys.executable, "-c", _CHILD, reader, str(path), str(tmp_path / "out.vtp")]
    try:
        done = subprocess.run(
            argv, capture_output=True, text=True, env=env, timeout=timeout, check=False
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"{reader} on {path} did not answer in {timeout} s (it blocked)")
    assert done.returncode == 0, done.stderr[-2000:]
    outcome = json.loads(done.stdout)
    if reader == "export":
        assert outcome["status"] == 1, outcome
        assert outcome["message"].count("\n") == 1, outcome
        assert not (tmp_path / "out.vtp").exists()
    else:
        assert outcome["message"] is not None, f"{reader} accepted {path}"
    return outcome


@pytest.mark.parametrize("reader", READERS)
def test_a_fifo_is_refused_at_once(tmp_path, reader):
    fifo = tmp_path / "pipe.ply"
    os.mkfifo(fifo)
    outcome = _read_in_child(reader, fifo, tmp_path, timeout=30)
    assert "FIFO" in outcome["message"] and "pipe.ply" in outcome["message"], outcome


@pytest.mark.parametrize("reader", READERS)
def test_a_link_to_dev_zero_is_refused_at_once(tmp_path, reader):
    link = tmp_path / "zero.ply"
    link.symlink_to("/dev/zero")
    outcome = _read_in_child(reader, link, tmp_path, timeout=30)
    assert "a device, not a regular file" in outcome["message"], outcome
    assert outcome["peak_mb"] < PEAK_LIMIT_MB, outcome


@pytest.mark.parametrize("reader", READERS)
def test_a_directory_is_refused(tmp_path, reader):
    folder = tmp_path / "folder.ply"
    folder.mkdir()
    outcome = _read_in_child(reader, folder, tmp_path, timeout=30)
    assert "directory" in outcome["message"], outcome


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("prefix", [b"", b"ply\n"], ids=["zeros", "ply-then-zeros"])
def test_a_gigabyte_of_zeros_costs_no_more_than_a_small_file(tmp_path, reader, prefix):
    junk = tmp_path / "junk.ply"
    with open(junk, "wb") as handle:
        handle.write(prefix)
        handle.truncate(1 << 30)  # sparse: no disk used
    outcome = _read_in_child(reader, junk, tmp_path)
    assert "not a PLY" in outcome["message"] or "end_header" in outcome["message"], outcome
    assert outcome["peak_mb"] < PEAK_LIMIT_MB, outcome
