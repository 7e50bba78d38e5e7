"""The window's frame loop under recorded input: orbit frame rates, hover latency and the
isovalue sweep rate of the real `loudscape` window (release build) under Xvfb at 1280x720.

Each case opens `loudscape FILE --view VIEW` in a private Xvfb screen (its own HOME, so no
remembered state), waits until the window has stopped painting (loaded, first views built),
warms up with one short orbit, then plays recorded input through XTest and watches what the
window paints through the X DAMAGE extension (bench/xdriver.py):

- orbit: a left-button drag across the 3D view at 60 motion events a second for a few seconds;
  frames per second = frames painted during the drag / its length (median of the runs);
- hover: the pointer jumps to a spot of the data; latency = from the motion event to the first
  painted frame whose pixels next to the cursor changed (the read-out drawn), median of the
  spots (the spots where no read-out appeared are counted apart);
- settle (Points view): a one-second drag that ends elsewhere; seconds from the release to the
  last painted frame (the points back to full density: the window stops painting when the
  progressive refinement is complete), median of the runs;
- return (Points view): then `R` (the default view, the one the window opened with, whose full
  picture was drawn before); seconds from the key to the last painted frame;
- isovalue sweep (Surface view): a drag of the isovalue slider back and forth; updates per
  second = painted frames whose 3D view differs from the one before / time from the press to
  the last such frame.

Usage: python bench/bench_window.py [--loudscape target/release/loudscape] [--vs OTHER_BINARY]
With --vs, the other binary runs each case right after ours (same load), and both columns print.

With --compare B: each song is opened with `--compare B` (A/B side by side, the song as A); the
settle case then also reports the longest frame from the release until the window goes quiet
(each half's points refined at rest: bounded frames, or one long frame per half).

With --open SONG (made from data/real-music when missing, --open-seconds long): the time from
starting `loudscape SONG` (fresh cache) to the first frame whose 3D view shows points, and to
the log line that the whole cloud was extracted, --runs times (PYTHONPATH reaches the
extractor: point it at the package to measure).
The ~5 M-point song is extracted once from data/real-music (see --big) with loudscape-extract.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from xdriver import XDriver  # noqa: E402

WIDTH, HEIGHT = 1280, 720
# The window's layout (src/ui/app.rs): a 270-point side panel on the left, the transport bar
# (about 45 points, 70 with the "no audio device" line) under the 3D view when a song is shown.
PANEL_W, TRANSPORT_H = 272, 72
VIEW = (PANEL_W, 0, WIDTH - PANEL_W, HEIGHT - TRANSPORT_H)  # x, y, w, h
CENTER = (VIEW[0] + VIEW[2] // 2, VIEW[1] + VIEW[3] // 2)
# Hover spots, offsets from the view's centre (inside the demo's and the big song's data box).
HOVER_SPOTS = [(-150, -60), (130, 50), (-60, 100), (170, -90), (10, 10), (-220, 30)]
# How long the window paints nothing before it counts as quiet (--quiet-seconds: longer than
# its longest frame, or a frame still being drawn is taken for quiet).
QUIET_S = 1.5
BUDGETS = {"orbit_demo": 20.0, "orbit_big": 10.0, "hover_ms": 100.0, "iso": 10.0}


@dataclass
class CaseResult:
    orbit_fps: list[float] = field(default_factory=list)
    hover_ms: list[float] = field(default_factory=list)
    hover_missed: int = 0
    # Hover tries discarded because the scene itself changed in the same frame.
    hover_scene: int = 0
    iso_rate: list[float] = field(default_factory=list)
    settle_s: list[float] = field(default_factory=list)
    return_s: list[float] = field(default_factory=list)
    # The longest gap between painted frames from the release of a settle drag to quiet.
    settle_frame_ms: list[float] = field(default_factory=list)
    note: str = ""


def start_xvfb() -> tuple[subprocess.Popen, str]:
    """A private Xvfb screen of WIDTH x HEIGHT; returns the process and its display name.

    With -noreset: by default Xvfb resets whenever its last client leaves, and a window that
    connects during the reset fails ("Failed to open connection to X server"); the first
    `xdotool search` of find_window, made as the window starts, is such a client.
    """
    if shutil.which("Xvfb") is None:
        raise RuntimeError("Xvfb is not installed (apt-get install xvfb)")
    read, write = os.pipe()
    proc = subprocess.Popen(
        [
            "Xvfb",
            "-displayfd",
            str(write),
            "-screen",
            "0",
            f"{WIDTH}x{HEIGHT}x24",
            "-nolisten",
            "tcp",
            "-noreset",
        ],
        pass_fds=(write,),
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    number = b""
    with os.fdopen(read, "rb") as pipe:
        while not number.endswith(b"\n"):
            chunk = pipe.read(1)
            if not chunk:
                raise RuntimeError("Xvfb did not start")
            number += chunk
    return proc, f":{number.decode().strip()}"


def find_window(display: str, proc: subprocess.Popen, timeout: float) -> int:
    env = dict(os.environ, DISPLAY=display)
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if proc.poll() is not None:
            raise RuntimeError(
                f"loudscape exited with status {proc.returncode} before its window showed"
            )
        found = subprocess.run(
            ["xdotool", "search", "--onlyvisible", "--name", "^loudscape$"],
            env=env,
            capture_output=True,
            text=True,
            check=False,
        ).stdout.split()
        if found:
            return int(found[-1])
        time.sleep(0.2)
    raise RuntimeError("no loudscape window appeared")


def orbit(x: XDriver, seconds: float) -> float:
    """One drag across the view; returns frames painted per second during it."""
    cx, cy = CENTER
    x.move(cx - 100, cy)
    x.pump_until(time.monotonic() + 0.2)
    start = x.button(True)
    tick, i = start, 0
    while tick - start < seconds:
        phase = (i % 120) / 120.0  # back and forth over 2 s
        dx = 200.0 * (1.0 - abs(2.0 * phase - 1.0))
        # Over whole periods the drag comes back to where it began, and so does the camera.
        x.move(int(cx - 100 + dx), int(cy + 30 * math.sin(2 * math.pi * phase)))
        i += 1
        tick = start + i / 60.0
        x.pump_until(tick)
    end = x.button(False)
    # The first frame may still be the one before the press.
    skip = min(0.25, seconds / 4)
    frames = [t for t in x.frames if start + skip < t <= end]
    return len(frames) / (end - start - skip)


def until_quiet(x: XDriver, since: float) -> float:
    """Seconds from `since` to the last frame painted before the window went quiet."""
    x.wait_quiet(QUIET_S, 300)
    frames = [t for t in x.frames if t > since]
    return frames[-1] - since if frames else 0.0


def longest_frame_ms(x: XDriver, since: float) -> float:
    """The longest time between `since` and the frames painted after it, in ms."""
    times = [since] + [t for t in x.frames if t > since]
    return 1000.0 * max((b - a for a, b in itertools.pairwise(times)), default=0.0)


def settle(x: XDriver, direction: int, result: CaseResult | None = None) -> float:
    """A one-second drag that ends elsewhere; seconds from the release to full density (and
    into `result`, the longest frame meanwhile)."""
    cx, cy = CENTER
    x.move(cx - 60 * direction, cy)
    x.pump_until(time.monotonic() + 0.2)
    start = x.button(True)
    for i in range(60):
        x.move(int(cx - 60 * direction + 2 * direction * i), cy)
        x.pump_until(start + (i + 1) / 60.0)
    released = x.button(False)
    seconds = until_quiet(x, released)
    if result is not None:
        result.settle_frame_ms.append(longest_frame_ms(x, released))
    return seconds


def key_return(x: XDriver, display: str, wid: int) -> float:
    """`R` (the default view, drawn in full before); seconds from the key to the last frame."""
    x.move(*CENTER)
    x.pump(0.1)
    env = dict(os.environ, DISPLAY=display)
    subprocess.run(["xdotool", "windowfocus", "--sync", str(wid)], env=env, check=False)
    x.pump(0.2)
    sent = time.monotonic()
    subprocess.run(["xdotool", "key", "r"], env=env, check=False)
    return until_quiet(x, sent)


def region_around(px: int, py: int) -> tuple[int, int, int, int]:
    """Where the read-out next to the cursor at (px, py) is drawn, clipped to the view."""
    x0, y0 = max(VIEW[0], px - 30), max(VIEW[1], py - 40)
    x1, y1 = min(VIEW[0] + VIEW[2], px + 330), min(VIEW[1] + VIEW[3], py + 160)
    return x0, y0, x1 - x0, y1 - y0


def changed_bits(a: bytes | None, b: bytes | None) -> int:
    if a is None or b is None or len(a) != len(b):
        return 0
    return (int.from_bytes(a, "little") ^ int.from_bytes(b, "little")).bit_count()


# A read-out (five lines of text on a dark box) changes far more bits than this.
READOUT_BITS = 4000


def outside(image: bytes | None, rects: list[tuple[int, int, int, int]]) -> bytes | None:
    """A grab of the 3D view with the given rectangles (screen coordinates) blanked."""
    if image is None:
        return None
    vx, vy, vw, vh = VIEW
    out = bytearray(image)
    stride = len(image) // vh
    for rx, ry, rw, rh in rects:
        for row in range(ry - vy, ry - vy + rh):
            start = row * stride + (rx - vx) * 4
            out[start : start + rw * 4] = bytes(rw * 4)
    return bytes(out)


def hover(x: XDriver, spot: tuple[int, int], last: tuple[int, int], timeout: float):
    """Moves from `last` to `spot`; ms until a painted frame changed the pixels next to it (the
    read-out drawn), or None when none did, or "scene" when that frame also changed the view
    elsewhere (the scene was still changing: not a hover measurement)."""
    rect = region_around(*spot)
    blank = [rect, region_around(*last)]
    before = x.grab(*rect)
    view_before = outside(x.grab(*VIEW), blank)
    sent = x.move(*spot)
    end = sent + timeout
    while time.monotonic() < end:
        got = x.pump(0.05)
        if changed_bits(x.grab(*rect), before) >= READOUT_BITS:
            seen = x.frames[-1] if got else time.monotonic()
            if outside(x.grab(*VIEW), blank) != view_before:
                return "scene"
            return (max(seen, sent) - sent) * 1e3
    return None


def shows_data(x: XDriver) -> bool:
    """Whether the middle of the 3D view holds a picture (many colours), not a line of text."""
    data = x.grab(CENTER[0] - 200, CENTER[1] - 150, 400, 300)
    return data is not None and len(set(memoryview(data).cast("I"))) > 200


def wait_loaded(x: XDriver, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if not x.frames:
            x.pump(0.5)
            continue
        if x.wait_quiet(6.0, end - time.monotonic()) and shows_data(x):
            return True
        x.pump(0.5)
    return False


def size_window(wid: int, env: dict) -> None:
    """Moves the window to (0, 0) at WIDTH x HEIGHT, until it stays so (winit applies its own
    size once mapped)."""
    steady = 0
    end = time.monotonic() + 30
    while steady < 3 and time.monotonic() < end:
        geometry = subprocess.run(
            ["xdotool", "getwindowgeometry", "--shell", str(wid)],
            env=env,
            capture_output=True,
            text=True,
            check=False,
        ).stdout
        values = dict(line.split("=", 1) for line in geometry.split() if "=" in line)
        if (
            values.get("WIDTH") == str(WIDTH)
            and values.get("HEIGHT") == str(HEIGHT)
            and values.get("X") == "0"
        ):
            steady += 1
        else:
            steady = 0
            subprocess.run(
                [
                    "xdotool",
                    "windowmove",
                    str(wid),
                    "0",
                    "0",
                    "windowsize",
                    str(wid),
                    str(WIDTH),
                    str(HEIGHT),
                ],
                env=env,
                check=False,
            )
        time.sleep(0.3)
    if steady < 3:
        raise RuntimeError(f"the window would not take {WIDTH}x{HEIGHT}")


def view_signature(x: XDriver) -> bytes:
    """Three rows and one column of the 3D view: enough to tell two surfaces apart."""
    vx, vy, vw, vh = VIEW
    rows = [x.grab(vx, vy + vh * k // 4, vw, 1) or b"" for k in (1, 2, 3)]
    return b"".join(rows) + (x.grab(vx + vw // 2, vy, 1, vh) or b"")


def iso_sweep(x: XDriver, slider: tuple[int, int, int], seconds: float) -> float:
    """Drags the isovalue slider (x0, x1, y on screen) back and forth; surface updates/s."""
    x0, x1, y = slider
    last = view_signature(x)
    changes: list[float] = []

    def watch(deadline: float) -> None:
        nonlocal last
        while (left := deadline - time.monotonic()) > 0:
            if x.pump(left):
                sig = view_signature(x)
                if sig != last:
                    changes.append(x.frames[-1])
                    last = sig

    x.move(x0, y)
    watch(time.monotonic() + 0.2)
    start = x.button(True)
    tick, i = start, 0
    while tick - start < seconds:
        phase = (i % 60) / 60.0  # there and back in 2 s at 30 events a second
        x.move(int(x0 + (x1 - x0) * (1.0 - abs(2.0 * phase - 1.0))), y)
        i += 1
        tick = start + i / 30.0
        watch(tick)
    x.button(False)
    # Updates still in the pipe count too; the rate is over the whole time they took.
    end = time.monotonic() + 30.0
    quiet_since = time.monotonic()
    while time.monotonic() < end and time.monotonic() - quiet_since < 5.0:
        n = len(changes)
        watch(time.monotonic() + 0.25)
        if len(changes) != n:
            quiet_since = time.monotonic()
    if not changes:
        raise RuntimeError("the isovalue sweep changed nothing: is --iso-slider on the slider?")
    return len(changes) / (changes[-1] - start)


def shoot(args, display: str, name: str) -> None:
    """A PNG of the whole screen into --shots (to look at what was measured)."""
    if args.shots:
        args.shots.mkdir(parents=True, exist_ok=True)
        env = dict(os.environ, DISPLAY=display)
        subprocess.run(
            ["import", "-window", "root", str(args.shots / f"{name}.png")], env=env, check=False
        )


def private_env(home: str, display: str, **extra: str) -> dict:
    """The environment of a window run in its own home (no remembered state) on `display`."""
    runtime = Path(home) / "runtime"
    runtime.mkdir(mode=0o700)
    env = dict(
        os.environ,
        DISPLAY=display,
        HOME=home,
        XDG_DATA_HOME=f"{home}/data",
        XDG_CONFIG_HOME=f"{home}/config",
        XDG_CACHE_HOME=f"{home}/cache",
        XDG_RUNTIME_DIR=str(runtime),
        **extra,
    )
    env.pop("WAYLAND_DISPLAY", None)
    return env


def run_case(binary: Path, ply: Path, view: str, args, display: str, tag: str) -> CaseResult:
    result = CaseResult()
    with tempfile.TemporaryDirectory(prefix="bench-window-") as home:
        env = private_env(home, display)
        log = open(Path(home) / "log.txt", "w")
        command = [str(binary), str(ply), "--view", view]
        if args.compare:
            command += ["--compare", str(args.compare)]
        proc = subprocess.Popen(command, env=env, stdout=log, stderr=log)
        try:
            wid = find_window(display, proc, 60)
            size_window(wid, env)
            x = XDriver(display)
            x.watch(wid)
            x.move(5, HEIGHT - 5)
            # Loaded and the first views built: the 3D view shows data (not the "Loading…"
            # line) and the window stops painting.
            if not wait_loaded(x, args.load_timeout):
                result.note = "never showed the data and went idle"
            shoot(args, display, f"{tag}-loaded")
            # Warm-up: pipelines, the moving resolution's steps, views still being built.
            for _ in range(2):
                orbit(x, 2.0)
                x.wait_quiet(max(4.0, QUIET_S), 120)
            for _ in range(args.runs):
                result.orbit_fps.append(orbit(x, args.orbit_seconds))
                x.wait_quiet(QUIET_S, 120)
            if view == "points" and args.settle:
                for i in range(args.runs):
                    x.wait_quiet(QUIET_S, 120)
                    result.settle_s.append(settle(x, 1 if i % 2 == 0 else -1, result))
                    result.return_s.append(key_return(x, display, wid))
            last = CENTER
            for dx, dy in HOVER_SPOTS[: args.hovers]:
                spot = (CENTER[0] + dx, CENTER[1] + dy)
                for _ in range(3):
                    x.wait_quiet(min(1.0, QUIET_S), 120)
                    ms = hover(x, spot, last, args.hover_timeout)
                    last = spot
                    if ms != "scene":
                        break
                    result.hover_scene += 1
                    x.move(*CENTER)
                    last = CENTER
                if ms == "scene":
                    ms = None
                if not result.hover_ms and ms is not None:
                    shoot(args, display, f"{tag}-hover")
                if ms is None:
                    result.hover_missed += 1
                else:
                    result.hover_ms.append(ms)
            if view == "surface" and args.iso and ply == args.demo:
                for _ in range(args.runs):
                    x.move(*CENTER)
                    x.wait_quiet(QUIET_S, 120)
                    try:
                        result.iso_rate.append(iso_sweep(x, args.iso_slider, args.iso_seconds))
                    except RuntimeError as e:
                        result.note = str(e)
                        break
                    shoot(args, display, f"{tag}-iso")
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.close()
    return result


def make_big_song(out: Path, venv_bin: Path, seconds: float) -> None:
    """A ~5 M-point song: the real tracks of data/real-music, resampled to 44.1 kHz stereo and
    laid end to end until `seconds`, extracted with loudscape-extract (hop 256)."""
    wav = out.with_suffix(".wav")
    real_music_song(wav, seconds)
    # The game tracks keep few high bins above the floor: a hop of 256 (four frames for each
    # default one) brings 170 s to about 5 M points, a 3-minute pop song's size at defaults.
    command = [str(venv_bin / "loudscape-extract"), "song", str(wav), "-o", str(out)]
    subprocess.run(command + ["--hop", "256", "--quiet"], check=True)


def real_music_song(out: Path, seconds: float) -> None:
    """The real tracks of data/real-music, resampled to 44.1 kHz stereo and laid end to end
    until `seconds`, written to `out` (WAV or FLAC, by its suffix)."""
    import numpy as np
    import soundfile as sf
    from scipy.signal import resample_poly

    tracks = sorted(
        p for p in Path("data/real-music").glob("*/*") if p.suffix in (".ogg", ".wav", ".flac")
    )
    if not tracks:
        raise RuntimeError("data/real-music has no tracks: run `make real-music` first")
    parts, total = [], 0.0
    for path in tracks:
        audio, rate = sf.read(path, dtype="float32", always_2d=True)
        if audio.shape[1] == 1:
            audio = np.repeat(audio, 2, axis=1)
        audio = audio[:, :2]
        if rate != 44100:
            g = math.gcd(44100, rate)
            audio = resample_poly(audio, 44100 // g, rate // g, axis=0).astype(np.float32)
        parts.append(audio)
        total += len(audio) / 44100
        if total >= seconds:
            break
    song = np.concatenate(parts)[: int(seconds * 44100)]
    out.parent.mkdir(parents=True, exist_ok=True)
    sf.write(out, song, 44100, subtype="PCM_16")


def coloured(image: bytes | None) -> int:
    """Pixels of a grab (BGRX) strongly red or blue: the points (coloured by hp), where the
    panels, the axes, the labels and the "Loading…" line are grey."""
    if image is None:
        return 0
    pixels = memoryview(image)
    return sum(1 for i in range(0, len(pixels), 16) if abs(pixels[i] - pixels[i + 2]) > 60)


def open_case(binary: Path, audio: Path, args, display: str) -> tuple[float, float, str]:
    """Opens `audio` (never extracted before: a fresh cache) in the window; returns the
    seconds from the start of the process to the first frame that shows points, and to the
    log line that the whole cloud was extracted, with the window's own lines about the first
    points and the whole cloud that replaced them (none before points while extracting)."""
    with tempfile.TemporaryDirectory(prefix="bench-open-") as home:
        env = private_env(
            home,
            display,
            LOUDSCAPE_CACHE_DIR=f"{home}/clouds",
            LOUDSCAPE_EXTRACT=str(args.extractor.resolve()),
        )
        log_path = Path(home) / "log.txt"
        log = open(log_path, "w")
        start = time.monotonic()
        proc = subprocess.Popen([str(binary), str(audio)], env=env, stdout=log, stderr=log)
        first = full = None
        said_fps: list[float] = []
        try:
            wid = find_window(display, proc, 60)
            size_window(wid, env)
            x = XDriver(display)
            end = start + args.load_timeout
            vx, vy, vw, vh = VIEW
            if args.open_orbit:
                x.watch(wid)
            while time.monotonic() < end and full is None:
                if first is None and coloured(x.grab(vx, vy, vw, vh * 6 // 10)) > 300:
                    first = time.monotonic() - start
                if "cloud extracted in" in log_path.read_text():
                    full = time.monotonic() - start
                elif first is not None and args.open_orbit:
                    # Orbiting while the points come in: frames painted a second.
                    fps = orbit(x, 2.0)
                    said_fps.append(fps)
                time.sleep(0.02)
            if first is None and full is not None:
                # Drawn in the frame after the cloud came.
                while time.monotonic() < full + start + 10 and first is None:
                    if coloured(x.grab(vx, vy, vw, vh * 6 // 10)) > 300:
                        first = time.monotonic() - start
                    time.sleep(0.02)
            # The window's line about the whole cloud comes with the frame that shows it.
            time.sleep(1.0)
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.close()
        said = " / ".join(
            line.split(": ", 2)[-1]
            for line in log_path.read_text().splitlines()
            if "first points shown" in line or "the whole cloud (" in line
        )
    if said_fps:
        said += f" / orbit while the points come in: {', '.join(f'{v:.1f}' for v in said_fps)} fps"
    return (first or math.nan, full or math.nan, said)


def open_song(args) -> int:
    """The --open case: time to the first points and to the whole cloud, --runs times for each
    binary, one after the other."""
    audio = args.open
    if not audio.is_file():
        print(f"making {audio}: {args.open_seconds:.0f} s of data/real-music ...", flush=True)
        real_music_song(audio, args.open_seconds)
    binaries = [("ours", args.loudscape)] + ([("vs", args.vs)] if args.vs else [])
    if args.compare and not args.compare.is_file():
        print(f"{args.compare}: no such file (--compare)", file=sys.stderr)
        return 1
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs", flush=True)
    xvfb, display = start_xvfb()
    times: dict[str, list[tuple[float, float]]] = {name: [] for name, _ in binaries}
    try:
        for _ in range(args.runs):
            for name, binary in binaries:
                first, full, said = open_case(binary, audio, args, display)
                times[name].append((first, full))
                print(f"{name}: first points {first:.2f} s, whole cloud {full:.2f} s {said}")
    finally:
        xvfb.terminate()
        xvfb.wait()
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print("\n| open a song | " + " | ".join(f"{n}: {b}" for n, b in binaries) + " |")
    print("|---|" + "---|" * len(binaries))
    for i, what in enumerate(["first points", "whole cloud"]):
        row = [fmt([t[i] for t in times[n]], 2) + " s" for n, _ in binaries]
        print(f"| {what} | " + " | ".join(row) + " |")
    return 0


def case_line(r: CaseResult) -> str:
    line = f"orbit fps {fmt(r.orbit_fps)}; hover ms {fmt(r.hover_ms, 0)}"
    if r.hover_missed:
        line += f" ({r.hover_missed} spots without a read-out)"
    if r.hover_scene:
        line += f" ({r.hover_scene} tries discarded: the scene changed too)"
    if r.iso_rate:
        line += f"; iso updates/s {fmt(r.iso_rate)}"
    if r.settle_s:
        line += f"; settle s {fmt(r.settle_s, 2)}; return s {fmt(r.return_s, 2)}"
        line += f"; longest settle frame ms {fmt(r.settle_frame_ms, 0)}"
    return line + (f"; {r.note}" if r.note else "")


def fmt(values: list[float], digits: int = 1) -> str:
    if not values:
        return "-"
    return (
        f"{statistics.median(values):.{digits}f} ({', '.join(f'{v:.{digits}f}' for v in values)})"
    )


def main() -> int:
    global QUIET_S
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loudscape", type=Path, default=Path("target/release/loudscape"))
    parser.add_argument(
        "--vs", type=Path, help="another loudscape binary, run case by case beside ours"
    )
    parser.add_argument("--demo", type=Path, default=Path("data/demo_song.ply"))
    parser.add_argument("--big", type=Path, default=Path("out/bench-window/real_5m.ply"))
    parser.add_argument("--big-seconds", type=float, default=170.0, help="length of the big song")
    parser.add_argument("--no-big", action="store_true", help="the demo only")
    parser.add_argument("--skip-demo", action="store_true", help="the big song only")
    parser.add_argument("--views", default="points,surface,volume")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--hovers", type=int, default=5)
    parser.add_argument("--orbit-seconds", type=float, default=4.0, help="whole 2 s periods")
    parser.add_argument("--iso-seconds", type=float, default=4.0)
    parser.add_argument("--hover-timeout", type=float, default=20.0)
    parser.add_argument("--load-timeout", type=float, default=300.0)
    parser.add_argument(
        "--iso-slider",
        type=lambda s: tuple(int(v) for v in s.split(",")),
        default=(20, 95, 408),
        help="X0,X1,Y: the isovalue slider's rail in the Surface view (window pixels)",
    )
    parser.add_argument("--no-iso", dest="iso", action="store_false")
    parser.add_argument(
        "--no-settle", dest="settle", action="store_false", help="skip settle and return"
    )
    parser.add_argument("--shots", type=Path, help="save screenshots of each case to this folder")
    parser.add_argument(
        "--compare", type=Path, help="open each song with --compare THIS (A/B side by side)"
    )
    parser.add_argument(
        "--quiet-seconds",
        type=float,
        default=QUIET_S,
        help="no frame painted this long: the window is quiet (longer than its longest frame)",
    )
    parser.add_argument(
        "--open",
        type=Path,
        help="instead: time to the first points and to the whole cloud of this song, opened "
        "in the window (made from data/real-music when missing)",
    )
    parser.add_argument("--open-seconds", type=float, default=180.0, help="length of that song")
    parser.add_argument(
        "--open-orbit",
        action="store_true",
        help="with --open: orbit the camera from the first points on, 2 s drags, and print the "
        "frames painted a second (the whole cloud's time is then late by up to 2 s)",
    )
    parser.add_argument(
        "--extractor", type=Path, default=Path(".venv/bin/loudscape-extract"), help="for --open"
    )
    args = parser.parse_args()
    QUIET_S = args.quiet_seconds
    for binary in [args.loudscape] + ([args.vs] if args.vs else []):
        if not binary.is_file():
            print(f"{binary}: no such binary (cargo build --release)", file=sys.stderr)
            return 1
    if args.open:
        return open_song(args)
    files = [] if args.skip_demo else [("demo", args.demo)]
    if not args.no_big:
        if not args.big.is_file():
            print(f"extracting the big song into {args.big} ...", flush=True)
            make_big_song(args.big, Path(sys.executable).parent, args.big_seconds)
        files.append(("big", args.big))
    binaries = [("ours", args.loudscape)] + ([("vs", args.vs)] if args.vs else [])
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs", flush=True)
    xvfb, display = start_xvfb()
    results: dict[tuple[str, str, str], CaseResult] = {}
    try:
        for label, ply in files:
            for view in args.views.split(","):
                for name, binary in binaries:
                    started = time.monotonic()
                    try:
                        r = run_case(binary, ply, view, args, display, f"{name}-{label}-{view}")
                    except RuntimeError as e:
                        r = CaseResult(note=str(e))
                    results[(name, label, view)] = r
                    line = case_line(r)
                    took = time.monotonic() - started
                    print(f"{name} {label} {view}: {line} [{took:.0f} s]", flush=True)
    finally:
        xvfb.terminate()
        xvfb.wait()
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print_table(results, binaries, files, args)
    return 0


def print_table(results, binaries, files, args) -> None:
    names = [n for n, _ in binaries]
    print("\n| measurement | budget | " + " | ".join(f"{n}: {b}" for n, b in binaries) + " |")
    print("|---|---|" + "---|" * len(names))

    def med(values):
        return statistics.median(values) if values else None

    def cell(value, unit, ok):
        if value is None:
            return "-"
        return f"{value:.1f} {unit}{'' if ok(value) else ' (misses it)'}"

    for label, _ in files:
        floor = BUDGETS["orbit_demo"] if label == "demo" else BUDGETS["orbit_big"]
        for view in args.views.split(","):
            row = [
                cell(
                    med(results.get((n, label, view), CaseResult()).orbit_fps),
                    "fps",
                    lambda v, floor=floor: v >= floor,
                )
                for n in names
            ]
            print(f"| orbit, {view}, {label} | >= {floor:.0f} fps | " + " | ".join(row) + " |")
        for view in args.views.split(","):
            row = []
            for n in names:
                r = results.get((n, label, view), CaseResult())
                c = cell(med(r.hover_ms), "ms", lambda v: v <= BUDGETS["hover_ms"])
                row.append(c + (f", {r.hover_missed} missed" if r.hover_missed else ""))
            print(f"| hover read-out, {view}, {label} | <= 100 ms | " + " | ".join(row) + " |")
    row = [
        cell(
            med(results.get((n, "demo", "surface"), CaseResult()).iso_rate), "/s", lambda v: v >= 10
        )
        for n in names
    ]
    print("| isovalue sweep, demo | >= 10 updates/s | " + " | ".join(row) + " |")
    for label, _ in files:
        for what, attr, unit, aim in (
            ("settle after an orbit", "settle_s", "s", "a few s"),
            ("return to the view", "return_s", "s", "a few s"),
            ("longest frame of the settle", "settle_frame_ms", "ms", "-"),
        ):
            row = [
                cell(
                    med(getattr(results.get((n, label, "points"), CaseResult()), attr)),
                    unit,
                    lambda v: True,
                )
                for n in names
            ]
            if any(c != "-" for c in row):
                print(f"| {what}, points, {label} | {aim} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    sys.exit(main())
