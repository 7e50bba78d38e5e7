"""Extraction against its peers: librosa's STFT + HPSS and ffmpeg's loudness meter (issue 37).

    .venv/bin/python bench/peers_extract.py [--runs 3] [--vs-code OLD/preprocess]

The inputs are real recordings: the tracks of data/real-music (``make real-music``).

1. **Song**: a 3:30 track, the 44.1 kHz tracks of data/real-music (hex-a-hop ``music-ending``,
   rrootage ``stg_a``, torus-trooper ``tt1`` and ``tt3``) as stereo, laid end to end and cut
   at 210 s, Ogg Vorbis q5 (made once with ffmpeg under ``out/peers/``). Each round runs, one
   after another:
   - ours: ``loudscape-extract song track.ogg -o x.ply --quiet``, the whole process
     (interpreter, imports, decoding, STFT, HPSS, loudness and true peak, points, write);
   - librosa: ``librosa.stft`` (n_fft 2048, hop 1024: ours) + ``np.abs`` +
     ``librosa.decompose.hpss(S, kernel_size=31, mask=True)`` on the decoded mono mix, timed
     inside its process (imports and decoding not counted);
   - ffmpeg: ``ffmpeg -i track.ogg -af ebur128=peak=true -f null -``, the whole process;
   - with ``--vs-code DIR``: ours with the extractor imported from ``DIR`` (an older tree's
     ``preprocess``, e.g. from ``git archive``).
2. **Timeline**: the eight tracks (the seven of data/real-music and the 3:30 track), an empty
   cache each run, ``--jobs 2``; seconds of audio per CPU-second of the whole process tree
   (the workers included), against ffmpeg's ebur128 meter run on the same eight files two at a
   time.

Medians of ``--runs`` rounds, then the ratios. Wall times on a shared machine move with its
load (printed); CPU seconds move less. Not a test.

Both extractor trees (ours and ``--vs-code``'s) are byte-compiled first, as ``pip install``
leaves an installed package: with ``PYTHONDONTWRITEBYTECODE`` set (as in some development
shells) every run would otherwise compile the package's sources again (about 0.1 s).
"""

from __future__ import annotations

import argparse
import compileall
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_song import run_child  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
MUSIC = os.path.join(REPO, "data", "real-music")
OUT = os.path.join(REPO, "out", "peers")
SONG_PARTS = (
    "hex-a-hop-data/music-ending.ogg",
    "rrootage-data/stg_a.ogg",
    "torus-trooper-data/tt1.ogg",
    "torus-trooper-data/tt3.ogg",
)
SONG_SECONDS = 210.0
N_FFT, HOP = 2048, 1024

LIBROSA_CHILD = """
import sys, time, numpy as np, soundfile, librosa
samples, rate = soundfile.read(sys.argv[1], dtype="float32", always_2d=True)
mono = samples.mean(axis=1)
wall, cpu = time.perf_counter(), time.process_time()
S = np.abs(librosa.stft(mono, n_fft=int(sys.argv[2]), hop_length=int(sys.argv[3])))
librosa.decompose.hpss(S, kernel_size=31, power=2.0, margin=1.0, mask=True)
print(time.perf_counter() - wall, time.process_time() - cpu)
"""

# The eight ffmpeg meters, two at a time, in one process whose children's CPU time counts.
FFMPEG_PAIRS_CHILD = """
import subprocess, sys
from concurrent.futures import ThreadPoolExecutor
def meter(path):
    subprocess.run(["ffmpeg", "-nostdin", "-hide_banner", "-nostats", "-i", path, "-af",
                    "ebur128=peak=true", "-f", "null", "-"], check=True, capture_output=True)
with ThreadPoolExecutor(2) as pool:
    list(pool.map(meter, sys.argv[1:]))
"""


def fail(message: str) -> int:
    print(f"peers_extract: {message}", file=sys.stderr)
    return 1


def duration_s(path: str) -> float:
    result = subprocess.run(
        ["ffprobe", "-v", "error", "-show_entries", "format=duration", "-of", "csv=p=0", path],
        capture_output=True,
        text=True,
        check=True,
    )
    return float(result.stdout.strip())


def make_song(path: str) -> None:
    """The 3:30 track (see the module docs), written through a temporary name."""
    inputs, chains = [], []
    for index, part in enumerate(SONG_PARTS):
        inputs += ["-i", os.path.join(MUSIC, part)]
        chains.append(f"[{index}:a]aformat=sample_rates=44100:channel_layouts=stereo[a{index}]")
    labels = "".join(f"[a{index}]" for index in range(len(SONG_PARTS)))
    graph = ";".join(chains) + f";{labels}concat=n={len(SONG_PARTS)}:v=0:a=1"
    graph += f",atrim=0:{SONG_SECONDS:g}"
    partial = path + ".partial.ogg"
    try:
        subprocess.run(
            ["ffmpeg", "-nostdin", "-v", "error", "-y", *inputs, "-filter_complex", graph]
            + ["-c:a", "libvorbis", "-q:a", "5", partial],
            check=True,
        )
        os.replace(partial, path)
    finally:
        if os.path.exists(partial):
            os.remove(partial)


def timeline_tracks(song: str) -> list[str]:
    tracks = sorted(
        os.path.join(root, name)
        for root, _, names in os.walk(MUSIC)
        for name in names
        if name.endswith((".ogg", ".wav"))
    )
    return [*tracks, song]


def timeline_cpu(extractor: str, manifest: str, scratch: str, env: dict | None) -> float:
    """CPU seconds of one timeline build (``env``: the older code's) with an empty cache."""
    cache = tempfile.mkdtemp(dir=scratch)
    try:
        command = [extractor] if env is None else [sys.executable, "-m", "loudscape_extract.cli"]
        command += ["timeline", "--manifest", manifest, "--quiet", "--jobs", "2"]
        command += ["-o", os.path.join(scratch, "timeline.ply"), "--cache-dir", cache]
        return run_child(command, env=env)[2]
    finally:
        shutil.rmtree(cache)


def line(label: str, values: list[float], unit: str = "s") -> str:
    runs = ", ".join(f"{v:.2f}" for v in values)
    return f"{label:34s} median {statistics.median(values):6.2f} {unit}  (runs {runs})"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--vs-code", help="an older tree's preprocess folder to time as well")
    parser.add_argument("--skip-timeline", action="store_true")
    args = parser.parse_args()
    if args.runs < 1:
        return fail(f"--runs must be >= 1, got {args.runs}")
    missing = [part for part in SONG_PARTS if not os.path.isfile(os.path.join(MUSIC, part))]
    if missing:
        return fail(f"{MUSIC}: missing {', '.join(missing)} (make real-music fetches them)")
    if shutil.which("ffmpeg") is None or shutil.which("ffprobe") is None:
        return fail("ffmpeg and ffprobe are needed on PATH")
    os.makedirs(OUT, exist_ok=True)
    song = os.path.join(OUT, "track-3m30.ogg")
    if not os.path.isfile(song):
        make_song(song)
    song_s = duration_s(song)
    tracks = timeline_tracks(song)
    audio_s = sum(duration_s(path) for path in tracks)
    extractor = os.path.join(os.path.dirname(sys.executable), "loudscape-extract")
    old_env = None
    if args.vs_code:
        old_env = dict(os.environ, PYTHONPATH=os.path.abspath(args.vs_code))
    for tree in [os.path.join(REPO, "preprocess"), args.vs_code]:
        if tree and not compileall.compile_dir(tree, quiet=2):
            return fail(f"{tree}: could not byte-compile the extractor's sources")
    print(f"song: {os.path.relpath(song, REPO)}, {song_s:.1f} s; {os.cpu_count()} CPUs")
    ours, ours_cpu, old, old_cpu, rosa, rosa_cpu, ff, ff_cpu = ([] for _ in range(8))
    ours_rss, old_rss = [], []
    line_ours, line_tl, line_old_tl, line_ff_tl = [], [], [], []
    loads = []
    with tempfile.TemporaryDirectory() as scratch:
        ply = os.path.join(scratch, "song.ply")
        manifest = os.path.join(scratch, "manifest.csv")
        with open(manifest, "w", encoding="utf-8") as handle:
            handle.write("path,year\n")
            for index, path in enumerate(tracks):
                handle.write(f"{path},{1990 + 3 * index}\n")
        for _ in range(args.runs):
            loads.append(os.getloadavg()[0])
            wall, rss, cpu, _ = run_child([extractor, "song", song, "-o", ply, "--quiet"])
            ours.append(wall)
            ours_cpu.append(cpu)
            ours_rss.append(rss)
            if old_env is not None:
                command = [sys.executable, "-m", "loudscape_extract.cli", "song", song]
                wall, rss, cpu, _ = run_child([*command, "-o", ply, "--quiet"], env=old_env)
                old.append(wall)
                old_cpu.append(cpu)
                old_rss.append(rss)
            _, _, _, stdout = run_child(
                [sys.executable, "-c", LIBROSA_CHILD, song, str(N_FFT), str(HOP)]
            )
            wall, cpu = (float(value) for value in stdout.split())
            rosa.append(wall)
            rosa_cpu.append(cpu)
            ffmpeg = ["ffmpeg", "-nostdin", "-hide_banner", "-nostats", "-i", song]
            wall, _, cpu, _ = run_child([*ffmpeg, "-af", "ebur128=peak=true", "-f", "null", "-"])
            ff.append(wall)
            ff_cpu.append(cpu)
            if args.skip_timeline:
                continue
            cpu = timeline_cpu(extractor, manifest, scratch, None)
            line_ours.append(cpu)
            line_tl.append(audio_s / cpu)
            if old_env is not None:
                line_old_tl.append(audio_s / timeline_cpu(extractor, manifest, scratch, old_env))
            _, _, cpu, _ = run_child([sys.executable, "-c", FFMPEG_PAIRS_CHILD, *tracks])
            line_ff_tl.append(audio_s / cpu)
    print("\nSong extraction (wall; CPU = user + sys)")
    print(line("ours, whole process", ours))
    print(line("  CPU", ours_cpu))
    print(f"  peak RSS {max(ours_rss):.0f} MiB")
    if old:
        print(line(f"older code ({args.vs_code})", old))
        print(line("  CPU", old_cpu))
        print(f"  peak RSS {max(old_rss):.0f} MiB")
    print(line("librosa stft+hpss alone", rosa))
    print(line("  CPU", rosa_cpu))
    print(line("ffmpeg ebur128=peak=true", ff))
    print(line("  CPU", ff_cpu))
    print(f"librosa / ours (wall): {statistics.median(rosa) / statistics.median(ours):.2f}x")
    print(
        f"librosa / ours (CPU):  {statistics.median(rosa_cpu) / statistics.median(ours_cpu):.2f}x"
    )
    if old:
        print(
            f"librosa / older code (wall): {statistics.median(rosa) / statistics.median(old):.2f}x"
        )
    print(f"ours / ffmpeg (wall):  {statistics.median(ours) / statistics.median(ff):.2f}x")
    print(f"real time (ours, wall): {song_s / statistics.median(ours):.0f}x")
    if line_tl:
        print(f"\nTimeline: {len(tracks)} tracks, {audio_s:.1f} s of audio, empty cache, --jobs 2")
        print(line("ours, CPU of the process tree", line_ours))
        print(line("ours", line_tl, "s of audio per CPU-s"))
        if line_old_tl:
            print(line("older code", line_old_tl, "s of audio per CPU-s"))
        print(line("ffmpeg ebur128, 2 at a time", line_ff_tl, "s of audio per CPU-s"))
        ratio = statistics.median(line_ff_tl) / statistics.median(line_tl)
        print(f"ffmpeg / ours: {ratio:.2f}x")
    print(
        f"\nat {time.strftime('%Y-%m-%d %H:%M')}, 1-minute load average at the rounds' starts "
        + ", ".join(f"{load:.2f}" for load in loads)
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
