"""Progress: per-stage lines on stderr for people, and JSON lines for programs.

``Progress`` prints a line a stage on stderr when it is a terminal.
``loudscape-extract song IN -o OUT --progress json`` (``JsonProgress``) prints on stdout, one
object a line::

    {"stage": "decode", "fraction": 0.0, "message": "decoding IN"}
    {"stage": "spectrogram", "fraction": 0.15, "message": "spectrogram"}
    ...
    {"stage": "hpss", "fraction": 0.31, "message": "161020 points so far",
     "points": {"path": "/abs/dir/.OUT.points-4242", "rows": 161020,
                "axes": {...}, "mode": "song", "freq_scale": "linear"}}
    ...
    {"done": "OUT"}

and on failure ``{"error": "..."}`` as its last line (the usual error line still goes to stderr).

Points while extracting: the points are made before the loudness pass, and each block's rows
(5 little-endian float32 a row: x y z scalar hp, exactly the PLY body's rows in its order) are
appended to a hidden body file beside the output, ``.<output name>.points-<pid>``. After a
block is in (flushed), a line with ``points`` says where the file is and how many complete
rows it holds (``rows``, which only grows, the last line's equal to the file's
``point_count``); ``axes`` is the final file's ``axes`` metadata object, so a reader can draw
the rows at once in their final place. The lines come at most every 0.2 s, and always after
the last block. The body file is removed when the extractor ends (a reader that cannot open
it any more ignores the line); the PLY itself is written as before.

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
(song.py's order, measured on a 3-minute 44.1 kHz stereo song: the second decoding pass, with
the loudness and true-peak filters, takes most of it); they only grow. A ``points`` line's
fraction moves through the ``hpss`` stage as the frames are done.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from typing import TextIO

from loudscape_extract.version import PROG

__all__ = ["STAGES", "JsonProgress", "JsonTimelineProgress", "PointsSoFar", "Progress"]


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
    ("spectrogram", "spectrogram", 0.15),
    ("building points", "points", 0.2),
    ("harmonic-percussive", "hpss", 0.2),
    ("dynamics and loudness", "loudness", 0.7),
    ("frame features", "frame features", 0.98),
    ("writing", "write", 0.98),
    ("done", "done", 1.0),
)


@dataclass(frozen=True)
class PointsSoFar:
    """Song-mode points written so far to the body file (see the module's description).

    Attributes
    ----------
    path : str
        Absolute path of the body file.
    rows : int
        Complete rows in it.
    axes : dict
        The final cloud's ``axes`` metadata object.
    freq_scale : str
    share : float
        Share of the track's frames done, in [0, 1].
    """

    path: str
    rows: int
    axes: dict
    freq_scale: str
    share: float


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

    def points(self, update: PointsSoFar) -> None:
        """A ``points`` line: stage ``hpss``, the fraction moving through that stage."""
        names = [stage for _, stage, _ in STAGES]
        at = names.index("hpss")
        low, high = STAGES[at][2], STAGES[at + 1][2]
        self.stage = "hpss"
        self.fraction = max(self.fraction, round(low + (high - low) * update.share, 4))
        self.emit(
            {
                "stage": self.stage,
                "fraction": self.fraction,
                "message": f"{update.rows} points so far",
                "points": {
                    "path": update.path,
                    "rows": update.rows,
                    "axes": update.axes,
                    "mode": "song",
                    "freq_scale": update.freq_scale,
                },
            }
        )

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
