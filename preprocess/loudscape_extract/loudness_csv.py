"""``loudscape-extract loudness``: a song's loudness curves with timestamps, as CSV.

One row per 100 ms segment, at the time an EBU Mode meter shows the reading (the end of the
segment, so the windows end there too):

- ``time_s``: end of the 100 ms segment, seconds from the start;
- ``momentary_lufs``: BS.1770 loudness of the 400 ms ending there (empty before 0.4 s and in
  digital silence);
- ``short_term_lufs``: of the 3 s ending there (empty before 3 s);
- ``psr_db``: true peak of those 3 s minus their short-term loudness (empty below -70 LUFS);
- ``true_peak_dbtp``: true peak (4x oversampled) of the 100 ms segment itself.

Everything is measured on the DC-free channels, as the cloud's metrics and curves are: an
audio file goes through the streamed extraction's two decoding passes (bounded memory; the
same sums a Song cloud's metrics come from, :func:`file_curves`). The whole
track's readings (integrated loudness, LRA, true peak, PLR, and the maximum momentary and
short-term loudness at any window position with the times a meter shows them) go to a second
table beside the first, ``NAME-summary.csv`` (``reading, value, unit, time_s``): spreadsheets
and ``pandas.read_csv`` read each file as one plain table, with no comment lines to skip.

A Song-mode cloud (``.ply``) works too when it stores its curves (metadata ``loudness``,
docs/FORMAT.md): its rows are the stored values (0.1 dB, 10 a second, fewer past 20 minutes),
moved from the window centres to the window ends; the cloud does not store the 100 ms true
peaks, so that column is empty. docs/FORMAT.md ("Loudness curves as CSV") is the reference.
"""

from __future__ import annotations

import argparse
import math
import os

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from loudscape_extract.audio import mix_to_mono
from loudscape_extract.csv_table import write_csv
from loudscape_extract.dynamics import (
    DC_WARN_THRESHOLD,
    dc_and_highpass,
    dc_warning,
    dynamics_from_segments,
    segment_true_peak,
    song_dynamics_metrics,
)
from loudscape_extract.errors import ExtractError
from loudscape_extract.loudness import (
    MOMENTARY_S,
    SHORT_TERM_S,
    loudness_from_energy,
    segment_energy_and_maxima,
    true_peak_dbtp,
)
from loudscape_extract.measures import WINDOW_MAXIMA_KEYS
from loudscape_extract.notices import warning_lines
from loudscape_extract.paths import check_output_path, check_regular_input
from loudscape_extract.ply import read_ply_metadata
from loudscape_extract.stream_decode import decode_track, signal_pass

__all__ = [
    "CURVE_COLUMNS",
    "SUMMARY_COLUMNS",
    "add_parser",
    "audio_curves",
    "cloud_curves",
    "file_curves",
    "run",
    "summary_path",
    "write_loudness_csv",
]

#: The curves table's columns, in order.
CURVE_COLUMNS = ("time_s", "momentary_lufs", "short_term_lufs", "psr_db", "true_peak_dbtp")
#: The summary table's columns.
SUMMARY_COLUMNS = ("reading", "value", "unit", "time_s")
#: The decoding passes' frame length (the command needs no spectrogram; only the frame
#: checks of the passes use it).
_N_FFT = 2048
_MOMENTARY_SEGMENTS = 4
_SHORT_TERM_SEGMENTS = 30
#: (reading, unit, the metric holding its time) in the summary's order.
_SUMMARY = (
    ("integrated_lufs", "LUFS", None),
    ("lra_lu", "LU", None),
    ("max_momentary_lufs", "LUFS", "max_momentary_s"),
    ("max_short_term_lufs", "LUFS", "max_short_term_s"),
    ("true_peak_dbtp", "dBTP", None),
    ("sample_peak_dbfs", "dBFS", None),
    ("plr_db", "dB", None),
    ("psr_median_db", "dB", None),
)


def _finite(value) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def _db(linear: float) -> float | None:
    return 20.0 * math.log10(linear) if linear > 0 else None


def audio_curves(samples: np.ndarray, *, sample_rate: float) -> tuple[list[dict], dict]:
    """The curves' rows and the whole-track readings of decoded audio.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels)]
        As decoded (the DC offset is removed here, as the extractor does).
    sample_rate : float

    Returns
    -------
    rows : list of dict
        Keyed by :data:`CURVE_COLUMNS`, one per complete 100 ms segment; None where not
        measurable.
    readings : dict
        ``integrated_lufs``, ``lra_lu``, ``max_momentary_lufs``, ``max_momentary_s``,
        ``max_short_term_lufs``, ``max_short_term_s``, ``true_peak_dbtp``,
        ``sample_peak_dbfs``, ``plr_db``, ``psr_median_db`` (None where not measurable) and
        ``dc_offset`` (the largest channel mean removed).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(4 * 8000) / 8000
    >>> tone = 0.1 * np.sin(2 * np.pi * 1000 * t)
    >>> rows, readings = audio_curves(np.stack([tone, tone], axis=1), sample_rate=8000)
    >>> len(rows), rows[3]["time_s"], rows[2]["momentary_lufs"]
    (40, 0.4, None)
    >>> round(rows[29]["short_term_lufs"], 1), round(readings["max_momentary_lufs"], 1)
    (-20.0, -20.0)
    """
    clean, dc = dc_and_highpass(samples, sample_rate=sample_rate, highpass_hz=None)
    (energy, boundaries), maxima = segment_energy_and_maxima(clean, sample_rate=sample_rate)
    segment_peak, overall_peak = segment_true_peak(clean, boundaries)
    mono = np.asarray(mix_to_mono(clean)[: boundaries[-1]], dtype=np.float64)
    starts = boundaries[:-1].astype(np.int64)
    n = energy.shape[0]
    dynamics = dynamics_from_segments(
        energy,
        boundaries,
        segment_peak=segment_peak,
        true_peak=overall_peak,
        mono_squares=np.add.reduceat(mono * mono, starts) if n else np.zeros(0),
        mono_peaks=np.maximum.reduceat(np.abs(mono), starts) if n else np.zeros(0),
        sample_rate=sample_rate,
    )
    true_peak = true_peak_dbtp(samples, sample_rate=sample_rate)
    return _curves(
        energy,
        boundaries,
        segment_peak=segment_peak,
        dynamics=dynamics,
        sample_rate=sample_rate,
        maxima=maxima,
        true_peak=10.0 ** (true_peak / 20.0) if true_peak is not None else 0.0,
        sample_peak=float(np.max(np.abs(samples))) if samples.size else 0.0,
        dc=dc,
    )


def file_curves(path: str, *, strict: bool = False) -> tuple[list[dict], dict, list[str]]:
    """:func:`audio_curves` of an audio file in bounded memory: the streamed extraction's two
    decoding passes (:mod:`loudscape_extract.stream_decode`), so the readings are the very
    values a Song cloud of the file holds.

    Returns
    -------
    rows, readings
        As :func:`audio_curves`.
    warnings : list of str
        ``<path>: <message>`` lines: a truncated file, clipping or cancelling channels, a
        large DC offset removed.

    Raises
    ------
    ExtractError
        As :func:`~loudscape_extract.stream_decode.decode_track` (unreadable, silent or
        shorter than 2048 samples).
    """
    decoded = decode_track(path, n_fft=_N_FFT, strict=strict)
    stats = signal_pass(decoded, n_fft=_N_FFT, hop_length=_N_FFT)
    rate = decoded.info.sample_rate
    dynamics = stats.dynamics(rate)
    rows, readings = _curves(
        stats.energy,
        stats.boundaries,
        segment_peak=stats.segment_peak,
        dynamics=dynamics,
        sample_rate=rate,
        maxima=stats.window_maxima,
        true_peak=max(stats.true_peak_decoded, decoded.sample_peak),
        sample_peak=decoded.sample_peak,
        dc=decoded.dc,
    )
    warnings = [f"{path}: {decoded.warning}"] if decoded.warning else []
    warnings += [f"{path}: {item['message']}" for item in decoded.signal if "message" in item]
    if readings["dc_offset"] > DC_WARN_THRESHOLD:
        warnings.append(dc_warning(path, readings["dc_offset"]))
    return rows, readings, warnings


def _curves(
    energy: np.ndarray,
    boundaries: np.ndarray,
    *,
    segment_peak: np.ndarray,
    dynamics,
    sample_rate: float,
    maxima: dict,
    true_peak: float,
    sample_peak: float,
    dc: np.ndarray,
) -> tuple[list[dict], dict]:
    """Rows and readings from the per-segment sums (one copy for both front ends)."""
    lengths = np.diff(boundaries).astype(np.float64)
    n = energy.shape[0]

    def windows(count: int) -> np.ndarray:
        """LUFS of the window of ``count`` segments ending at each segment (NaN before)."""
        out = np.full(n, np.nan)
        if n >= count:
            sums = sliding_window_view(energy, count).sum(axis=-1)
            spans = sliding_window_view(lengths, count).sum(axis=-1)
            with np.errstate(divide="ignore"):
                out[count - 1 :] = -0.691 + 10.0 * np.log10(sums / spans)
        return out

    momentary = windows(_MOMENTARY_SEGMENTS)
    short_term = windows(_SHORT_TERM_SEGMENTS)
    # PSR and its median exactly as the cloud's curves and metrics have them.
    psr = np.full(n, np.nan)
    if n >= _SHORT_TERM_SEGMENTS:
        psr[_SHORT_TERM_SEGMENTS - 1 :] = dynamics.psr_db
    with np.errstate(divide="ignore"):
        segment_db = 20.0 * np.log10(np.asarray(segment_peak, dtype=np.float64))
    rows = [
        {
            "time_s": round(float(boundaries[k + 1]) / sample_rate, 4),
            "momentary_lufs": _finite(momentary[k]),
            "short_term_lufs": _finite(short_term[k]),
            "psr_db": _finite(psr[k]),
            "true_peak_dbtp": _finite(segment_db[k]),
        }
        for k in range(n)
    ]
    integrated, lra = loudness_from_energy(energy, boundaries)
    clean_peak = _db(dynamics.true_peak)
    readings = {
        "integrated_lufs": integrated,
        "lra_lu": lra,
        **{key: maxima.get(key) for key in WINDOW_MAXIMA_KEYS},
        "true_peak_dbtp": _db(true_peak),
        "sample_peak_dbfs": _db(sample_peak),
        "plr_db": None if integrated is None or clean_peak is None else clean_peak - integrated,
        "psr_median_db": song_dynamics_metrics(dynamics)["psr_median_db"],
        "dc_offset": float(np.max(np.abs(dc))) if np.size(dc) else 0.0,
    }
    return rows, readings


def cloud_curves(metadata: dict, *, path: str) -> tuple[list[dict], dict]:
    """The rows and readings a Song cloud's metadata stores (see the module docs).

    Raises
    ------
    ExtractError
        A timeline cloud, or a Song cloud without loudness curves: the audio is needed.
    """
    if metadata.get("mode") != "song":
        raise ExtractError(
            f"a {metadata.get('mode', 'unknown')} cloud stores no loudness curves; "
            "give the song's audio file",
            path=path,
        )
    curves = metadata.get("loudness")
    if not isinstance(curves, dict) or not curves.get("rate_hz"):
        raise ExtractError(
            "this cloud stores no loudness curves (written before they were added); "
            "give the song's audio file",
            path=path,
        )
    try:
        rate = float(curves["rate_hz"])
        momentary_start = float(curves["momentary_start_s"])
        short_start = float(curves["short_term_start_s"])
        # Value i is centred on start + i / rate and the first window starts at 0, so each
        # window ends half a window (= start) later. A track shorter than a window has one
        # value for the whole track, which is no 400 ms or 3 s reading: left out.
        series = {
            "momentary_lufs": (momentary_start, MOMENTARY_S, curves["momentary_lufs"]),
            "short_term_lufs": (short_start, SHORT_TERM_S, curves["short_term_lufs"]),
            "psr_db": (short_start, SHORT_TERM_S, curves["psr_db"]),
        }
        by_time: dict[float, dict] = {}
        for column, (start, window_s, values) in series.items():
            if start < window_s / 2 - 1e-6:
                continue
            for i, value in enumerate(values):
                time_s = round(2.0 * start + i / rate, 4)
                row = by_time.setdefault(time_s, dict.fromkeys(CURVE_COLUMNS))
                row["time_s"] = time_s
                row[column] = None if value is None else float(value)
    except (KeyError, TypeError, ValueError) as exc:
        raise ExtractError(
            f"the cloud's loudness curves are malformed ({exc})", path=path
        ) from None
    metrics = metadata.get("metrics") or {}
    readings = {key: _finite(metrics.get(key)) for key, _unit, _time in _SUMMARY}
    for _key, _unit, time_key in _SUMMARY:
        if time_key is not None:
            readings[time_key] = _finite(metrics.get(time_key))
    return [by_time[t] for t in sorted(by_time)], readings


def summary_path(csv_path: str) -> str:
    """Where the summary table goes: ``NAME-summary.csv`` beside ``NAME.csv``."""
    stem, extension = os.path.splitext(csv_path)
    return f"{stem}-summary{extension or '.csv'}"


def _is_cloud(path: str) -> bool:
    with open(path, "rb") as handle:
        return handle.read(4) == b"ply\n"


def write_loudness_csv(
    source: str, csv_path: str | None, *, strict: bool = False
) -> tuple[list[dict], dict, list[str]]:
    """Read ``source`` (audio or a Song cloud) and, with ``csv_path``, write the curves there
    and the summary beside it (:func:`summary_path`), each atomically.

    Returns
    -------
    rows, readings
        As :func:`audio_curves`.
    warnings : list of str
        ``<source>: <message>`` lines: a truncated file, a large DC offset removed, or the
        warnings a cloud carries.

    Raises
    ------
    ExtractError
        Unreadable input, a cloud without curves, an output that is an input, or a failed
        write; nothing is written then.
    """
    check_regular_input(source, what="input")
    if csv_path is not None:
        summary = summary_path(csv_path)
        for output in (csv_path, summary):
            check_output_path(output, inputs=[source], extensions=(".csv",), flag="--csv")
    if _is_cloud(source):
        metadata = read_ply_metadata(source)
        rows, readings = cloud_curves(metadata, path=source)
        warnings = warning_lines(metadata)
    else:
        rows, readings, warnings = file_curves(source, strict=strict)
    if csv_path is not None:
        write_csv(csv_path, CURVE_COLUMNS, rows)
        write_csv(summary, SUMMARY_COLUMNS, _summary_rows(readings))
    return rows, readings, warnings


def _summary_rows(readings: dict) -> list[dict]:
    return [
        {
            "reading": key,
            "value": readings.get(key),
            "unit": unit,
            "time_s": readings.get(time_key) if time_key else None,
        }
        for key, unit, time_key in _SUMMARY
    ]


def add_parser(commands) -> argparse.ArgumentParser:
    """The ``loudness`` subcommand's parser, added to ``commands`` (argparse subparsers)."""
    parser = commands.add_parser(
        "loudness",
        help="a song's loudness curves every 100 ms (CSV) and its EBU Mode readings",
        description="Momentary, short-term, PSR and true peak every 100 ms of one song, and "
        "its integrated loudness, LRA, true peak and maximum momentary and short-term "
        "loudness (at any window position, with the time a meter shows them). Reads an "
        "audio file, or a Song-mode PLY that stores its curves.",
    )
    parser.add_argument("input", help="audio file, or a Song-mode PLY with loudness curves")
    parser.add_argument(
        "--csv",
        help="write the curves here (.csv, one row per 100 ms) and the whole-track readings "
        "beside it as NAME-summary.csv",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help="refuse truncated or corrupt audio instead of using what decodes (with a warning)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no 'wrote' summaries on stderr")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    return parser


def _format(value: float | None, unit: str) -> str:
    return "n/a" if value is None else f"{value:.1f} {unit}"


def run(args: argparse.Namespace, *, say) -> int:
    """The ``loudness`` subcommand: the readings on stdout, one a line; warnings and
    ``wrote`` lines on stderr (through ``say``)."""
    rows, readings, warnings = write_loudness_csv(args.input, args.csv, strict=args.strict)
    for line in warnings:
        say(f"warning: {line}")
    for key, unit, time_key in _SUMMARY:
        line = f"{key:<20} {_format(readings.get(key), unit)}"
        if time_key and readings.get(time_key) is not None:
            line += f" at {readings[time_key]:.3f} s"
        print(line)
    if args.csv and not args.quiet:
        say(f"wrote {args.csv} ({len(rows)} rows, one per 100 ms)")
        say(f"wrote {summary_path(args.csv)} ({len(_SUMMARY)} readings)")
    return 0
