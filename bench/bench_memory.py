"""Peak memory of Song extraction on long synthesized tracks (5, 20 and 60 minutes).

    .venv/bin/python bench/bench_memory.py [--minutes 5 20 60] [--code DIR]

For each length it writes a 44.1 kHz stereo 16-bit WAV (the demo song's generator, its
3 minutes repeated, written block by block), runs ``python -m loudscape_extract.cli song
x.wav -o x.ply --quiet`` as a child process and prints its wall time, CPU time and peak RSS
(``ru_maxrss``). ``--code DIR`` runs the extractor found in DIR (a ``preprocess`` folder of
another checkout, e.g. ``git archive`` of an older commit) instead of this one, for
before/after figures. Not a test: the 60-minute run takes minutes and writes a 2.5 GB file.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile

import soundfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_song import SAMPLE_RATE, run_child, synthesize_song  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def write_track(path: str, minutes: float) -> None:
    """``minutes`` of the 3-minute synthesized song, repeated, as 16-bit stereo WAV."""
    song = synthesize_song()
    total = int(round(minutes * 60 * SAMPLE_RATE))
    with soundfile.SoundFile(
        path, "w", samplerate=SAMPLE_RATE, channels=song.shape[1], subtype="PCM_16"
    ) as handle:
        written = 0
        while written < total:
            part = song[: total - written]
            handle.write(part)
            written += part.shape[0]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, nargs="+", default=[5.0, 20.0, 60.0])
    parser.add_argument("--code", help="preprocess folder of the extractor to run")
    parser.add_argument("--scratch", help="folder for the WAV and PLY (default: a temp dir)")
    args = parser.parse_args()
    code = os.path.abspath(args.code or os.path.join(REPO, "preprocess"))
    env_path = code + os.pathsep + os.environ.get("PYTHONPATH", "")
    os.environ["PYTHONPATH"] = env_path
    print(
        f"extractor: {os.path.relpath(code, REPO)}; {os.cpu_count()} CPUs; "
        f"python {platform.python_version()}"
    )
    with tempfile.TemporaryDirectory(dir=args.scratch) as scratch:
        for minutes in args.minutes:
            wav = os.path.join(scratch, "long.wav")
            ply = os.path.join(scratch, "long.ply")
            write_track(wav, minutes)
            command = [sys.executable, "-m", "loudscape_extract.cli", "song", wav, "-o", ply]
            wall, rss, cpu, _ = run_child([*command, "--quiet"])
            size = os.path.getsize(ply) / 1e6
            print(
                f"{minutes:g} min: wall {wall:.1f} s, CPU {cpu:.1f} s, peak RSS {rss:.0f} MiB, "
                f"output {size:.0f} MB",
                flush=True,
            )
            os.unlink(ply)
            os.unlink(wav)
    return 0


if __name__ == "__main__":
    sys.exit(main())
