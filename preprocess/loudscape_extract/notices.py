"""Warnings about an input that travel with its cloud: the metadata's ``warnings`` array.

Each warning is ``{"kind": str, "message": str}`` (docs/FORMAT.md, "Warnings"); in Timeline
mode each ``songs[i]`` carries its own and the top-level array repeats them with ``"path"``.
``message`` is one line without the file name: whoever shows it prefixes the file. The same
lines are printed on stderr as ``warning: <file>: <message>`` when the cloud is written.
"""

from __future__ import annotations

import math

import numpy as np

from loudscape_extract.dynamics import DC_WARN_THRESHOLD, dc_message

__all__ = [
    "CANCEL_WARN_DB",
    "CLIP_LEVEL",
    "CLIP_RUN",
    "KINDS",
    "ClipRuns",
    "cancel_notice",
    "clip_notice",
    "decode_notice",
    "notice",
    "timeline_warnings",
    "track_warnings",
    "warning_lines",
    "warnings_problem",
]

#: The kinds written so far; readers show any kind, new ones may be added.
KINDS = ("truncated", "corrupt", "dc_offset", "channels_cancel", "clipping")

#: The mono mix this far (or further) below the channels' mean energy is reported. Two
#: uncorrelated channels of equal level mix to -3 dB, identical ones to 0 dB, one silent
#: channel to -3 dB; -20 dB needs a channel correlation of -0.98 or below (99 % of the energy
#: cancels), which no ordinary stereo mix reaches but one channel with its polarity flipped does.
CANCEL_WARN_DB = 20.0
#: A sample at or beyond this magnitude is at full scale (int16's 32767/32768 is 0.99997).
CLIP_LEVEL = 0.9999
#: This many consecutive full-scale samples on a channel count as one clipped run.
CLIP_RUN = 3


class ClipRuns:
    """Runs of :data:`CLIP_RUN` or more consecutive samples at or beyond :data:`CLIP_LEVEL`
    on each channel, counted across consecutive blocks."""

    def __init__(self, channels: int) -> None:
        self.tail = np.zeros((CLIP_RUN, channels), dtype=bool)
        self.runs = 0
        self.samples = 0
        self.first: int | None = None

    def feed(self, start: int, samples: np.ndarray, *, peak: float | None = None) -> None:
        """Count the runs of ``samples`` (the block from sample ``start``); ``peak``, the
        block's largest absolute sample when the caller has it, skips a block below full
        scale at once."""
        if peak is not None and peak < CLIP_LEVEL:
            self.tail[:] = False
            return
        at = np.abs(samples) >= CLIP_LEVEL
        if not at.any():
            self.tail[:] = False
            return
        m = np.concatenate([self.tail, at])
        # A run reaches CLIP_RUN samples at i: the CLIP_RUN samples up to i are at full
        # scale and the one before them is not.
        reach = ~m[:-CLIP_RUN]
        inside = np.ones_like(reach)
        for k in range(1, CLIP_RUN + 1):
            inside &= m[k : m.shape[0] - CLIP_RUN + k]
        reach &= inside
        self.runs += int(reach.sum())
        # Samples that belong to a run of CLIP_RUN or more (counted where the run is seen).
        self.samples += int(inside.sum()) + (CLIP_RUN - 1) * int(reach.sum())
        if self.first is None and reach.any():
            row = int(np.argmax(reach.any(axis=1)))
            self.first = start + row - (CLIP_RUN - 1)
        self.tail = m[-CLIP_RUN:]

    def first_s(self, sample_rate: int) -> float | None:
        return None if self.first is None else max(self.first, 0) / sample_rate


def notice(kind: str, message: str) -> dict:
    """One warning object; ``message`` is made one line."""
    return {"kind": kind, "message": " ".join(str(message).split())}


def decode_notice(text: str) -> dict | None:
    """The decoder's note on a damaged file (:attr:`Audio.warning`) as a warning, or None.

    ``corrupt`` for mid-stream damage (pages failing their CRC, a decoder error before the end,
    ``corrupt audio: ...``), ``truncated`` when less decoded than the container promises or
    the stream's end is missing."""
    if not text:
        return None
    ends = ("the file promises", "last page", "end-of-stream")
    truncated = not text.startswith("corrupt") and any(end in text for end in ends)
    return notice("truncated" if truncated else "corrupt", text)


def cancel_notice(mono_energy: float, channel_energy: float) -> dict | None:
    """``channels_cancel`` when the mono mix's mean square is :data:`CANCEL_WARN_DB` or more
    below the channels' mean (None otherwise, and for silence)."""
    if not channel_energy > 0:
        return None
    drop = math.inf if mono_energy <= 0 else 10.0 * math.log10(channel_energy / mono_energy)
    if drop < CANCEL_WARN_DB:
        return None
    figure = "entirely" if math.isinf(drop) else f"{drop:.1f} dB"
    return notice(
        "channels_cancel",
        f"the channels cancel in the mono mix: it is {figure} below the channels' mean level "
        "(a channel in opposite polarity?); the points are drawn from the mono mix, the "
        "loudness metrics measure the channels",
    )


def clip_notice(runs: int, clipped_samples: int, first_s: float | None) -> dict | None:
    """``clipping`` when at least one run of :data:`CLIP_RUN` full-scale samples was found."""
    if runs <= 0:
        return None
    when = "" if first_s is None else f", the first at {first_s:.3f} s"
    return notice(
        "clipping",
        f"clipped: {runs} run(s) of {CLIP_RUN} or more consecutive samples at or beyond full "
        "scale "
        f"({clipped_samples} samples in runs{when})",
    )


def track_warnings(*, decode_warning: str, metrics: dict, signal: list | tuple = ()) -> list:
    """Every warning about one track, in a fixed order: the decode problem, the DC offset
    (``metrics["dc_offset"]`` over :data:`DC_WARN_THRESHOLD`), then ``signal`` (channel
    cancellation, clipping: found while decoding)."""
    out = []
    decoded = decode_notice(decode_warning)
    if decoded:
        out.append(decoded)
    offset = metrics.get("dc_offset") or 0.0
    if offset > DC_WARN_THRESHOLD:
        out.append(notice("dc_offset", dc_message(offset)))
    out += [dict(item) for item in signal]
    return out


def timeline_warnings(songs: list) -> list:
    """The top-level array of a timeline: each song's warnings with its ``path``."""
    return [{**item, "path": song["path"]} for song in songs for item in song.get("warnings", [])]


def warning_lines(metadata: dict) -> list[str]:
    """``<file>: <message>`` for each warning of a cloud's metadata, as every reader shows
    them: the song's path (timeline: the warning's ``path``; song: ``source.path``)."""
    items = metadata.get("warnings")
    if not isinstance(items, list):
        return []
    source = metadata.get("source") if isinstance(metadata.get("source"), dict) else {}
    lines = []
    for item in items:
        if isinstance(item, dict):
            where = item.get("path") or source.get("path") or "?"
            lines.append(f"{where}: {item.get('message', '')}")
    return lines


def warnings_problem(value: object, *, with_path: bool = False) -> str:
    """Why ``value`` is not a valid ``warnings`` array (``""`` when it is)."""
    if not isinstance(value, list):
        return f" must be an array, found {type(value).__name__}"
    for index, item in enumerate(value):
        if not isinstance(item, dict):
            return f"[{index}] must be an object"
        keys = ("kind", "message", "path") if with_path else ("kind", "message")
        for key in keys:
            if not isinstance(item.get(key), str):
                return f"[{index}].{key} must be a string"
        if "\n" in item["message"]:
            return f"[{index}].message must be one line"
    return ""
