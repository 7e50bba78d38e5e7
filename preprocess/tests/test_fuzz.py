"""The Python fuzzers (fuzz_py.py) in a short run: a few seconds of structured and mutated
manifests and PLY files (read_cloud's behind FIFOs, devices and folders too) and of the notebook
API's arguments, each under its time and memory limit, with no finding. ``make
fuzz-py`` runs them for longer. Also the regressions of what they found."""

import json
import os
import subprocess
import sys

import pytest

from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import read_ply

HERE = os.path.dirname(os.path.abspath(__file__))


def test_short_fuzz_run_has_no_finding():
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": os.path.join(HERE, "..")}
    command = [sys.executable, os.path.join(HERE, "fuzz_py.py"), "--seconds", "4", "--round", "20"]
    done = subprocess.run(
        [*command, "--json"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    assert done.returncode in (0, 1), done.stderr
    report = json.loads(done.stdout)
    assert report["findings"] == [], report["findings"]
    for target in ("manifest", "ply", "read_cloud", "api"):
        assert report["inputs"][target] >= 20, report


@pytest.mark.parametrize("count", [b"x", b"1e3", b"", b"-4"])
def test_read_ply_bad_vertex_count_is_an_error_not_a_traceback(tmp_path, count):
    # Found by fuzz_py.py: int() of the count raised ValueError out of read_ply.
    path = tmp_path / "a.ply"
    header = b"ply\nformat binary_little_endian 1.0\nelement vertex " + count + b"\n"
    header += b"".join(b"property float " + p + b"\n" for p in (b"x", b"y", b"z", b"scalar", b"hp"))
    path.write_bytes(header + b"end_header\n")
    with pytest.raises(ExtractError, match="vertex count"):
        read_ply(path)
