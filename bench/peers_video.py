"""Videos against their peer: ffmpeg's constant-Q spectrum video (issue 37 item 4).

    .venv/bin/python bench/peers_video.py --loudscape target/release/loudscape [--runs 3]

Each round runs, one after another, the whole processes: ``loudscape video data/demo_song.ply
--start 0 --end 10 --size 1280x720 --fps 30`` for points and for the volume with the camera
still (the default) and turning (``--camera orbit``, where every frame is drawn afresh), and the
peer, ffmpeg drawing a constant-Q spectrum of the same 10 s of audio and encoding it as we do
(``showcqt`` at 1280x720 30 fps, x264 ``veryfast``, AAC). Medians of ``--runs`` rounds: wall and
CPU seconds, seconds of wall time per second of video (the aims: points 0.5, volume 2) and the
ratio to the peer's wall time in the same run. Not a test; the machine's load is printed.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_song import run_child  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
DEMO = os.path.join(REPO, "data", "demo_song.ply")
AUDIO = os.path.join(REPO, "data", "demo_song.flac")
SECONDS = 10.0
#: What each video draws, and its aim in seconds of wall time per second of video.
CASES = (
    ("points, still camera", ["--view", "points"], 0.5),
    ("volume, still camera", ["--view", "volume"], 2.0),
    ("points, orbit", ["--view", "points", "--camera", "orbit"], 0.5),
    ("volume, orbit", ["--view", "volume", "--camera", "orbit"], 2.0),
)


def load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loudscape", default=os.path.join(REPO, "target/release/loudscape"))
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    for path, what in ((args.loudscape, "the loudscape binary"), (AUDIO, "the demo's audio")):
        if not os.path.exists(path):
            print(f"peers_video: {path}: {what} is missing", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as scratch:
        out = os.path.join(scratch, "video.mp4")
        peer = ["ffmpeg", "-nostdin", "-v", "error", "-y", "-i", AUDIO, "-t", f"{SECONDS:g}"]
        peer += ["-filter_complex", "[0:a]showcqt=s=1280x720:r=30[v]", "-map", "[v]"]
        peer += ["-map", "0:a", "-c:v", "libx264", "-preset", "veryfast", "-c:a", "aac", out]
        ours = [args.loudscape, "video", DEMO, "--start", "0", "--end", f"{SECONDS:g}"]
        ours += ["--size", "1280x720", "--fps", "30", "--progress", "none", "-o", out]
        print(f"10 s of the demo at 1280x720, 30 fps; load average {load()}")
        walls: dict[str, list[float]] = {name: [] for name, _, _ in CASES}
        cpus: dict[str, list[float]] = {name: [] for name, _, _ in CASES}
        peer_walls: list[float] = []
        peer_cpus: list[float] = []
        for _ in range(args.runs):
            for name, extra, _ in CASES:
                if os.path.exists(out):
                    os.remove(out)
                wall, _, cpu, _ = run_child([*ours, *extra])
                walls[name].append(wall)
                cpus[name].append(cpu)
                wall, _, cpu, _ = run_child(peer)
                peer_walls.append(wall)
                peer_cpus.append(cpu)
        peer_wall = statistics.median(peer_walls)
        print(
            f"{'peer (showcqt + x264 + AAC)':28s} wall {peer_wall:6.2f} s  "
            f"CPU {statistics.median(peer_cpus):6.2f} s  {peer_wall / SECONDS:.2f} s/s"
        )
        for name, _, aim in CASES:
            wall = statistics.median(walls[name])
            per_second = wall / SECONDS
            verdict = "met" if per_second <= aim else "not met"
            print(
                f"{name:28s} wall {wall:6.2f} s  CPU {statistics.median(cpus[name]):6.2f} s  "
                f"{per_second:.2f} s/s (aim {aim:g}: {verdict})  {wall / peer_wall:.2f}x the peer"
            )
        print(f"load average after: {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
