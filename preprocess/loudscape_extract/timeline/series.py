"""The per-frame series a timeline keeps of each song, and the y and z measures drawn from them:
one table that :class:`~loudscape_extract.timeline.frames.SongFrames`, the cache's entries
(order, plausible ranges) and the layout (axis labels, ``--y-measure`` and ``--z-measure``)
all iterate. A new series is one row here and one field of ``SongFrames``.

>>> [series.name for series in SERIES][:3]
['rms_dbfs', 'crest_db', 'loudness_a_db']
>>> y_measure_of("rms").series, y_measure_of("rms").unit
('rms_dbfs', 'dBFS')
"""

from __future__ import annotations

from dataclasses import dataclass

from loudscape_extract.errors import ExtractError

__all__ = [
    "DEFAULT_Y_MEASURE",
    "DEFAULT_Z_MEASURE",
    "Measure",
    "SERIES",
    "Series",
    "Y_MEASURES",
    "Y_MEASURE_TABLE",
    "Z_MEASURES",
    "Z_MEASURE_TABLE",
    "y_measure_of",
    "z_measure_of",
]


@dataclass(frozen=True)
class Series:
    """One per-frame series of a song's non-silent frames (float32, one value a frame).

    Attributes
    ----------
    name : str
        Its field of ``FrameFeatures`` and ``SongFrames``.
    low, high : float
        The plausible range of its finite values (a cache entry outside it is refused). Wide:
        a float file may be +60 dBFS, a frame of one tiny sample -900 dB; they catch garbage,
        not odd music.
    nan_allowed : bool
        Whether a frame may have no value (NaN).
    optional : bool
        The series may be missing from ``FrameFeatures`` (empty: features built without it);
        it is then kept as NaN.
    """

    name: str
    low: float
    high: float
    nan_allowed: bool
    optional: bool = False


#: Every series, in the order of a cache entry's body (docs/FORMAT.md does not cover entries;
#: changing the order needs a new ``CACHE_VERSION``).
SERIES = (
    Series("rms_dbfs", -1000.0, 70.0, False),  # non-silent frames only: always a level
    Series("crest_db", -0.01, 100.0, False),  # peak >= RMS
    Series("loudness_a_db", -1500.0, 100.0, True),
    Series("hp_mean", 0.0, 1.0, True),
    Series("psr_db", -50.0, 200.0, True),  # NaN: the 3 s window is under the gate
    Series("crest_3s_db", -0.01, 200.0, True),
    # BS.1770 loudness of the 400 ms / 3 s block around each frame; NaN where unmeasurable.
    Series("momentary_lufs", -1000.0, 100.0, True, optional=True),
    Series("short_term_lufs", -1000.0, 100.0, True, optional=True),
)


@dataclass(frozen=True)
class Measure:
    """A choice of ``--y-measure`` or ``--z-measure``: the series drawn and its axis.

    Attributes
    ----------
    key : str
        The choice's name on the command line and in the metadata (``axes.y.measure``).
    series : str
        The :class:`Series` it draws.
    label, unit : str
        Its axis's label and unit.
    """

    key: str
    series: str
    label: str
    unit: str


#: The y axis: BS.1770 momentary loudness of the 400 ms block centred on the frame (default),
#: short-term loudness of the 3 s window, the paper's unweighted frame RMS, or the frame's
#: A-weighted level (docs/DYNAMICS.md, "The level axis"); the label names the measure and its
#: reference.
Y_MEASURE_TABLE = (
    Measure("momentary", "momentary_lufs", "momentary loudness (BS.1770, 400 ms)", "LUFS"),
    Measure("short-term", "short_term_lufs", "short-term loudness (BS.1770, 3 s)", "LUFS"),
    Measure("rms", "rms_dbfs", "RMS level (frame)", "dBFS"),
    Measure("a-weighted", "loudness_a_db", "A-weighted level (frame, re full-scale sine)", "dB"),
)
#: The z axis: PSR of the 3 s window centred on the frame (default), the 3 s crest factor, or
#: the paper's crest factor of the STFT frame itself (46 ms at 44.1 kHz; measures waveform
#: shape rather than compression, see docs/DYNAMICS.md).
Z_MEASURE_TABLE = (
    Measure("psr", "psr_db", "PSR (true peak - short-term loudness, 3 s)", "dB"),
    Measure("crest-3s", "crest_3s_db", "crest factor (3 s)", "dB"),
    Measure("crest-frame", "crest_db", "crest factor (frame)", "dB"),
)
Y_MEASURES = tuple(m.key for m in Y_MEASURE_TABLE)
Z_MEASURES = tuple(m.key for m in Z_MEASURE_TABLE)
DEFAULT_Y_MEASURE = "momentary"
DEFAULT_Z_MEASURE = "psr"


def _measure(table: tuple[Measure, ...], key: str, what: str) -> Measure:
    for measure in table:
        if measure.key == key:
            return measure
    choices = ", ".join(m.key for m in table)
    raise ExtractError(f"{what} must be one of {choices}, got {key!r}")


def y_measure_of(key: str, *, what: str = "y_measure") -> Measure:
    """The y measure named ``key`` (one of :data:`Y_MEASURES`).

    Raises
    ------
    ExtractError
        Another name; ``what`` names the option in the message.
    """
    return _measure(Y_MEASURE_TABLE, key, what)


def z_measure_of(key: str, *, what: str = "z_measure") -> Measure:
    """The z measure named ``key`` (one of :data:`Z_MEASURES`).

    Raises
    ------
    ExtractError
        Another name; ``what`` names the option in the message.
    """
    return _measure(Z_MEASURE_TABLE, key, what)
