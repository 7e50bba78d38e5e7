"""Streaming normalization: known answers from the services' published rules."""

import pytest

from loudscape_extract.normalization import SERVICES, normalization_gain, streaming_gains

BY_KEY = {service.key: service for service in SERVICES}


def gain(key, lufs, peak):
    return normalization_gain(BY_KEY[key], integrated_lufs=lufs, true_peak_dbtp=peak)


def test_a_loud_master_is_turned_down_by_every_service():
    gains = streaming_gains({"integrated_lufs": -8.0, "true_peak_dbtp": 0.5})
    assert gains == pytest.approx(
        {"spotify": -6.0, "spotify_loud": -3.0, "spotify_quiet": -11.0, "youtube": -6.0,
         "aes_td1008": -8.0}
    )  # fmt: skip


def test_turning_up_stops_at_the_true_peak_ceiling():
    # Spotify's own example: -20 LUFS with its true peak at -5 dB is lifted to -16 LUFS only
    assert gain("spotify", -20.0, -5.0) == pytest.approx(4.0)
    assert gain("spotify", -20.0, -9.0) == pytest.approx(6.0)  # enough headroom: to -14
    assert gain("spotify", -20.0, -0.5) == 0.0  # peak above -1 dBTP already: not turned up
    assert gain("spotify_loud", -20.0, -0.5) == pytest.approx(9.0)  # loud: a limiter, no rule
    assert gain("youtube", -20.0, -9.0) == 0.0  # YouTube only turns down
    assert gain("spotify_quiet", -22.0, -6.0) == pytest.approx(3.0)


def test_missing_loudness_gives_no_gain():
    assert set(streaming_gains({"integrated_lufs": None}).values()) == {None}
    assert gain("spotify", -20.0, None) is None  # turning up needs the peak
    assert gain("spotify", -8.0, None) == pytest.approx(-6.0)  # turning down does not


def test_report_per_song_rows_carry_each_services_gain():
    from loudscape_extract.report import SONG_COLUMNS, per_song

    loud = {"integrated_lufs": -8.0, "true_peak_dbtp": 0.3}
    quiet = {"integrated_lufs": -20.0, "true_peak_dbtp": -5.0}
    songs = [{"year": 2011, "metrics": loud}, {"year": 1991, "metrics": quiet}]
    rows = per_song({"songs": songs})
    assert all(f"{s.key}_gain_db" in SONG_COLUMNS for s in SERVICES)
    assert list(rows[0]) == list(SONG_COLUMNS)
    assert rows[0]["spotify_gain_db"] == -6.0 and rows[0]["youtube_gain_db"] == -6.0
    assert rows[1]["spotify_gain_db"] == 4.0 and rows[1]["youtube_gain_db"] == 0.0
