"""Progress: per-stage lines on stderr for people, and JSON lines for programs.

``Progress`` prints a line a stage on stderr when it is a terminal.
``loudscape-extract song IN -o OUT --progress json`` (``JsonProgress``) prints on stdout, one
object a line::

    {"stage": "decode", "fraction": 0.0, "message": "decoding IN"}
    {"stage": "spectrogram", "fraction": 0.77, "message": "spectrogram"}
    ...
    {"done": "OUT"}

and on failure ``{"error": "..."}`` as its last line (the usual error line still goes to stderr).

``loudscape-extract timeline ... --progress json`` (``JsonTimelineProgress``) prints one object
a song as each finishes (in the order they finish), then the songs left out for want of a year
and those that failed, then ``done``::

    {"stage": "songs", "fraction": 0.5, "song": "a.flac", "songs_done": 1, "songs_total": 2}
    {"stage": "songs", "fraction": 1.0, "song": "b.flac", "songs_done": 2, "songs_total": 2,
     "failed": "b.flac: silent"}
    {"without_year": ["c.flac"], "failed": {"b.flac": "b.flac: silent"}}
    {"done": "timeline.ply"}

A song's line carries ``failed`` only when it failed. The keys ``done`` and ``error`` appear
only in the last line, as for a song.
The fractions are the share of a typical song's extraction time spent before each stage starts
(the streamed pipeline of stream.py, measured on a 3-minute 44.1 kHz stereo song: the second
decoding pass, with the loudness and true-peak filters, takes most of it); they only grow.
"""

from __future__ import annotations

import json
import sys
import time
from typing import TextIO

from loudscape_extract.version import PROG

__all__ = ["STAGES", "JsonProgress", "JsonTimelineProgress", "Progress"]


class Progress:
    """Per-stage progress lines on stderr, only when enabled (stderr is a TTY and not quiet)."""

    def __init__(self, *, enabled: bool) -> None:
        self.enabled = enabled
        self.start = time.perf_counter()

    def __call__(self, message: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            print(f"{PROG}: [{elapsed:6.2f} s] {message}", file=sys.stderr, flush=True)


#: (message prefix, stage name, fraction of the work done when the stage starts), in order.
STAGES: tuple[tuple[str, str, float], ...] = (
    ("decoding", "decode", 0.0),
    ("dynamics and loudness", "loudness", 0.08),
    ("spectrogram", "spectrogram", 0.77),
    ("frame features", "frame features", 0.79),
    ("building points", "points", 0.80),
    ("harmonic-percussive", "hpss", 0.82),
    ("writing", "write", 0.99),
    ("done", "done", 1.0),
)


class JsonProgress:
    """Progress callback writing one JSON object a line (``stage``, ``fraction``, ``message``).

    Parameters
    ----------
    stream : file, optional
        Where to write (default ``sys.stdout``); flushed after every line.
    """

    def __init__(self, *, stream: TextIO | None = None) -> None:
        self.stream = stream
        self.stage = "start"
        self.fraction = 0.0

    def emit(self, record: dict) -> None:
        stream = self.stream or sys.stdout
        stream.write(json.dumps(record) + "\n")
        stream.flush()

    def __call__(self, message: str) -> None:
        for prefix, stage, fraction in STAGES:
            if message.startswith(prefix):
                self.stage = stage
                self.fraction = max(self.fraction, fraction)
                break
        if self.stage == "done":
            return
        self.emit({"stage": self.stage, "fraction": self.fraction, "message": message})

    def done(self, output: str) -> None:
        """The last line of a successful run: the file written."""
        self.emit({"done": output})

    def error(self, message: str) -> None:
        """The last line of a failed run: the same text as the error line on stderr."""
        self.emit({"error": message})


class JsonTimelineProgress(JsonProgress):
    """Per-song JSON lines of a timeline build (see the module's description).

    Called as the timeline's progress callback, ``(songs_done, songs_total, path)``; the
    failures seen so far are given by ``failed`` (path -> reason) when known.
    """

    def __call__(self, done: int, total: int, path: str, failed: str | None = None) -> None:  # type: ignore[override]
        record = {
            "stage": "songs",
            "fraction": done / total if total else 1.0,
            "song": path,
            "songs_done": done,
            "songs_total": total,
        }
        if failed:
            record["failed"] = failed
        self.emit(record)

    def left_out(self, *, without_year: list[str], failed: dict[str, str]) -> None:
        """The songs the timeline does not hold: without a year, and failed."""
        self.emit({"without_year": list(without_year), "failed": dict(failed)})
