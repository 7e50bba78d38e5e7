"""The one table of the timeline's per-frame series and measures (timeline/series.py): what
SongFrames holds, what a cache entry stores and what the axes can draw all come from it."""

import dataclasses

import numpy as np
import pytest

from loudscape_extract import ExtractError
from loudscape_extract.timeline import cache, layout
from loudscape_extract.timeline.frames import SongFrames
from loudscape_extract.timeline.series import (
    SERIES,
    Y_MEASURE_TABLE,
    Z_MEASURE_TABLE,
    y_measure_of,
    z_measure_of,
)


def test_song_frames_holds_exactly_the_registered_series():
    arrays = {
        f.name for f in dataclasses.fields(SongFrames) if f.type in ("np.ndarray", np.ndarray)
    }
    assert arrays == {s.name for s in SERIES}


def test_the_cache_stores_the_registered_series_in_order_with_their_ranges():
    assert cache._SERIES == tuple(s.name for s in SERIES)
    for s in SERIES:
        assert cache._SERIES_RANGES[s.name] == (s.low, s.high, s.nan_allowed)


def test_every_measure_draws_a_registered_series_and_the_axes_say_its_label():
    names = {s.name for s in SERIES}
    for measure in Y_MEASURE_TABLE + Z_MEASURE_TABLE:
        assert measure.series in names, measure
    for measure in Y_MEASURE_TABLE:
        y = layout.y_axis(measure.key)
        assert (y["label"], y["unit"], y["measure"]) == (measure.label, measure.unit, measure.key)
    assert layout.Y_MEASURES == tuple(m.key for m in Y_MEASURE_TABLE)
    assert layout.Z_MEASURES == tuple(m.key for m in Z_MEASURE_TABLE)


def test_an_unknown_measure_is_refused_naming_the_option_and_the_choices():
    with pytest.raises(ExtractError, match=r"--y-measure must be one of momentary, .*got 'loud'"):
        y_measure_of("loud", what="--y-measure")
    with pytest.raises(ExtractError, match=r"z_measure must be one of psr, crest-3s, crest-frame"):
        z_measure_of("crest")
