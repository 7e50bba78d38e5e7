"""Benchmark Song extraction on a synthesized 3-minute 44.1 kHz stereo song.

    .venv/bin/python bench/bench_song.py [--runs 3] [--librosa-runs 3] [--vs-code OLD/preprocess]

Prints, as medians of the runs:
- ours: ``loudscape-extract song x.wav -o x.ply --quiet`` end to end as a child process
  (interpreter start, imports, decode, STFT, HPSS, loudness metrics, points, write);
- librosa: ``librosa.stft`` + ``np.abs`` + ``librosa.decompose.hpss(S, mask=True)`` on the same
  mono mix in a child process, timed inside it (imports and decoding not counted);
- with ``--vs-code DIR``: the same command with the extractor imported from ``DIR`` (an older
  tree's ``preprocess``, e.g. from ``git archive``), its runs interleaved with ours;
- peak memory (``ru_maxrss``) of each kind of child process.
Not a test: timings on a shared machine are noisy, hence the medians.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import soundfile

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SAMPLE_RATE = 44100
DURATION_S = 180.0

LIBROSA_CHILD = """
import sys, time, numpy as np, soundfile, librosa
samples, rate = soundfile.read(sys.argv[1], dtype="float32", always_2d=True)
mono = samples.mean(axis=1)
start = time.perf_counter()
S = np.abs(librosa.stft(mono, n_fft=2048, hop_length=1024))
librosa.decompose.hpss(S, kernel_size=31, power=2.0, margin=1.0, mask=True)
print(time.perf_counter() - start)
"""


def synthesize_song() -> np.ndarray:
    path = os.path.join(REPO, "preprocess", "scripts", "make_demo_song.py")
    spec = importlib.util.spec_from_file_location("make_demo_song", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.synthesize(sample_rate=SAMPLE_RATE, duration_s=DURATION_S)


def run_child(command: list[str], env: dict | None = None) -> tuple[float, float, float, str]:
    """Run a child through a small wrapper; return (wall s, its peak RSS in MiB, its CPU s
    (user + system), its stdout).

    The wrapper has only that one child, so ``RUSAGE_CHILDREN``'s ``ru_maxrss`` is its peak.
    """
    wrapper = (
        "import json, resource, subprocess, sys, time\n"
        "t = time.perf_counter()\n"
        "r = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
        "wall = time.perf_counter() - t\n"
        "if r.returncode: sys.exit(r.stderr)\n"
        "u = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "print(json.dumps([wall, u.ru_maxrss, u.ru_utime + u.ru_stime, r.stdout.strip()]))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", wrapper, *command],
        capture_output=True,
        text=True,
        check=True,
        env=env,
    )
    wall, rss, cpu, stdout = json.loads(result.stdout)
    rss_bytes = rss if platform.system() == "Darwin" else rss * 1024  # macOS: bytes, Linux: KiB
    return wall, rss_bytes / 2**20, cpu, stdout


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--librosa-runs", type=int, default=3)
    parser.add_argument("--vs-code", help="an older tree's preprocess folder to time as well")
    args = parser.parse_args()
    old_env = None
    if args.vs_code:
        old_env = dict(os.environ, PYTHONPATH=os.path.abspath(args.vs_code))
    executable = os.path.join(os.path.dirname(sys.executable), "loudscape-extract")
    with tempfile.TemporaryDirectory() as scratch:
        wav = os.path.join(scratch, "song.wav")
        ply = os.path.join(scratch, "song.ply")
        soundfile.write(wav, synthesize_song(), SAMPLE_RATE, subtype="PCM_16")
        print(
            f"input: synthesized song, {DURATION_S:.0f} s, {SAMPLE_RATE} Hz, stereo, 16-bit WAV; "
            f"{os.cpu_count()} CPUs; python {platform.python_version()}"
        )
        ours_times, ours_rss, ours_cpu = [], [], []
        old_times, old_cpu = [], []
        for _ in range(args.runs):
            wall, rss, cpu, _ = run_child([executable, "song", wav, "-o", ply, "--quiet"])
            ours_times.append(wall)
            ours_rss.append(rss)
            ours_cpu.append(cpu)
            if old_env is not None:
                old_ply = os.path.join(scratch, "old.ply")
                command = [sys.executable, "-m", "loudscape_extract.cli", "song", wav]
                wall, _, cpu, _ = run_child([*command, "-o", old_ply, "--quiet"], env=old_env)
                old_times.append(wall)
                old_cpu.append(cpu)
        size_mb = os.path.getsize(ply) / 1e6
        librosa_times, librosa_rss = [], []
        for _ in range(args.librosa_runs):
            _, rss, _, stdout = run_child([sys.executable, "-c", LIBROSA_CHILD, wav])
            librosa_times.append(float(stdout))
            librosa_rss.append(rss)
    print(f"ours (end to end, CLI):     runs {', '.join(f'{t:.2f}' for t in ours_times)} s")
    print(
        f"  median {statistics.median(ours_times):.2f} s, peak RSS {max(ours_rss):.0f} MiB, "
        f"CPU (user+sys) median {statistics.median(ours_cpu):.2f} s"
    )
    print(f"  output {size_mb:.1f} MB")
    if old_times:
        print(f"older code ({args.vs_code}): runs {', '.join(f'{t:.2f}' for t in old_times)} s")
        print(
            f"  median {statistics.median(old_times):.2f} s, "
            f"CPU (user+sys) median {statistics.median(old_cpu):.2f} s"
        )
    print(f"librosa (stft + hpss only): runs {', '.join(f'{t:.2f}' for t in librosa_times)} s")
    print(f"  median {statistics.median(librosa_times):.2f} s, peak RSS {max(librosa_rss):.0f} MiB")
    print(f"speed-up: {statistics.median(librosa_times) / statistics.median(ours_times):.1f}x")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"at {time.strftime('%Y-%m-%d %H:%M')}, 1-minute load average {load:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
