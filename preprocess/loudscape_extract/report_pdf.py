"""The song report's page: one A4 sheet, as PDF (text that can be copied and searched) or PNG.

From top to bottom: the song and its source; the verdict against the delivery target; the
readings (integrated loudness, LRA, true and sample peak, max momentary and short-term
loudness with their times, PLR, PSR median, DR, true-peak overs) beside each streaming
service's playback gain and level as heard (chevrons: each one 2 dB turned down or up, as
Loudness Penalty shows them); momentary and short-term loudness against time with the
integrated level, the target, the maxima and the true-peak overs; PSR against time; the
short-term loudness histogram with the LRA band; notes (warnings, what the input lacks); the
method.

:func:`draw_page` takes plain data (:func:`loudscape_extract.song_report.song_page`), so this
module knows nothing of how the song was measured.
"""

from __future__ import annotations

import math
import os
import textwrap
import time

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.paths import atomic_output
from loudscape_extract.version import GENERATOR

__all__ = ["PAGE_EXTENSIONS", "draw_page", "lra_band", "minutes", "require_matplotlib"]

#: What a page may be written as.
PAGE_EXTENSIONS = (".pdf", ".png")
#: A4 portrait, inches.
_PAGE = (8.27, 11.69)
_INK, _SOFT, _RULE = "0.12", "0.45", "0.8"
_MOMENTARY, _SHORT_TERM = "#8fb8de", "#1f4e89"
_OVER_0, _OVER_1 = "#c0392b", "#f0a35e"
_PASS, _FAIL = "#1e7b34", "#b03a2e"
_DOWN, _UP = "#c0392b", "#1e7b34"
_CHEVRON_DB = 2.0


def require_matplotlib() -> None:
    """Raise :class:`ExtractError` saying how to install matplotlib when it is missing (the
    reports draw with it; it is the ``report`` extra), before any work is done."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise ExtractError(
            "matplotlib is not installed: pip install 'loudscape-extract[report]' "
            f"(needed to draw reports; {exc})"
        ) from exc


def minutes(seconds: float) -> str:
    """``m:ss.s`` (``h:mm:ss`` from an hour).

    >>> minutes(83.44), minutes(3725.0)
    ('1:23.4', '1:02:05')
    """
    if seconds >= 3600:
        hours, rest = divmod(int(round(seconds)), 3600)
        return f"{hours}:{rest // 60:02d}:{rest % 60:02d}"
    whole, fraction = divmod(round(seconds, 1), 60)
    return f"{int(whole)}:{fraction:04.1f}"


def lra_band(short_term_lufs: np.ndarray) -> tuple[float, float] | None:
    """The 10th and 95th percentiles of the short-term loudness that EBU Tech 3342 counts
    (above -70 LUFS, and within 20 LU of their power mean): the LRA band drawn on the
    histogram. None when nothing is counted.

    >>> lra_band(np.array([-20.0, -18.0, -16.0, -80.0]))
    (-19.6, -16.2)
    """
    values = short_term_lufs[np.isfinite(short_term_lufs)]
    values = values[values > -70.0]
    if values.size == 0:
        return None
    mean = 10.0 * math.log10(float(np.mean(10.0 ** (values / 10.0))))
    values = values[values > mean - 20.0]
    low, high = np.percentile(values, [10.0, 95.0])
    return round(float(low), 4), round(float(high), 4)


def _curve(curves: dict, key: str, start_key: str) -> tuple[np.ndarray, np.ndarray]:
    values = np.array([np.nan if v is None else v for v in curves[key]], dtype=float)
    times = curves[start_key] + np.arange(values.size) / curves["rate_hz"]
    return times, values


def _dots(values: np.ndarray) -> str | None:
    """A marker for a curve too short to show as a line (a song under a few seconds)."""
    return "o" if np.count_nonzero(np.isfinite(values)) < 5 else None


def _fmt(value, unit: str, digits: int = 1, sign: bool = False) -> str:
    if value is None:
        return "n/a"
    return f"{value:+.{digits}f} {unit}" if sign else f"{value:.{digits}f} {unit}"


def _readings(song: dict) -> list[tuple[str, str]]:
    metrics, curves = song["metrics"], song["curves"] or {}

    def at(key_value, key_time, unit):
        value, when = metrics.get(key_value), metrics.get(key_time)
        text = _fmt(value, unit)
        return text if value is None or when is None else f"{text} at {minutes(when)}"

    dr = metrics.get("dr_db")
    overs = "n/a"
    if "overs_0dbtp_count" in curves:
        overs = (
            f"{curves['overs_0dbtp_count']} runs over 0 dBTP, {curves['overs_1dbtp_count']} over -1"
        )
    return [
        ("Integrated loudness", _fmt(metrics.get("integrated_lufs"), "LUFS")),
        ("Loudness range (LRA)", _fmt(metrics.get("lra_lu"), "LU")),
        ("True peak (max)", _fmt(metrics.get("true_peak_dbtp"), "dBTP", sign=True)),
        ("Sample peak", _fmt(metrics.get("sample_peak_dbfs"), "dBFS", sign=True)),
        ("Max momentary (400 ms)", at("max_momentary_lufs", "max_momentary_s", "LUFS")),
        ("Max short-term (3 s)", at("max_short_term_lufs", "max_short_term_s", "LUFS")),
        ("PLR (peak to loudness)", _fmt(metrics.get("plr_db"), "dB")),
        ("PSR median (3 s)", _fmt(metrics.get("psr_median_db"), "dB")),
        ("DR (TT meter)", "n/a" if dr is None else f"DR{round(dr)} ({dr:.1f} dB)"),
        ("True-peak overs", overs),
    ]


def _header(fig, page: dict) -> float:
    song = page["song"]
    fig.text(0.06, 0.965, "Loudness report", fontsize=17, weight="bold", color=_INK)
    fig.text(0.94, 0.967, GENERATOR, fontsize=8, color=_SOFT, ha="right")
    fig.text(0.06, 0.942, song["name"], fontsize=12, color=_INK)
    facts = []
    if song["duration_s"] is not None:
        facts.append(f"duration {minutes(song['duration_s'])}")
    if song["sample_rate"]:
        facts.append(f"{song['sample_rate'] / 1000:g} kHz")
    if song["channels"]:
        facts.append({1: "mono", 2: "stereo"}.get(song["channels"], f"{song['channels']} ch"))
    facts.append(f"input {song['path']}")
    fig.text(0.06, 0.925, "   ".join(facts)[:130], fontsize=8, color=_SOFT)
    verdict = page["verdict"]
    if verdict is not None:
        colour = _PASS if verdict["passed"] else _FAIL
        word, _, rest = verdict["text"].partition(" ")
        fig.text(
            0.06,
            0.893,
            f" {word} ",
            fontsize=12,
            weight="bold",
            color="white",
            bbox={"boxstyle": "round,pad=0.3", "facecolor": colour, "edgecolor": colour},
        )
        _wrapped(fig, 0.15, 0.9, rest, width=98, size=8.5, colour=_INK, step=0.013)
    else:
        fig.text(
            0.06,
            0.893,
            "No delivery target chosen (--target spotify, --target-lufs -14 --max-true-peak -1)",
            fontsize=8.5,
            color=_SOFT,
        )
    return 0.87


def _wrapped(fig, x, y, text, *, width, size, colour, step):
    for i, line in enumerate(textwrap.wrap(text, width)[:3]):
        fig.text(x, y - i * step, line, fontsize=size, color=colour, va="center")


def _readings_panel(fig, page: dict, rect) -> None:
    ax = fig.add_axes(rect)
    ax.axis("off")
    ax.set_title("Readings", loc="left", fontsize=10, weight="bold", color=_INK)
    rows = _readings(page["song"])
    for i, (label, value) in enumerate(rows):
        y = 1.0 - (i + 0.5) / len(rows)
        ax.text(0.0, y, label, fontsize=9, color=_INK, va="center", transform=ax.transAxes)
        ax.text(0.98, y, value, fontsize=9, color=_INK, va="center", ha="right", weight="bold")
        ax.axhline(y - 0.5 / len(rows), color=_RULE, linewidth=0.5)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)


def _heard_panel(fig, page: dict, rect) -> None:
    ax = fig.add_axes(rect)
    heard = list(page["heard"].values())
    ax.set_title("Playback normalization", loc="left", fontsize=10, weight="bold", color=_INK)
    ax.axis("off")
    n = len(heard) + 1
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    header = 1.0 - 0.5 / n
    for x, text, align in (
        (0.0, "service", "left"),
        (0.46, "target", "right"),
        (0.775, "gain", "right"),
        (1.0, "as heard", "right"),
    ):
        ax.text(x, header, text, fontsize=7.5, color=_SOFT, va="center", ha=align)
    ax.axhline(1.0 - 1.0 / n, color=_SOFT, linewidth=0.6)
    for i, (name, target, gain, level) in enumerate(heard):
        y = 1.0 - (i + 1.5) / n
        ax.text(0.0, y, name, fontsize=8, color=_INK, va="center")
        ax.text(0.46, y, f"{target:.0f}", fontsize=8, color=_SOFT, va="center", ha="right")
        if gain is None:
            ax.text(0.775, y, "n/a", fontsize=8.5, color=_SOFT, va="center", ha="right")
        else:
            count = min(5, math.ceil(abs(gain) / _CHEVRON_DB - 1e-9)) if abs(gain) >= 0.05 else 0
            glyph, colour = ("\u25bc", _DOWN) if gain < 0 else ("\u25b2", _UP)
            ax.text(0.48, y, glyph * count, fontsize=6.5, color=colour, va="center")
            ax.text(0.775, y, f"{gain:+.1f} dB", fontsize=8.5, color=_INK, va="center", ha="right")
            ax.text(
                1.0, y, _fmt(level, "LUFS"), fontsize=8.5, weight="bold", va="center", ha="right"
            )
        ax.axhline(y - 0.5 / n, color=_RULE, linewidth=0.5)


def _time_axis(ax, duration: float) -> None:
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    ax.set_xlim(0.0, max(duration, 1.0))
    ax.xaxis.set_major_locator(MaxNLocator(nbins=10, steps=[1, 1.5, 2, 3, 5, 6, 10]))
    tenths = duration < 20.0  # a short song's ticks are under a second apart
    ax.xaxis.set_major_formatter(
        FuncFormatter(lambda s, _pos: minutes(s) if tenths else minutes(s).split(".")[0])
    )


def _style(ax) -> None:
    ax.grid(True, color=_RULE, linewidth=0.5)
    ax.tick_params(labelsize=7.5, colors=_INK)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def _missing(ax, text: str) -> None:
    ax.text(
        0.5, 0.5, text, ha="center", va="center", fontsize=9, color=_SOFT, transform=ax.transAxes
    )
    ax.set_xticks([])
    ax.set_yticks([])


def _curves_panel(ax, page: dict, duration: float) -> None:
    song, target = page["song"], page["target"]
    metrics, curves = song["metrics"], song["curves"]
    ax.set_title("Loudness against time (BS.1770)", loc="left", fontsize=10, weight="bold")
    if curves is None:
        _missing(ax, "this cloud carries no loudness curves: extract the song again to draw them")
        return
    tm, momentary = _curve(curves, "momentary_lufs", "momentary_start_s")
    ts, short = _curve(curves, "short_term_lufs", "short_term_start_s")
    ax.plot(
        tm,
        momentary,
        color=_MOMENTARY,
        linewidth=0.6,
        label="momentary (400 ms)",
        marker=_dots(momentary),
    )
    ax.plot(
        ts, short, color=_SHORT_TERM, linewidth=1.3, label="short-term (3 s)", marker=_dots(short)
    )
    integrated = metrics.get("integrated_lufs")
    if integrated is not None:
        ax.axhline(
            integrated,
            color=_INK,
            linewidth=0.9,
            linestyle="--",
            label=f"integrated {integrated:.1f} LUFS",
        )
    if target is not None and target["lufs"] is not None:
        low, high = target["lufs"] - target["tolerance_lu"], target["lufs"] + target["tolerance_lu"]
        ax.axhspan(
            low,
            high,
            color=_PASS,
            alpha=0.12,
            linewidth=0,
            label=f"target {target['lufs']:.0f} \u00b1 {target['tolerance_lu']:.1f} LU",
        )
    finite = np.concatenate([momentary[np.isfinite(momentary)], short[np.isfinite(short)]])
    top = float(finite.max()) if finite.size else 0.0
    bottom = float(np.percentile(finite, 2)) if finite.size else -60.0
    low = max(bottom - 4.0, top - 45.0)
    ax.set_ylim(low - 0.25 * (top + 5.0 - low), top + 5.0)  # the lowest quarter: the legend
    for key_value, key_time, colour, name in (
        ("max_momentary_lufs", "max_momentary_s", _MOMENTARY, "max M"),
        ("max_short_term_lufs", "max_short_term_s", _SHORT_TERM, "max S"),
    ):
        value, when = metrics.get(key_value), metrics.get(key_time)
        if value is not None and when is not None:
            ax.plot(
                [when],
                [value],
                marker="v",
                color=colour,
                markeredgecolor=_INK,
                markersize=7,
                linestyle="none",
                zorder=5,
            )
            ax.annotate(
                f"{name} {value:.1f}",
                (when, value),
                xytext=(5, 3),
                textcoords="offset points",
                fontsize=7.5,
                color=_INK,
            )
    for key, colour, label in (
        ("overs_1dbtp", _OVER_1, "true peak over -1 dBTP"),
        ("overs_0dbtp", _OVER_0, "true peak over 0 dBTP"),
    ):
        spans = curves.get(key) or []
        for i, (start, end) in enumerate(spans):
            ax.axvspan(
                start,
                max(end, start + duration / 800.0),
                ymin=0.94,
                ymax=1.0,
                color=colour,
                linewidth=0,
                label=None if i else label,
            )
    ax.set_ylabel("LUFS", fontsize=8)
    _time_axis(ax, duration)
    ax.legend(loc="lower left", fontsize=7, ncol=3, framealpha=0.9)


def _psr_panel(ax, page: dict, duration: float) -> None:
    song = page["song"]
    ax.set_title(
        "PSR against time (true peak minus short-term loudness, 3 s)",
        loc="left",
        fontsize=10,
        weight="bold",
    )
    if song["curves"] is None:
        _missing(ax, "no PSR curve in this cloud")
        return
    times, psr = _curve(song["curves"], "psr_db", "short_term_start_s")
    ax.plot(times, psr, color="#6c3483", linewidth=1.0, marker=_dots(psr))
    median = song["metrics"].get("psr_median_db")
    if median is not None:
        ax.axhline(median, color=_INK, linestyle="--", linewidth=0.8)
        ax.annotate(
            f"median {median:.1f} dB",
            (1.0, median),
            xycoords=("axes fraction", "data"),
            xytext=(-4, 3),
            textcoords="offset points",
            ha="right",
            fontsize=7.5,
        )
    finite = psr[np.isfinite(psr)]
    if finite.size:
        ax.set_ylim(max(0.0, float(finite.min()) - 2.0), float(finite.max()) + 2.0)
    ax.set_ylabel("dB", fontsize=8)
    _time_axis(ax, duration)


def _histogram_panel(ax, page: dict) -> None:
    song = page["song"]
    metrics = song["metrics"]
    ax.set_title("Short-term loudness histogram", loc="left", fontsize=10, weight="bold")
    if song["curves"] is None:
        _missing(ax, "no short-term curve in this cloud")
        return
    _, short = _curve(song["curves"], "short_term_lufs", "short_term_start_s")
    values = short[np.isfinite(short) & (short > -70.0)]
    if values.size == 0:
        _missing(ax, "no short-term loudness above -70 LUFS")
        return
    band = lra_band(short)
    if band is not None:
        lra = metrics.get("lra_lu")
        label = "LRA band (10th-95th percentile)" + ("" if lra is None else f", {lra:.1f} LU")
        ax.axvspan(band[0], band[1], color="#f5d76e", alpha=0.45, linewidth=0, label=label)
    low, high = math.floor(values.min()), math.ceil(values.max())
    bins = np.arange(low, high + 0.5, 0.5) if high > low else 10
    ax.hist(values, bins=bins, color=_SHORT_TERM, alpha=0.85)
    integrated = metrics.get("integrated_lufs")
    if integrated is not None:
        ax.axvline(
            integrated,
            color=_INK,
            linestyle="--",
            linewidth=0.9,
            label=f"integrated {integrated:.1f} LUFS",
        )
    ax.set_xlabel("short-term loudness (LUFS)", fontsize=8)
    ax.set_ylabel("windows (100 ms apart)", fontsize=8)
    ax.legend(loc="upper left", fontsize=7)


def _notes_panel(fig, page: dict, rect) -> None:
    ax = fig.add_axes(rect)
    ax.axis("off")
    ax.set_title("Notes", loc="left", fontsize=10, weight="bold", color=_INK)
    song = page["song"]
    notes = [f"Warning: {line}" for line in song["warnings"]]
    if song["curves"] is None:
        notes.append("The input cloud carries no loudness curves (written by an older version).")
    metrics = song["metrics"]
    if "max_momentary_lufs" not in metrics or "max_short_term_lufs" not in metrics:
        notes.append(
            "Max momentary and short-term loudness: not among the input's metrics (a cloud "
            "written by an older version); extract the song again for them."
        )
    if not notes:
        notes.append("No warnings about the input.")
    notes.append(
        "Gain: what each service applies at playback (negative turns down); chevrons, one "
        "per 2 dB. Overs: 100 ms segments whose true peak exceeds the level (strip on top)."
    )
    lines = [part for note in notes for part in textwrap.wrap(note, 58)]
    for i, line in enumerate(lines[:14]):
        ax.text(
            0.0, 0.97 - i * 0.075, line, fontsize=7.5, color=_INK, va="top", transform=ax.transAxes
        )


def draw_page(page: dict, output: str) -> None:
    """Draw the report of ``page`` and save it to ``output`` (its extension decides PDF or
    PNG); matplotlib must be installed (the caller checks)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    song = page["song"]
    duration = song["duration_s"] or 0.0
    if song["curves"] is not None and not duration:
        rate = song["curves"]["rate_hz"]
        duration = len(song["curves"]["momentary_lufs"]) / rate
    style = {"pdf.fonttype": 42, "font.family": "DejaVu Sans", "axes.titlepad": 4}
    with plt.rc_context(style):
        fig = plt.figure(figsize=_PAGE)
        try:
            top = _header(fig, page)
            _readings_panel(fig, page, [0.06, top - 0.235, 0.40, 0.215])
            _heard_panel(fig, page, [0.53, top - 0.235, 0.41, 0.215])
            curves = fig.add_axes([0.09, 0.385, 0.85, 0.215])
            _curves_panel(curves, page, duration)
            psr = fig.add_axes([0.09, 0.245, 0.85, 0.095])
            _psr_panel(psr, page, duration)
            hist = fig.add_axes([0.09, 0.06, 0.42, 0.14])
            _histogram_panel(hist, page)
            _notes_panel(fig, page, [0.56, 0.06, 0.38, 0.14])
            for ax in (curves, psr, hist):
                _style(ax)
            made = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
            fig.text(
                0.06,
                0.012,
                "Method: ITU-R BS.1770-4 loudness and true peak (4x oversampled); EBU Tech "
                "3341 momentary and short-term loudness; EBU Tech 3342 LRA;\nPSR over 3 s "
                "windows; TT Dynamic Range. Normalization rules: docs/DYNAMICS.md. "
                f"Made {made}.",
                fontsize=6.5,
                color=_SOFT,
                linespacing=1.4,
            )
            extension = os.path.splitext(output)[1].lower()
            metadata = (
                {"Title": f"Loudness report: {song['name']}", "Creator": GENERATOR}
                if extension == ".pdf"
                else {"Software": GENERATOR}
            )
            with atomic_output(output) as temporary:
                fig.savefig(temporary, format=extension[1:], dpi=150, metadata=metadata)
        finally:
            plt.close(fig)
