"""Command line: ``loudscape-extract song track.mp3 -o track.ply``.

Subcommands are thin: they parse flags, call the pipeline functions and turn
:class:`ExtractError` into one line on stderr and exit status 1 (2 for bad flags).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence

from loudscape_extract.errors import ExtractError

PROG = "loudscape-extract"


class Progress:
    """Per-stage progress lines on stderr, only when enabled (stderr is a TTY and not quiet)."""

    def __init__(self, *, enabled: bool) -> None:
        self.enabled = enabled
        self.start = time.perf_counter()

    def __call__(self, message: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            print(f"{PROG}: [{elapsed:6.2f} s] {message}", file=sys.stderr, flush=True)


def check_output_path(output: str) -> None:
    """Fail early when the output cannot be created (missing directory, or a directory)."""
    directory = os.path.dirname(os.path.abspath(output))
    if os.path.isdir(output):
        raise ExtractError("output path is a directory", path=output)
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=output)
    if not os.access(directory, os.W_OK):
        raise ExtractError(f"output directory {directory!r} is not writable", path=output)


def extract_song(
    source: str,
    output: str,
    *,
    n_fft: int = 2048,
    hop_length: int = 1024,
    floor_db: float | None = None,
    freq_scale: str = "linear",
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Song mode end to end: decode, features, points, atomic PLY write.

    Parameters
    ----------
    source : str
        Audio file; recorded in the metadata exactly as given.
    output : str
        PLY file to write.
    n_fft, hop_length : int
        STFT parameters.
    floor_db : float, optional
        Noise floor below the peak bin (default :data:`DEFAULT_FLOOR_DB`); 0 disables it.
    freq_scale : {"linear", "log"}
    progress : callable, optional
        Called with a short message before each stage.

    Returns
    -------
    metadata : dict
        What was written into the file's ``loudscape-meta`` comment.
    """
    from loudscape_extract import __version__
    from loudscape_extract.audio import decode_audio
    from loudscape_extract.features import track_features
    from loudscape_extract.ply import write_ply
    from loudscape_extract.points import DEFAULT_FLOOR_DB, song_metadata, song_points

    say = progress or (lambda _message: None)
    floor = DEFAULT_FLOOR_DB if floor_db is None else floor_db
    check_output_path(output)
    say(f"decoding {source}")
    audio = decode_audio(source)
    say(f"{audio.duration_s:.1f} s, {audio.sample_rate} Hz, {audio.n_channels} channel(s)")
    try:
        features = track_features(audio, n_fft=n_fft, hop_length=hop_length, progress=say)
        say("building points")
        cloud = song_points(features, floor_db=floor, freq_scale=freq_scale)
    except ExtractError as exc:
        if exc.path is None:
            exc.path = source
        raise
    source_format = f"{audio.format}/{audio.subtype}"
    del audio
    metadata = song_metadata(
        features, cloud, generator=f"{PROG} {__version__}", source_format=source_format
    )
    say(f"writing {cloud.points.shape[0]} points to {output}")
    write_ply(output, points=cloud.points, metadata=metadata)
    say("done")
    return metadata


def _positive_even(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 4 or value % 2:
        raise argparse.ArgumentTypeError(f"must be an even integer >= 4, got {value}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _non_negative_db(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of dB, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    from loudscape_extract import __version__
    from loudscape_extract.points import DEFAULT_FLOOR_DB, FREQ_SCALES

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
    song.add_argument("--hop", type=_positive_int, default=1024, help="STFT hop (1024)")
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
    timeline = commands.add_parser(
        "timeline",
        help="many songs -> one chronological cloud (one point per sampled frame)",
        description="Many songs -> one point cloud ordered by year: x song position (by year "
        "or by order), y frame RMS level (-60..0 dBFS), z frame crest factor (1st-99th "
        "percentile over all songs), scalar A-weighted frame level, hp frame hp ratio. Years, "
        "titles and artists come from tags (mutagen) or from --manifest.",
    )
    timeline.add_argument(
        "inputs", nargs="*", help="audio files and folders (searched recursively)"
    )
    timeline.add_argument(
        "--manifest",
        help="CSV with columns path, year[, title, artist]; paths relative to its folder",
    )
    timeline.add_argument("-o", "--output", default="timeline.ply", help="PLY file to write")
    timeline.add_argument(
        "--x-by",
        choices=("year", "order"),
        default="year",
        help="x proportional to the year (default) or each song an equal span in order",
    )
    timeline.add_argument(
        "--frames-per-song",
        type=_positive_int,
        default=1024,
        help="frames sampled evenly per song (1024; fewer if a song has fewer)",
    )
    timeline.add_argument("--n-fft", type=_positive_even, default=2048, help="STFT size (2048)")
    timeline.add_argument("--hop", type=_positive_int, default=1024, help="STFT hop (1024)")
    timeline.add_argument(
        "--cache-dir",
        help="per-song feature cache (default $XDG_CACHE_HOME/loudscape or ~/.cache/loudscape)",
    )
    timeline.add_argument("--no-cache", action="store_true", help="neither read nor write it")
    timeline.add_argument(
        "--jobs",
        "-j",
        type=_positive_int,
        default=os.cpu_count() or 1,
        help="songs in parallel worker processes (default: number of cores)",
    )

    report = commands.add_parser(
        "report",
        help="plot a timeline's per-year loudness metrics (PNG, optional CSV)",
        description="Per year: integrated loudness, crest factor (median and 5th-95th "
        "percentile band over songs), loudness range and hp mean, from a timeline PLY.",
    )
    report.add_argument("input", help="timeline PLY written by the timeline command")
    report.add_argument("-o", "--output", default="report.png", help="PNG file to write")
    report.add_argument("--csv", help="also write the per-year table as CSV")

    from loudscape_extract import export

    for sub in (song, timeline, report, export.add_parser(commands)):
        sub.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
        sub.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    return parser


def run_timeline(args: argparse.Namespace, *, tty: bool) -> int:
    """The timeline subcommand: build, then a summary on stderr; 1 when any song failed."""
    from loudscape_extract.timeline import build_timeline, default_cache_dir

    width = [0]

    def progress(done: int, total: int, path: str) -> None:
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
            progress=progress,
        )
    finally:
        if tty and width[0]:
            print("\r" + " " * width[0] + "\r", end="", file=sys.stderr, flush=True)
    elapsed = time.perf_counter() - start
    for path in result.without_year:
        print(f"{PROG}: skipped: {path}: no year in its tags", file=sys.stderr)
    for path, reason in sorted(result.failed.items()):
        print(f"{PROG}: skipped: {path}: {reason}", file=sys.stderr)
    if not args.quiet:
        songs = result.metadata["songs"]
        print(
            f"{PROG}: wrote {args.output}: {len(songs)} song(s), "
            f"{result.metadata['point_count']} points in {elapsed:.1f} s "
            f"({result.cached} from cache)",
            file=sys.stderr,
        )
        if result.few_frames:
            print(
                f"{PROG}: {len(result.few_frames)} song(s) have fewer than "
                f"{args.frames_per_song} non-silent frames and use all they have: "
                + ", ".join(result.few_frames[:5])
                + (" ..." if len(result.few_frames) > 5 else ""),
                file=sys.stderr,
            )
        if result.without_year:
            print(
                f"{PROG}: left out {len(result.without_year)} song(s) without a year",
                file=sys.stderr,
            )
    if result.failed:
        print(
            f"{PROG}: {len(result.failed)} song(s) failed and were skipped: "
            + ", ".join(sorted(result.failed)),
            file=sys.stderr,
        )
        return 1
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``loudscape-extract``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "song" and args.hop > args.n_fft:
        parser.error(f"--hop {args.hop} is larger than --n-fft {args.n_fft}")
    progress = Progress(enabled=not args.quiet and sys.stderr.isatty())
    try:
        if args.command == "song":
            output = args.output or os.path.splitext(args.input)[0] + ".ply"
            extract_song(
                args.input,
                output,
                n_fft=args.n_fft,
                hop_length=args.hop,
                floor_db=args.floor_db,
                freq_scale=args.freq_scale,
                progress=progress,
            )
        elif args.command == "timeline":
            return run_timeline(args, tty=not args.quiet and sys.stderr.isatty())
        elif args.command == "report":
            from loudscape_extract.report import write_report

            write_report(args.input, args.output, csv_path=args.csv)
        elif args.command == "export":
            from loudscape_extract import export

            return export.run(args)
    except ExtractError as exc:
        if args.debug:
            raise
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        if args.debug:
            raise
        print(f"{PROG}: interrupted; no file written", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - one line, no traceback, unless --debug
        if args.debug:
            raise
        reason = " ".join(str(exc).split()) or type(exc).__name__
        where = getattr(args, "input", None) or getattr(args, "output", "")
        print(f"{PROG}: error: {where}: internal error: {reason}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
