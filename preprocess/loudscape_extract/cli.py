"""Command line: ``loudscape-extract song track.mp3 -o track.ply``.

Argument parsing only: subcommands parse flags, call the library (:func:`extract_song`,
:func:`build_timeline`, :func:`write_report`) and turn :class:`ExtractError` into one line on
stderr and exit status 1 (2 for bad flags). Nothing in the library imports this module.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence

from loudscape_extract import export
from loudscape_extract.audio import decode_audio
from loudscape_extract.blas_threads import one_blas_thread
from loudscape_extract.compare import MAX_VERSIONS, compare_versions
from loudscape_extract.compare_sheet import summary_json, write_compare_csv, write_sheet
from loudscape_extract.dynamics import HIGHPASS_HZ
from loudscape_extract.errors import ExtractError
from loudscape_extract.interrupts import Terminated, sigterm_raises
from loudscape_extract.loudness_csv import add_parser as add_loudness_parser
from loudscape_extract.loudness_csv import run as run_loudness
from loudscape_extract.memory import keep_freed_memory
from loudscape_extract.messages import one_line
from loudscape_extract.normalization import NORMALIZE_CHOICES, PRESETS
from loudscape_extract.notices import warning_lines
from loudscape_extract.paths import check_output_path
from loudscape_extract.ply import read_ply_metadata
from loudscape_extract.progress import JsonProgress, JsonTimelineProgress, Progress
from loudscape_extract.report import write_report
from loudscape_extract.song import extract_song
from loudscape_extract.song_cloud import DEFAULT_FLOOR_DB, FREQ_SCALES, MAX_FLOOR_DB
from loudscape_extract.song_report import (
    TARGET_CHOICES,
    Target,
    input_kind,
    preset_target,
    write_folder_report,
    write_song_report,
)
from loudscape_extract.timeline import (
    DEFAULT_MAX_POINTS,
    DEFAULT_Y_MEASURE,
    DEFAULT_Z_MEASURE,
    MIN_FRAMES_PER_SONG,
    Y_MEASURES,
    Z_MEASURES,
    build_timeline,
    default_cache_dir,
    discover_audio,
    read_tags,
)
from loudscape_extract.version import PROG, __version__

__all__ = ["build_parser", "main"]


#: Ranges of the numeric flags: wide enough for any real use, narrow enough that a typo
#: (``--floor-db 1e308``, ``--n-fft 1000000000``, ``--jobs 99999``) is refused at once with a
#: clear line instead of overflowing, exhausting memory or forking without end.
MAX_N_FFT = 1 << 16
MAX_HOP = 1 << 16
MAX_FRAMES_PER_SONG = 1_000_000
MAX_POINTS_FLAG = 2_000_000_000
MAX_JOBS = max(256, 4 * (os.cpu_count() or 1))


def _integer(text: str, low: int, high: int, *, even: bool = False) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not low <= value <= high or (even and value % 2):
        kind = "an even integer" if even else "an integer"
        raise argparse.ArgumentTypeError(f"must be {kind} from {low:,} to {high:,}, got {text}")
    return value


def _positive_even(text: str) -> int:
    return _integer(text, 4, MAX_N_FFT, even=True)


def _hop(text: str) -> int:
    return _integer(text, 1, MAX_HOP)


def _frames_per_song(text: str) -> int:
    return _integer(text, 1, MAX_FRAMES_PER_SONG)


def _max_points(text: str) -> int:
    return _integer(text, 0, MAX_POINTS_FLAG)


def _jobs(text: str) -> int:
    return _integer(text, 1, MAX_JOBS)


def _non_negative_db(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of dB, got {text!r}") from None
    if not 0 <= value <= MAX_FLOOR_DB:  # NaN fails too
        raise argparse.ArgumentTypeError(
            f"must be a number of dB from 0 to {MAX_FLOOR_DB:g} (0 keeps every bin), got {text}"
        )
    return value


def _loudness_flag(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not -70.0 <= value <= 10.0:  # NaN fails too
        raise argparse.ArgumentTypeError(f"must be from -70 to 10, got {text}")
    return value


def _tolerance(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of LU, got {text!r}") from None
    if not 0.0 <= value <= 20.0:
        raise argparse.ArgumentTypeError(f"must be from 0 to 20 LU, got {text}")
    return value


def _add_song_report_arguments(report: argparse.ArgumentParser) -> None:
    """The song and folder report's flags (``report``)."""
    target = report.add_mutually_exclusive_group()
    target.add_argument(
        "--target",
        choices=TARGET_CHOICES,
        help="delivery target: a normalization preset's loudness and true-peak ceiling "
        "(pass/fail line on the page and in the CSV)",
    )
    target.add_argument(
        "--target-lufs", type=_loudness_flag, help="delivery target's integrated loudness"
    )
    report.add_argument(
        "--max-true-peak",
        type=_loudness_flag,
        help="delivery target's true-peak ceiling in dBTP (default -1 with --target-lufs)",
    )
    report.add_argument(
        "--tolerance-lu",
        type=_tolerance,
        default=1.0,
        help="how far the integrated loudness may be from the target (1.0 LU)",
    )
    report.add_argument(
        "--format",
        choices=("pdf", "png"),
        default="pdf",
        help="a folder's pages: PDF (default) or PNG",
    )
    report.add_argument(
        "--jobs",
        "-j",
        type=_jobs,
        default=os.cpu_count() or 1,
        help="a folder: songs in parallel worker processes (default: number of cores)",
    )
    report.add_argument(
        "--cache-dir", help="measured songs' cache (default: the timeline's cache folder)"
    )
    report.add_argument("--no-cache", action="store_true", help="neither read nor write it")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, description="Turn audio into loudscape point clouds (PLY)."
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    song = commands.add_parser(
        "song",
        help="one track -> one point per STFT bin",
        description="One track -> one point per STFT bin: x time, y level, z frequency, "
        "scalar A-weighted level, hp harmonic-percussive ratio. Whole-track loudness "
        "metrics go into the file's metadata.",
    )
    song.add_argument("input", help="audio file: wav, flac, ogg/vorbis, opus, mp3, aiff")
    song.add_argument(
        "-o", "--output", help="PLY file to write (default: the input's name with .ply)"
    )
    song.add_argument("--n-fft", type=_positive_even, default=2048, help="STFT size (2048)")
    song.add_argument("--hop", type=_hop, default=1024, help="STFT hop (1024)")
    song.add_argument(
        "--floor-db",
        type=_non_negative_db,
        default=DEFAULT_FLOOR_DB,
        help=f"drop bins more than this many dB below the track's loudest bin "
        f"({DEFAULT_FLOOR_DB:g}; 0 keeps every bin)",
    )
    song.add_argument(
        "--freq-scale",
        choices=FREQ_SCALES,
        default="linear",
        help="z axis: linear in bin index (default) or log frequency (drops the 0 Hz bin)",
    )
    song.add_argument(
        "--progress",
        choices=("text", "json"),
        default="text",
        help="json: one JSON object a line on stdout (stage, fraction; done or error last)",
    )
    song.add_argument(
        "--highpass",
        action="store_true",
        help=f"also high-pass at {HIGHPASS_HZ:g} Hz (infrasound) before frame level, crest, "
        "PSR and DR (DC is always removed)",
    )
    timeline = commands.add_parser(
        "timeline",
        help="many songs -> one chronological cloud (one point per sampled frame)",
        description="Many songs -> one point cloud ordered by year: x song position (by year "
        "or by order), y the frame's loudness (-60..0 LUFS, BS.1770 momentary by default; see "
        "--y-measure), z the dynamics of the 3 s around each "
        "frame (PSR by default; see --z-measure; 1st-99th percentile over all songs), scalar "
        "A-weighted frame level, hp frame hp ratio. Years, titles and artists come from tags "
        "(mutagen) or from --manifest.",
    )
    timeline.add_argument(
        "inputs", nargs="*", help="audio files and folders (searched recursively)"
    )
    timeline.add_argument(
        "--manifest",
        help="CSV with columns path, year[, title, artist]; paths relative to its folder",
    )
    timeline.add_argument("-o", "--output", default="timeline.ply", help="PLY file to write (.ply)")
    timeline.add_argument(
        "--x-by",
        choices=("year", "order"),
        default="year",
        help="x proportional to the year (default) or each song an equal span in order "
        "(songs without a year then come last instead of being left out)",
    )
    timeline.add_argument(
        "--y-measure",
        choices=Y_MEASURES,
        default=DEFAULT_Y_MEASURE,
        help="y axis: momentary (BS.1770 loudness of the 400 ms around the frame, LUFS; "
        "default), short-term (of the 3 s around it), rms (the paper's unweighted frame RMS, "
        "dBFS) or a-weighted (the frame's A-weighted level)",
    )
    timeline.add_argument(
        "--z-measure",
        choices=Z_MEASURES,
        default=DEFAULT_Z_MEASURE,
        help="z axis: psr (true peak minus short-term loudness over the 3 s around the frame; "
        "default), crest-3s (peak/RMS over those 3 s) or crest-frame (the paper's crest "
        "factor of the STFT frame alone, which measures waveform shape, not compression)",
    )
    timeline.add_argument(
        "--highpass",
        action="store_true",
        help=f"also high-pass each song at {HIGHPASS_HZ:g} Hz before its dynamics",
    )
    timeline.add_argument(
        "--frames-per-song",
        type=_frames_per_song,
        default=1024,
        help="frames sampled evenly per song (1024; fewer if a song has fewer, or if "
        "--max-points needs it)",
    )
    timeline.add_argument(
        "--max-points",
        type=_max_points,
        default=DEFAULT_MAX_POINTS,
        help=f"lower the frames per song so the cloud stays under this many points, but not "
        f"below {MIN_FRAMES_PER_SONG} a song ({DEFAULT_MAX_POINTS:,}; 0: no cap)",
    )
    timeline.add_argument("--n-fft", type=_positive_even, default=2048, help="STFT size (2048)")
    timeline.add_argument("--hop", type=_hop, default=1024, help="STFT hop (1024)")
    timeline.add_argument(
        "--cache-dir",
        help="per-song feature cache (default $XDG_CACHE_HOME/loudscape or ~/.cache/loudscape)",
    )
    timeline.add_argument("--no-cache", action="store_true", help="neither read nor write it")
    timeline.add_argument(
        "--list-songs",
        action="store_true",
        help="only list the audio files found and the year, title and artist of their tags "
        "(with --progress json: one object a song, then done); nothing is written",
    )
    timeline.add_argument(
        "--progress",
        choices=("text", "json"),
        default="text",
        help="json: one JSON object a song on stdout as each finishes (song, songs_done, "
        "songs_total, fraction), then the songs left out, then done or error",
    )
    timeline.add_argument(
        "--jobs",
        "-j",
        type=_jobs,
        default=os.cpu_count() or 1,
        help="songs in parallel worker processes (default: number of cores); with --dask, "
        "the local cluster's workers",
    )
    engine = timeline.add_mutually_exclusive_group()
    engine.add_argument(
        "--dask",
        action="store_true",
        help="run the songs on a local Dask cluster (--jobs worker processes) instead of "
        "the process pool (needs the [dask] extra)",
    )
    engine.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the songs on an existing dask.distributed scheduler, e.g. "
        "tcp://host:8786; its workers must see the song paths and --cache-dir (a shared "
        "folder)",
    )

    report = commands.add_parser(
        "report",
        help="a song's loudness report (PDF or PNG), a folder's, or a timeline's per year",
        description="A song (audio file or song cloud): one page with the EBU Mode readings, "
        "PLR, PSR, DR, the loudness and PSR curves, the short-term histogram with the LRA "
        "band, each streaming service's gain and level as heard, and a verdict against "
        "--target. A folder: a page per song and summary.csv in the -o folder. A timeline "
        "PLY: per year, integrated loudness with streaming targets, PLR, DR, PSR (the songs, "
        "their median, a 5th-95th percentile band where a year has 5 songs or more), loudness "
        "range, hp mean and songs per year (PNG).",
    )
    report.add_argument(
        "input", help="audio file, song cloud (.ply), folder of audio, or timeline PLY"
    )
    report.add_argument(
        "-o",
        "--output",
        help="page to write (.pdf or .png; default: the input's name with -report.pdf; a "
        "timeline: report.png); a folder: the folder for the pages and summary.csv",
    )
    report.add_argument(
        "--csv",
        help="also write the numbers as CSV (.csv): a song's one row, or a timeline's "
        "per-year table (and per-song beside it)",
    )
    report.add_argument(
        "--normalize",
        choices=NORMALIZE_CHOICES,
        default="none",
        help="timeline: also draw each song and year as heard after this playback "
        "normalization (streaming services, broadcast; docs/DYNAMICS.md)",
    )
    _add_song_report_arguments(report)

    compare = commands.add_parser(
        "compare",
        help="compare 2 to 8 versions of a song: aligned in time, matched in loudness",
        description="Aligns every version to the first (offset and time map, with a "
        "confidence; unrelated music is said and not shifted), finds the gain that matches "
        "each to the quietest one's integrated loudness (or to a service's level, --match), "
        "and prints or writes the metrics, the aligned loudness curves and the tonal balance "
        "at matched loudness (docs/COMPARE.md).",
    )
    compare.add_argument("versions", nargs="+", metavar="VERSION", help="audio files, A first")
    compare.add_argument("-o", "--output", help="write the sheet (.png or .pdf)")
    compare.add_argument("--csv", help="write the table as CSV (.csv), one row a version")
    compare.add_argument(
        "--json", action="store_true", help="print each version's offset, gain and metrics as JSON"
    )
    compare.add_argument(
        "--match",
        choices=("quietest", *PRESETS),
        default="quietest",
        help="the loudness the versions are matched to: the quietest version's (default) or a "
        "service's level with its rules",
    )

    for sub in (song, timeline):
        sub.add_argument(
            "--strict",
            action="store_true",
            help="refuse truncated or corrupt audio instead of using what decodes (with a warning)",
        )
    for sub in (song, timeline, report, compare, export.add_parser(commands)):
        sub.add_argument(
            "-q",
            "--quiet",
            action="store_true",
            help="no progress or 'wrote' summaries on stderr (warnings and errors still show)",
        )
        sub.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    add_loudness_parser(commands)
    return parser


def _say(text: str) -> None:
    """One line on stderr, prefixed with the program's name, whitespace collapsed, capped."""
    print(one_line(f"{PROG}: {text}"), file=sys.stderr, flush=True)


def _list(items, limit: int = 5) -> str:
    shown = ", ".join(str(item) for item in items[:limit])
    return shown + (f" and {len(items) - limit} more" if len(items) > limit else "")


def run_song(args: argparse.Namespace, progress: Progress) -> int:
    """The song subcommand: extract, then a ``wrote ...`` summary."""
    output = args.output or os.path.splitext(args.input)[0] + ".ply"
    start = time.perf_counter()
    metadata = extract_song(
        args.input,
        output,
        n_fft=args.n_fft,
        hop_length=args.hop,
        floor_db=args.floor_db,
        freq_scale=args.freq_scale,
        strict=args.strict,
        highpass_hz=HIGHPASS_HZ if args.highpass else None,
        progress=progress,
        warn=lambda text: _say(f"warning: {text}"),
        points=getattr(progress, "points", None),  # --progress json: the points line
    )
    if hasattr(progress, "done"):
        progress.done(output)
    if not args.quiet:
        _say(
            f"wrote {output} ({metadata['point_count']} points, "
            f"{metadata['stft']['frames_kept']} of {metadata['stft']['frames']} frames, "
            f"{metadata['source']['duration_s']:.1f} s of audio, "
            f"{time.perf_counter() - start:.1f} s)"
        )
    return 0


def list_songs(args: argparse.Namespace, json_progress=None) -> int:
    """``timeline --list-songs``: the songs found under the inputs with their tags, on stdout.

    A program (the app, to ask for the missing years before building) reads one JSON object a
    song, ``{"song", "year", "title", "artist", "tag_error"}`` (year null when the tags have
    none), then ``{"done": ""}``; people read one ``path<TAB>year<TAB>title<TAB>artist`` line a
    song.
    """
    if not args.inputs:
        raise ExtractError("no input: give folders or files to list")
    passed_over: dict = {}
    found = discover_audio(args.inputs, skipped=passed_over)
    for path, reason in passed_over.items():
        _say(f"skipped: {path}: {reason}")
    for path in found:
        tags = read_tags(path)
        if json_progress is not None:
            json_progress.emit(
                {
                    "song": path,
                    "year": tags["year"],
                    "title": tags["title"],
                    "artist": tags["artist"],
                    "tag_error": tags["error"],
                }
            )
        else:
            year = "" if tags["year"] is None else str(tags["year"])
            print(f"{path}\t{year}\t{tags['title']}\t{tags['artist']}", flush=True)
    if json_progress is not None:
        json_progress.done("")
    return 0


def run_timeline(args: argparse.Namespace, *, tty: bool, json_progress=None) -> int:
    """The timeline subcommand: build, then a summary on stderr; 1 when any song failed.

    ``json_progress`` (a :class:`JsonTimelineProgress`) hears every song as it finishes.
    """
    width = [0]

    def progress(done: int, total: int, path: str) -> None:
        if json_progress is not None:
            json_progress(done, total, path)
        if tty:
            line = f"{PROG}: [{done}/{total}] {os.path.basename(path)}"[:100]
            print("\r" + line.ljust(width[0]), end="", file=sys.stderr, flush=True)
            width[0] = len(line)

    start = time.perf_counter()
    cache_dir = None if args.no_cache else (args.cache_dir or default_cache_dir())
    try:
        result = build_timeline(
            args.inputs,
            args.output,
            manifest=args.manifest,
            x_by=args.x_by,
            frames_per_song=args.frames_per_song,
            n_fft=args.n_fft,
            hop_length=args.hop,
            cache_dir=cache_dir,
            jobs=args.jobs,
            strict=args.strict,
            z_measure=args.z_measure,
            y_measure=args.y_measure,
            highpass_hz=HIGHPASS_HZ if args.highpass else None,
            progress=progress,
            max_points=args.max_points,
            scheduler="local" if args.dask else args.scheduler,
        )
    finally:
        if tty and width[0]:
            print("\r" + " " * width[0] + "\r", end="", file=sys.stderr, flush=True)
    elapsed = time.perf_counter() - start
    if json_progress is not None:
        json_progress.left_out(without_year=result.without_year, failed=result.failed)
        json_progress.done(args.output)
    for note in result.notes:
        _say(f"warning: {note}")
    for path in result.without_year:
        _say(f"skipped: {path}: no year in its tags")
    for path, reason in sorted(result.failed.items()):
        _say(f"skipped: {path}: {reason}")
    for item in result.metadata.get("warnings", []):
        _say(f"warning: {item['path']}: {item['message']}")
    if not args.quiet:
        songs = result.metadata["songs"]
        _say(
            f"wrote {args.output} ({result.metadata['point_count']} points, "
            f"{len(songs)} song(s), {result.cached} from cache, {elapsed:.1f} s)"
        )
        if result.few_frames:
            _say(
                f"{len(result.few_frames)} song(s) have fewer than {result.frames_per_song} "
                f"non-silent frames and use all they have: {_list(result.few_frames)}"
            )
        if result.frames_per_song < args.frames_per_song:
            _say(
                f"{result.frames_per_song} frames per song (of {args.frames_per_song}) keep "
                f"{len(songs)} songs under --max-points {args.max_points:,}"
            )
        if result.without_year:
            _say(f"left out {len(result.without_year)} song(s) without a year")
    if result.failed:
        _say(
            f"{len(result.failed)} song(s) failed and were skipped: " + _list(sorted(result.failed))
        )
        return 1
    return 0


def run_export(args: argparse.Namespace) -> int:
    """The export subcommand: one VTK XML PolyData file, then the ``wrote ...`` summary."""
    output = args.output or os.path.splitext(args.input)[0] + ".vtp"
    n_points = export.export_vtp(args.input, output)
    _say_cloud_warnings(args.input)
    if not args.quiet:
        _say(f"wrote {output} ({n_points} points, VTK XML PolyData)")
    return 0


def _say_cloud_warnings(path: str) -> None:
    """The warnings a cloud carries (docs/FORMAT.md, "Warnings"), one ``warning:`` line each."""
    for line in warning_lines(read_ply_metadata(path)):
        _say(f"warning: {line}")


def _report_target(args: argparse.Namespace):
    if args.target:
        preset = preset_target(args.target, tolerance_lu=args.tolerance_lu)
        if args.max_true_peak is None:
            return preset
        return Target(preset.name, preset.lufs, args.max_true_peak, args.tolerance_lu)
    if args.target_lufs is not None or args.max_true_peak is not None:
        peak = -1.0 if args.max_true_peak is None else args.max_true_peak
        lufs = args.target_lufs
        name = f"{lufs:g} LUFS, {peak:g} dBTP" if lufs is not None else f"{peak:g} dBTP"
        return Target(name, lufs, peak, args.tolerance_lu)
    return None


def run_song_report(args: argparse.Namespace, kind: str) -> int:
    """``report`` of a song or a folder: pages (and CSV), the verdict and ``wrote`` lines; 1
    when a song of a folder failed (a FAIL verdict is a result, not an error: 0)."""
    target = _report_target(args)
    cache_dir = None if args.no_cache else (args.cache_dir or default_cache_dir())
    notes: list[str] = []
    if kind == "folder":
        if not args.output:
            raise ExtractError("give the folder for the pages with -o", path=args.input)
        if args.csv:
            raise ExtractError("--csv is for one song; a folder's numbers are in summary.csv")
        tty, width = not args.quiet and sys.stderr.isatty(), [0]

        def progress(done: int, total: int, path: str) -> None:
            if tty:
                line = f"{PROG}: [{done}/{total}] {os.path.basename(path)}"[:100]
                print("\r" + line.ljust(width[0]), end="", file=sys.stderr, flush=True)
                width[0] = len(line)

        try:
            result = write_folder_report(
                args.input,
                args.output,
                extension="." + args.format,
                target=target,
                jobs=args.jobs,
                cache_dir=cache_dir,
                on_done=progress,
            )
        finally:
            if width[0]:
                print("\r" + " " * width[0] + "\r", end="", file=sys.stderr, flush=True)
        for line in result.notes:
            _say(line)
        for path, reason in sorted(result.failed.items()):
            _say(f"skipped: {path}: {reason}")
        fails = sum(row.get("verdict") == "fail" for row in result.rows)
        if not args.quiet:
            _say(
                f"wrote {len(result.pages)} page(s) and {result.summary} "
                f"({len(result.rows)} song(s), {result.cached} from cache"
                + (f", {fails} FAIL against {target.name}" if target else "")
                + ")"
            )
        return 1 if result.failed else 0
    output = args.output or os.path.splitext(args.input)[0] + "-report.pdf"
    song, verdict = write_song_report(
        args.input, output, csv_path=args.csv, target=target, cache_dir=cache_dir, notes=notes
    )
    for line in notes + [f"warning: {song.path}: {w}" for w in song.warnings]:
        _say(line)
    if verdict is not None:
        _say(verdict.text)
    if not args.quiet:
        _say(f"wrote {output}")
        if args.csv:
            _say(f"wrote {args.csv} (1 row)")
    return 0


def run_report(args: argparse.Namespace) -> int:
    """The report subcommand: a song's or a folder's (:func:`run_song_report`), or a
    timeline's PNG (and CSV), then ``wrote ...`` summaries."""
    kind = input_kind(args.input)
    if kind != "timeline":
        if args.normalize != "none":
            raise ExtractError("--normalize is for a timeline; a song's page shows every preset")
        return run_song_report(args, kind)
    song_flags = ("target", "target_lufs", "max_true_peak")
    given = [name for name in song_flags if getattr(args, name) is not None]
    if given:
        flag = "--" + given[0].replace("_", "-")
        raise ExtractError(f"{flag} is for a song or a folder, not a timeline", path=args.input)
    args.output = args.output or "report.png"
    rows = write_report(args.input, args.output, csv_path=args.csv, normalize=args.normalize)
    _say_cloud_warnings(args.input)
    if not args.quiet:
        songs = sum(row["songs"] for row in rows)
        _say(f"wrote {args.output} ({songs} song(s), {len(rows)} year(s))")
        if args.csv:
            _say(f"wrote {args.csv} ({len(rows)} row(s), one per year)")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """The compare subcommand: decode, align, match; JSON on stdout, sheet and CSV files."""
    if not 2 <= len(args.versions) <= MAX_VERSIONS:
        raise ExtractError(f"compare takes 2 to {MAX_VERSIONS} versions, got {len(args.versions)}")
    if args.output:
        check_output_path(args.output, inputs=args.versions, extensions=(".png", ".pdf"))
    if args.csv:
        check_output_path(args.csv, inputs=args.versions, extensions=(".csv",), flag="--csv")
    if not (args.output or args.csv or args.json):
        raise ExtractError("say what to write: -o SHEET.png, --csv TABLE.csv or --json")
    audios = []
    for path in args.versions:
        audio = decode_audio(path)
        if audio.warning:
            _say(f"warning: {path}: {audio.warning}")
        audios.append(audio)
    say = (lambda _m: None) if args.quiet else (lambda m: _say(m))
    versions = compare_versions(audios, match=args.match, progress=say)
    for v in versions[1:]:
        if not v.alignment.alignable:
            _say(f"warning: {v.path}: not aligned to {versions[0].path}: {v.alignment.reason}")
    if args.output:
        write_sheet(args.output, versions, match=args.match)
        if not args.quiet:
            _say(f"wrote {args.output} ({len(versions)} versions)")
    if args.csv:
        write_compare_csv(args.csv, versions)
        if not args.quiet:
            _say(f"wrote {args.csv} ({len(versions)} row(s), one per version)")
    if args.json:
        print(summary_json(versions, match=args.match))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``loudscape-extract``; returns the exit status.

    Every message is one line on stderr. SIGTERM is turned into an exception so temporaries
    are removed and worker processes stopped; exit status 130 after Ctrl+C, 143 after SIGTERM.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in ("song", "timeline") and args.hop > args.n_fft:
        parser.error(f"--hop {args.hop} is larger than --n-fft {args.n_fft}")
    if args.command in ("song", "timeline"):
        keep_freed_memory()  # block after block of large arrays: reused, not zeroed again
        one_blas_thread()  # small products: no helper threads left spinning after each
    progress = Progress(enabled=not args.quiet and sys.stderr.isatty())
    if getattr(args, "progress", "text") == "json":
        progress = JsonTimelineProgress() if args.command == "timeline" else JsonProgress()
    try:
        with sigterm_raises():
            if args.command == "song":
                return run_song(args, progress)
            if args.command == "timeline" and args.list_songs:
                return list_songs(args, progress if hasattr(progress, "left_out") else None)
            if args.command == "timeline":
                return run_timeline(
                    args,
                    tty=not args.quiet and sys.stderr.isatty(),
                    json_progress=progress if hasattr(progress, "left_out") else None,
                )
            if args.command == "export":
                return run_export(args)
            if args.command == "loudness":
                return run_loudness(args, say=_say)
            if args.command == "compare":
                return run_compare(args)
            return run_report(args)
    except ExtractError as exc:
        if args.debug:
            raise
        _say(f"error: {exc}")
        if hasattr(progress, "error"):
            progress.error(str(exc))
        return 1
    except KeyboardInterrupt as exc:
        if args.debug:
            raise
        what = "terminated" if isinstance(exc, Terminated) else "interrupted"
        kept = "; songs finished so far stay in the cache" if args.command == "timeline" else ""
        if args.command == "report" and os.path.isdir(args.input):
            _say(f"{what}; the pages finished so far are kept, no summary.csv written")
        else:
            _say(f"{what}; no file written{kept}")
        return 143 if isinstance(exc, Terminated) else 130
    except Exception as exc:  # noqa: BLE001 - one line, no traceback, unless --debug
        if args.debug:
            raise
        reason = " ".join(str(exc).split()) or type(exc).__name__
        where = getattr(args, "input", None) or getattr(args, "output", "")
        _say(f"error: {where}: internal error: {reason}")
        if hasattr(progress, "error"):
            progress.error(f"{where}: internal error: {reason}")
        return 1


if __name__ == "__main__":
    sys.exit(main())
