"""The window goes idle at rest: once the demo is shown in a view and nothing moves, it stops
painting, in every view.

A window that keeps asking for frames at rest costs a whole core (and on a laptop its battery)
while the user only looks, and it makes the window benchmark's waits for a quiet window time out.
Each view is opened on the demo in a private Xvfb screen (bench/bench_window.py's helpers), the
painted frames are counted through the X DAMAGE extension (bench/xdriver.py) and, once the data
shows and the view's grid or surface has been built, the window must fall quiet and stay so.

The binary is ``$LOUDSCAPE_BIN``, by default ``target/debug/loudscape``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import bench_window as bw  # noqa: E402
from xdriver import XDriver  # noqa: E402

BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape"))
DEMO = ROOT / "data" / "demo_song.ply"
# The window builds the view's grid (and surface) after the data shows; on lavapipe under load
# that can take a while, so the quiet period only has to begin within this time.
SETTLE_S = 120.0
QUIET_S = 3.0


@pytest.fixture(scope="module")
def display():
    if shutil.which("Xvfb") is None or shutil.which("xdotool") is None:
        pytest.fail("Xvfb and xdotool are needed (scripts/setup-system.sh installs them)")
    if not BINARY.exists():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    xvfb, name = bw.start_xvfb()
    yield name
    xvfb.terminate()
    xvfb.wait(10)


@pytest.mark.parametrize("view", ["points", "surface", "volume"])
def test_the_window_stops_painting_at_rest(display, view, tmp_path):
    runtime = tmp_path / "runtime"
    runtime.mkdir(mode=0o700)
    env = dict(
        os.environ,
        DISPLAY=display,
        HOME=str(tmp_path),
        XDG_CONFIG_HOME=str(tmp_path / "config"),
        XDG_DATA_HOME=str(tmp_path / "data"),
        XDG_CACHE_HOME=str(tmp_path / "cache"),
        XDG_RUNTIME_DIR=str(runtime),
    )
    env.pop("WAYLAND_DISPLAY", None)
    with open(tmp_path / "log.txt", "w") as log:
        proc = subprocess.Popen(
            [str(BINARY), str(DEMO), "--view", view], env=env, stdout=log, stderr=log
        )
    try:
        try:
            wid = bw.find_window(display, proc, 60)
        except RuntimeError as error:
            pytest.fail(f"{error}: {(tmp_path / 'log.txt').read_text().strip()}")
        bw.size_window(wid, env)
        x = XDriver(display)
        x.watch(wid)
        # The pointer out of the view, so no hover read-out is drawn.
        x.move(5, bw.HEIGHT - 5)
        end = time.monotonic() + SETTLE_S
        while not bw.shows_data(x):
            assert time.monotonic() < end, f"the {view} view never showed the demo"
            x.pump(0.2)
        assert x.wait_quiet(QUIET_S, max(end - time.monotonic(), QUIET_S)), (
            f"the {view} view kept painting at rest: {len(x.frames)} frames, "
            f"none {QUIET_S:.0f} s apart within {SETTLE_S:.0f} s"
        )
        before = len(x.frames)
        x.pump_until(time.monotonic() + QUIET_S)
        assert len(x.frames) == before, (
            f"the {view} view painted {len(x.frames) - before} frames at rest after falling quiet"
        )
        assert proc.poll() is None, f"loudscape exited with {proc.returncode}"
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
