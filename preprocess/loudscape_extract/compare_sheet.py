"""The comparison's outputs: a sheet (PNG or PDF), a CSV table and a JSON summary.

The sheet has, on one page: the aligned short-term loudness curves of every version on the first
version's clock (as recorded and at matched loudness), the difference of each version's
long-term average spectrum to the first's in 1/3-octave bands at matched loudness, and the
table of metrics with each version's offset, matching gain and differences to the first.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np

from loudscape_extract.compare import METRIC_KEYS, THIRD_OCTAVE_HZ, Version
from loudscape_extract.csv_table import write_csv
from loudscape_extract.errors import ExtractError
from loudscape_extract.normalization import SERVICES
from loudscape_extract.paths import atomic_output

__all__ = ["CSV_COLUMNS", "summary_json", "write_compare_csv", "write_sheet"]

#: Labels with units, as the sheet's table and the CSV's header say them.
LABELS = {
    "integrated_lufs": "Integrated\n(LUFS)",
    "lra_lu": "LRA\n(LU)",
    "true_peak_dbtp": "True peak\n(dBTP)",
    "max_momentary_lufs": "Max mom.\n(LUFS)",
    "max_short_term_lufs": "Max short-t.\n(LUFS)",
    "plr_db": "PLR\n(dB)",
    "psr_median_db": "PSR median\n(dB)",
    "dr_db": "DR\n(dB)",
}
CSV_COLUMNS = (
    "version",
    "path",
    "offset_s",
    "alignable",
    "alignment_confidence",
    "match_gain_db",
    *METRIC_KEYS,
    *(f"{key}_diff" for key in METRIC_KEYS),
    *(f"streaming_{service.key}_db" for service in SERVICES),
    "warnings",
)


def _name(path: str) -> str:
    return os.path.basename(path) or path


def _rows(versions: list[Version]) -> list[dict]:
    first = versions[0].metrics
    rows = []
    for i, v in enumerate(versions):
        row = {
            "version": chr(ord("A") + i),
            "path": v.path,
            "offset_s": round(v.alignment.offset_s, 6) + 0.0 if v.alignment.alignable else None,
            "alignable": v.alignment.alignable,
            "alignment_confidence": round(v.alignment.confidence, 3),
            "match_gain_db": v.match_gain_db,
        }
        for key in METRIC_KEYS:
            value, base = v.metrics.get(key), first.get(key)
            row[key] = value
            row[f"{key}_diff"] = None if value is None or base is None else value - base
        for service in SERVICES:
            row[f"streaming_{service.key}_db"] = v.metrics.get("streaming", {}).get(service.key)
        row["warnings"] = "; ".join(v.warnings)
        rows.append(row)
    return rows


def write_compare_csv(path: str, versions: list[Version]) -> int:
    """One row a version (A, B, ...): offset, matching gain, metrics and their differences to A."""
    return write_csv(path, CSV_COLUMNS, _rows(versions))


def summary_json(versions: list[Version], *, match: str) -> str:
    """The comparison as JSON: for each version its path, ``offset_s`` against the first,
    ``match_gain_db``, the alignment (confidence, time map) and the metrics."""
    return json.dumps(
        {"match": match, "versions": [v.to_json() for v in versions]}, indent=2, allow_nan=False
    )


def _fmt(value, digits: int = 1, signed: bool = False) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    value = round(float(value), digits) + 0.0  # no "-0.0"
    return f"{value:+.{digits}f}" if signed else f"{value:.{digits}f}"


def write_sheet(path: str, versions: list[Version], *, match: str) -> None:
    """The one-page sheet, PNG or PDF by ``path``'s extension, written atomically.

    Raises
    ------
    ExtractError
        matplotlib is missing (the ``report`` extra), or another extension than .png / .pdf.
    """
    extension = os.path.splitext(path)[1].lower()
    if extension not in (".png", ".pdf"):
        raise ExtractError("the comparison sheet is written as .png or .pdf", path=path)
    try:
        import matplotlib
    except ImportError as exc:
        raise ExtractError(
            "the comparison sheet needs matplotlib: pip install 'loudscape-extract[report]'"
        ) from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(11.69, 8.27), dpi=110)  # A4 landscape
    grid = fig.add_gridspec(2, 2, height_ratios=(1.15, 1.0), hspace=0.32, wspace=0.2)
    match_text = "matched to the quietest version" if match == "quietest" else f"matched to {match}"
    fig.suptitle(
        f"Comparison of {len(versions)} versions, aligned to A and {match_text}",
        fontsize=13,
        x=0.06,
        ha="left",
    )

    ax = fig.add_subplot(grid[0, 0])
    for i, v in enumerate(versions):
        level = np.where(np.isfinite(v.short_term_lufs), v.short_term_lufs, np.nan)
        gain = v.match_gain_db or 0.0
        letter = chr(ord("A") + i)
        ax.plot(
            v.short_term_times_s,
            level + gain,
            color=f"C{i}",
            linewidth=1.2,
            label=f"{letter} {_fmt(gain, 1, True)} dB"
            + ("" if v.alignment.alignable else " (not aligned)"),
        )
    ax.set_xlabel("time on A's clock (s)")
    ax.set_ylabel("short-term loudness,\nmatched (LUFS)")
    ax.set_title("Aligned short-term loudness (3 s)", fontsize=10, loc="left")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    low = [np.nanpercentile(v.short_term_lufs[np.isfinite(v.short_term_lufs)], 2)
           + (v.match_gain_db or 0.0) for v in versions
           if np.isfinite(v.short_term_lufs).any()]  # fmt: skip
    if low:
        ax.set_ylim(bottom=min(low) - 3)

    ax = fig.add_subplot(grid[0, 1])
    centres = np.asarray(THIRD_OCTAVE_HZ, dtype=float)
    ax.axhline(0.0, color="0.35", linewidth=0.8)
    for i, v in enumerate(versions[1:], start=1):
        ax.semilogx(
            centres,
            v.spectrum_difference_db,
            "o-",
            color=f"C{i}",
            markersize=3,
            linewidth=1.2,
            label=f"{chr(ord('A') + i)} - A" + ("" if v.alignment.alignable else " (other music)"),
        )
    ax.set_xlabel("1/3-octave band (Hz)")
    ax.set_ylabel("difference at matched\nloudness (dB)")
    ax.set_title("Tonal balance against A", fontsize=10, loc="left")
    ax.set_xticks([31.5, 63, 125, 250, 500, 1000, 2000, 4000, 8000, 16000])
    ax.set_xticklabels(["31", "63", "125", "250", "500", "1k", "2k", "4k", "8k", "16k"])
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)

    ax = fig.add_subplot(grid[1, :])
    ax.axis("off")
    rows = _rows(versions)
    header = ["", "file", "offset (s)\n(confidence)", "match\ngain (dB)"]
    header += [LABELS[k] for k in METRIC_KEYS]
    cells = []
    for row, v in zip(rows, versions, strict=True):
        if v.alignment.alignable:
            offset = f"{_fmt(v.alignment.offset_s, 3, True)} ({100 * v.alignment.confidence:.0f} %)"
            if len(v.alignment.segments) > 1:
                offset += f", {len(v.alignment.segments)} parts"
        else:
            offset = "not alignable"
        line = [row["version"], _name(v.path)[:28], offset, _fmt(row["match_gain_db"], 1, True)]
        for key in METRIC_KEYS:
            value, diff = row[key], row[f"{key}_diff"]
            text = _fmt(value)
            if row["version"] != "A" and diff is not None:
                text += f" ({_fmt(diff, 1, True)})"
            line.append(text)
        cells.append(line)
    table = ax.table(cellText=cells, colLabels=header, loc="upper center", cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    table.scale(1.0, 1.5)
    for (r, _c), cell in table.get_celld().items():
        if r == 0:
            cell.set_text_props(weight="bold")
            cell.set_height(cell.get_height() * 2.0)
    table.auto_set_column_width(list(range(len(header))))
    ax.set_title("Metrics (difference to A in brackets)", fontsize=10, loc="left")
    fig.text(
        0.06,
        0.04,
        "offset: how much later a version's music starts than A's (negative: earlier); "
        "parts: a time map with that many stretches (a cut or an edit).\n"
        "match gain: the gain each version plays at in the matched curves and spectra. "
        "Confidence: the share of A's music found in the version times the envelopes' "
        "correlation.",
        fontsize=7.5,
        color="0.3",
        va="bottom",
    )
    warned = [
        f"{chr(ord('A') + i)} ({_name(v.path)}): {line}"
        for i, v in enumerate(versions)
        for line in v.warnings
    ]
    if warned:
        text = "warning: " + " | ".join(warned)
        fig.text(0.06, 0.015, text[:300], fontsize=7.5, color="#b00000", va="bottom")
    try:
        with atomic_output(path) as temporary:
            fig.savefig(temporary, format=extension[1:])
    finally:
        plt.close(fig)
