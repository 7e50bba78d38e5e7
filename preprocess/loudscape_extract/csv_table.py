"""CSV tables as the extractor writes them: one header row, atomic, safe to open in a spreadsheet.

Every CSV the project writes goes through :func:`write_csv`. Text cells that a spreadsheet
would read as a formula (a title such as ``=HYPERLINK(...)``, ``+cmd|' /C calc'!A0`` or
``@SUM(...)``) get a leading single quote, as the OWASP guidance on CSV injection advises:
Excel, LibreOffice and Google Sheets then show the text instead of running it. Numbers are
written as numbers (a negative loudness stays ``-14.2``); ``None`` is an empty cell.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Sequence

from loudscape_extract.paths import atomic_output

__all__ = ["FORMULA_STARTS", "csv_cell", "write_csv"]

#: A text cell starting with one of these is read as a formula by some spreadsheet (OWASP:
#: equals, plus, minus, at, tab, carriage return; line feed for good measure).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r", "\n")


def csv_cell(value: object, *, decimals: int = 4) -> object:
    """One cell as written: floats rounded to ``decimals``, ``None`` empty, formula-like text
    quoted.

    Examples
    --------
    >>> csv_cell("=HYPERLINK(\\"http://x\\")")
    '\\'=HYPERLINK("http://x")'
    >>> csv_cell(-14.23456), csv_cell(None), csv_cell("Song 2"), csv_cell(3)
    (-14.2346, '', 'Song 2', 3)
    """
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return round(value, decimals)
    if isinstance(value, int):
        return value
    text = str(value)
    return "'" + text if text.startswith(FORMULA_STARTS) else text


def write_csv(path: str, columns: Sequence[str], rows: Iterable[dict]) -> int:
    """Write ``rows`` (dicts keyed by ``columns``; missing keys are empty) to ``path``
    atomically, every cell through :func:`csv_cell`; returns the number of rows.

    Raises
    ------
    ExtractError
        The file cannot be written (:func:`atomic_output` names it and the reason).
    """
    count = 0
    with (
        atomic_output(path) as temporary,
        open(temporary, "w", newline="", encoding="utf-8") as handle,
    ):
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([csv_cell(row.get(column)) for column in columns])
            count += 1
    return count
