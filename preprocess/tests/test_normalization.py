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


def test_presets_shift_a_song_to_what_is_heard():
    """Issue 28's known answers: -8 LUFS under a -14 LUFS preset sits at -14; -20 LUFS stays
    at -20 under a preset that never turns up and is raised, limited by its true peak, under
    one that does; broadcast brings both to its target."""
    from loudscape_extract.normalization import NORMALIZE_CHOICES, PRESETS, preset_gain
    from loudscape_extract.report import heard_lufs

    loud = {"integrated_lufs": -8.0, "true_peak_dbtp": 0.5}
    quiet = {"integrated_lufs": -20.0, "true_peak_dbtp": -5.0}
    assert NORMALIZE_CHOICES[0] == "none" and set(NORMALIZE_CHOICES[1:]) == set(PRESETS)
    assert heard_lufs(loud, "spotify") == pytest.approx(-14.0)
    assert heard_lufs(loud, "youtube") == pytest.approx(-14.0)
    assert heard_lufs(quiet, "youtube") == pytest.approx(-20.0)  # never turned up
    assert heard_lufs(quiet, "spotify") == pytest.approx(-16.0)  # up to a -1 dBTP peak only
    assert heard_lufs(quiet, "aes_td1008") == pytest.approx(-16.0)
    assert heard_lufs(quiet, "spotify_loud") == pytest.approx(-11.0)  # a limiter: no rule
    for song in (loud, quiet):
        assert heard_lufs(song, "ebu_r128") == pytest.approx(-23.0)
        assert heard_lufs(song, "atsc_a85") == pytest.approx(-24.0)
        assert heard_lufs(song, "none") == song["integrated_lufs"]
    assert preset_gain("none", {}) == 0.0
    assert heard_lufs({"integrated_lufs": None}, "spotify") is None


def test_report_penalty_and_heard_columns_per_year():
    from loudscape_extract.report import REPORT_COLUMNS, per_year

    songs = [
        {"year": 1990, "metrics": {"integrated_lufs": -20.0, "true_peak_dbtp": -5.0}},
        {"year": 1990, "metrics": {"integrated_lufs": -16.0, "true_peak_dbtp": -3.0}},
        {"year": 2010, "metrics": {"integrated_lufs": -8.0, "true_peak_dbtp": 0.5}},
    ]
    rows = per_year({"songs": songs}, normalize="spotify")
    assert list(rows[0]) == list(REPORT_COLUMNS)
    assert rows[0]["normalize"] == "spotify"
    # 1990: turned up 4 and 2 dB (peaks), heard at -16 and -14; 2010: taken off 6 dB
    assert rows[0]["spotify_penalty_db_median"] == pytest.approx(-3.0)
    assert rows[0]["heard_integrated_lufs_median"] == pytest.approx(-15.0)
    assert rows[0]["youtube_penalty_db_median"] == pytest.approx(0.0)
    assert rows[1]["spotify_penalty_db_median"] == pytest.approx(6.0)
    assert rows[1]["ebu_r128_penalty_db_median"] == pytest.approx(15.0)
    assert rows[1]["heard_integrated_lufs_median"] == pytest.approx(-14.0)
    assert per_year({"songs": songs})[0]["heard_integrated_lufs_median"] is None
