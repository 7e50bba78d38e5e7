"""The noise floor's one keep rule: it fades in, so no band ends in a wall at the floor."""

import numpy as np
import pytest

from loudscape_extract.audio import Audio
from loudscape_extract.features import track_features
from loudscape_extract.floor import (
    FLOOR_TAPER_DB,
    bin_uniform,
    floor_edge_ratio,
    floor_keep_mask,
    taper_width,
)
from loudscape_extract.points import song_points

RATE = 44100


def _quiet_track(seconds=3.0):
    """A -30 dBFS tone over hiss whose 4-22 kHz bins sit about 76 dB under the peak bin, where
    an 80 dB floor below the peak cuts the hiss near its densest level."""
    rng = np.random.default_rng(12)
    t = np.arange(int(seconds * RATE)) / RATE
    tone = 0.0316 * np.sin(2 * np.pi * 440.0 * t) * (0.6 + 0.4 * np.sin(2 * np.pi * 0.5 * t))
    mono = tone + 8e-5 * rng.standard_normal(t.shape)
    return Audio(
        path="quiet.wav", samples=np.stack([mono, mono], 1).astype(np.float32), sample_rate=RATE
    )


def test_quiet_tracks_high_band_fades_out_at_the_floor():
    features = track_features(_quiet_track())
    cloud = song_points(features, floor_db=80.0)
    y_min, y_max = cloud.axes["y"]["min"], cloud.axes["y"]["max"]
    levels = y_min + (cloud.points[:, 1].astype(np.float64) + 1) * 0.5 * (y_max - y_min)
    freq = (cloud.points[:, 2].astype(np.float64) + 1) * 0.5 * features.frequencies_hz[-1]
    high = levels[freq >= 4000.0]
    # the hiss's hump is inside the 40 dB above the floor, so the band is dense near it ...
    counts, _ = np.histogram(high, bins=40, range=(y_min, y_min + 40))
    assert counts.argmax() < 15
    # ... and still stops softly: a hard floor left 0.8 of the densest 1 dB in the lowest 1 dB
    assert floor_edge_ratio(high, y_min=y_min) < 0.2
    assert high.min() >= y_min - 1e-3
    # nothing above the fade is dropped: every 4-22 kHz bin at or above it is a point
    drawn = features.level_db[features.frequencies_hz >= 4000.0][:, ~features.frames.silent]
    assert np.count_nonzero(high >= y_min + FLOOR_TAPER_DB + 0.01) == np.count_nonzero(
        drawn >= y_min + FLOOR_TAPER_DB + 0.01
    )


def test_keep_mask_fades_linearly_from_the_floor():
    rng = np.random.default_rng(3)
    levels = rng.uniform(-100.0, -60.0, size=(400, 500)).astype(np.float32)
    keep = floor_keep_mask(
        levels, frame_index=np.arange(400), bin_index=np.arange(500), y_min=-90.0, floor_db=80.0
    )
    assert not keep[levels < -90.0].any()
    assert keep[levels >= -90.0 + FLOOR_TAPER_DB].all()
    for low in range(-90, -78, 2):  # kept fraction = the ramp's mean over each 2 dB slice
        inside = (levels >= low) & (levels < low + 2)
        expected = (low + 1 - -90.0) / FLOOR_TAPER_DB
        assert keep[inside].mean() == pytest.approx(expected, abs=0.02), low


def test_keep_rule_depends_on_absolute_indices_only():
    u = bin_uniform(np.arange(50)[:, None], np.arange(1025)[None, :])
    assert u.shape == (50, 1025) and 0.0 <= u.min() and u.max() < 1.0
    assert abs(u.mean() - 0.5) < 0.01
    # a block starting at frame 20 sees the same numbers as the whole track there
    np.testing.assert_array_equal(
        bin_uniform(np.arange(20, 30)[:, None], np.arange(1025)), u[20:30]
    )
    assert taper_width(0.0) == 0.0 and taper_width(10.0) == 5.0 and taper_width(80.0) == 12.0
