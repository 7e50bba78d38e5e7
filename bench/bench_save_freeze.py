"""How long the window does not answer after Ctrl+S (Save PNG) on a large cloud.

Opens ``loudscape FILE`` in the current X display (run it under ``xvfb-run``) with a private
HOME and no file dialog, waits ``--settle`` seconds for the points to reach full detail, presses
Ctrl+S through xdotool and keeps moving the pointer over the view, and prints when the window's
"saving …" line (written in the frame that handles the key) and its "picture: saved" line came,
in seconds after the key. Figures, not a test: the machine's load moves them.

Example (``--compare B`` for the A/B compare, ``--press compare=difference`` for its
Difference view)::

    xvfb-run -a -s "-screen 0 1600x1000x24" python bench/bench_save_freeze.py \\
        --loudscape target/debug/loudscape out/bench-window/real_5m.ply
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time


def xdotool(*args: str) -> str:
    """Runs xdotool with ``args``; what it printed, stripped."""
    done = subprocess.run(["xdotool", *args], capture_output=True, text=True, check=False)
    return done.stdout.strip()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("cloud", help="a .ply cloud (or a song) to open")
    parser.add_argument("--loudscape", default="target/release/loudscape")
    parser.add_argument("--settle", type=float, default=25.0, help="seconds before Ctrl+S")
    parser.add_argument("--compare", help="B of an A/B compare (loudscape FILE --compare B)")
    parser.add_argument(
        "--press", action="append", default=[], help="a scripted press before Ctrl+S (repeat)"
    )
    args = parser.parse_args()
    binary = os.path.abspath(args.loudscape)
    cloud = os.path.abspath(args.cloud)
    for path in (binary, cloud):
        if not os.path.isfile(path):
            print(f"bench_save_freeze: {path}: no such file", file=sys.stderr)
            return 2
    xdotool_path = shutil.which("xdotool")
    if xdotool_path is None:
        print("bench_save_freeze: xdotool: not found on PATH", file=sys.stderr)
        return 2
    home = tempfile.mkdtemp(prefix="loudscape-save-freeze-")
    env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="")
    env.update({k: home for k in ("HOME", "XDG_DATA_HOME", "XDG_CONFIG_HOME")})
    env.update({k: home for k in ("XDG_STATE_HOME", "XDG_CACHE_HOME")})
    # No zenity: no dialog opens, the PNG lands in the (private) current folder.
    env["PATH"] = "/nonexistent-folder-without-zenity"
    lines: list[tuple[float, str]] = []
    command = [binary, cloud]
    if args.compare:
        command += ["--compare", os.path.abspath(args.compare)]
    for press in args.press:
        command += ["--press", press]
    window = subprocess.Popen(command, cwd=home, env=env, stderr=subprocess.PIPE, text=True)

    def read() -> None:
        assert window.stderr is not None
        for line in window.stderr:
            lines.append((time.monotonic(), line.rstrip()))

    threading.Thread(target=read, daemon=True).start()
    try:
        win = ""
        deadline = time.monotonic() + 90
        while not win and time.monotonic() < deadline and window.poll() is None:
            time.sleep(0.2)
            found = xdotool("search", "--all", "--pid", str(window.pid), "--name", "^loudscape$")
            win = found.split("\n")[0]
        if not win:
            print("bench_save_freeze: no loudscape window appeared", file=sys.stderr)
            return 1
        time.sleep(args.settle)
        xdotool("windowfocus", "--sync", win)
        xdotool("mousemove", "--window", win, "900", "400")
        time.sleep(1.0)
        key = time.monotonic()
        xdotool("key", "ctrl+s")
        saving = saved = None
        moves = 0
        while time.monotonic() - key < 60 and saved is None:
            xdotool("mousemove", "--window", win, str(880 + 20 * (moves % 2)), "420")
            moves += 1
            for at, line in list(lines):
                if saving is None and "saving " in line:
                    saving = at - key
                if line.startswith("picture: saved"):
                    saved = (at - key, line)
            time.sleep(0.05)
        if saving is None or saved is None:
            print("bench_save_freeze: no save within 60 s:", file=sys.stderr)
            print("\n".join(line for _, line in lines), file=sys.stderr)
            return 1
        print(f"saving line {saving:.2f} s after the key; {saved[1]} at {saved[0]:.2f} s")
        return 0
    finally:
        window.terminate()
        window.wait()
        shutil.rmtree(home, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
