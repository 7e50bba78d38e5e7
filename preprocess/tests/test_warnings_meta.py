"""Warnings travel with the data: what the extractor says about an input on stderr is also in
the cloud's metadata (``warnings``; docs/FORMAT.md), fresh or from the timeline cache; and the
signal warnings (cancelling channels, clipping) are raised when, and only when, they apply."""

import numpy as np
import pytest
import soundfile
from test_timeline import tag

from loudscape_extract.cli import main
from loudscape_extract.contract import check_metadata
from loudscape_extract.errors import ExtractError
from loudscape_extract.notices import CANCEL_WARN_DB, ClipRuns, decode_notice, warnings_problem
from loudscape_extract.ply import read_ply
from loudscape_extract.stream import stream_track

from conftest import musical_signal

RATE = 16000
FAST = ["--n-fft", "512", "--hop", "256"]


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def write_stereo(path, left, right, fmt=None):
    soundfile.write(str(path), np.stack([left, right], axis=1).astype(np.float32), RATE, format=fmt)


def warning_lines(err):
    return [line for line in err.splitlines() if line.startswith("loudscape-extract: warning:")]


def song(tmp_path, capsys, source, *extra):
    out = tmp_path / (source.stem + ".ply")
    status, err = run(["song", source, "-o", out, *FAST, *extra], capsys)
    assert status == 0, err
    return read_ply(out)[1], err


def test_truncated_flac_warning_is_in_the_metadata_and_on_stderr(tmp_path, capsys):
    source = tmp_path / "cut.flac"
    y = musical_signal(sample_rate=RATE, duration_s=4.0) * 0.4
    write_stereo(source, y, y)
    data = source.read_bytes()
    source.write_bytes(data[:-100])
    meta, err = song(tmp_path, capsys, source)
    (item,) = meta["warnings"]
    assert item["kind"] == "truncated"
    assert "of the 4.00 s the file promises" in item["message"], item
    assert str(source) not in item["message"]  # the reader prefixes the file
    assert warning_lines(err) == [f"loudscape-extract: warning: {source}: {item['message']}"]


def test_a_clean_file_has_no_warnings_key(tmp_path, capsys):
    source = tmp_path / "clean.wav"
    y = musical_signal(sample_rate=RATE, duration_s=2.0, seed=3) * 0.4
    write_stereo(source, y, 0.8 * y)
    meta, err = song(tmp_path, capsys, source)
    assert "warnings" not in meta and warning_lines(err) == []


def test_antiphase_channels_warn_with_the_figure(tmp_path, capsys):
    source = tmp_path / "antiphase.wav"
    y = musical_signal(sample_rate=RATE, duration_s=2.0) * 0.4
    # One channel in opposite polarity plus 16-bit dither: the mono mix is quantization noise.
    write_stereo(source, y, -y + 1e-4 * np.random.default_rng(0).standard_normal(y.size), "WAV")
    meta, err = song(tmp_path, capsys, source)
    kinds = [w["kind"] for w in meta["warnings"]]
    assert kinds == ["channels_cancel"]
    message = meta["warnings"][0]["message"]
    drop = float(message.split("it is ")[1].split(" dB")[0])
    assert drop > 60  # 65.0 dB: the noise against the music
    assert "channels_cancel" not in err and f"{source}: the channels cancel" in err
    # The metrics still measure the channels: a loud file, not a silent one.
    assert meta["metrics"]["integrated_lufs"] > -30


@pytest.mark.parametrize(
    ("correlation", "warns"), [(1.0, False), (0.0, False), (-0.9, False), (-0.995, True)]
)
def test_cancellation_threshold_separates_mixes_from_flipped_channels(tmp_path, correlation, warns):
    rng = np.random.default_rng(7)
    a, b = rng.standard_normal((2, 3 * RATE)) * 0.1
    left = a
    right = correlation * a + np.sqrt(1 - correlation**2) * b
    source = tmp_path / "c.wav"
    write_stereo(source, left, right, "WAV")
    track = stream_track(str(source), n_fft=512, hop_length=256)
    assert [w["kind"] for w in track.signal] == (["channels_cancel"] if warns else [])
    expected_drop = -10 * np.log10((1 + correlation) / 2) if correlation > -1 else np.inf
    assert (expected_drop >= CANCEL_WARN_DB) == warns


def test_one_silent_channel_is_not_cancellation(tmp_path):
    y = musical_signal(sample_rate=RATE, duration_s=2.0) * 0.4
    source = tmp_path / "left.wav"
    write_stereo(source, y, np.zeros_like(y))
    assert stream_track(str(source), n_fft=512, hop_length=256).signal == ()


def test_clipping_runs_are_counted_across_blocks(tmp_path, capsys):
    y = np.sin(2 * np.pi * 220 * np.arange(2 * RATE) / RATE) * 1.6  # clipped at full scale
    source = tmp_path / "clipped.wav"
    write_stereo(source, np.clip(y, -1, 1), 0.5 * y / 1.6, "WAV")
    whole = stream_track(str(source), n_fft=512, hop_length=256)
    blocked = stream_track(str(source), n_fft=512, hop_length=256, block_samples=1001)
    (item,) = whole.signal
    assert item["kind"] == "clipping" and blocked.signal == whole.signal
    # 220 Hz for 2 s, clipped on both half-waves: 880 runs.
    assert "880 run(s)" in item["message"]
    meta, _ = song(tmp_path, capsys, source)
    assert [w["kind"] for w in meta["warnings"]] == ["clipping"]


def test_clip_counter_counts_runs_split_between_blocks():
    at = np.zeros(20)
    at[[3, 4, 5, 9, 10, 14, 15, 16, 17]] = 1.0  # runs of 3, 2 (too short) and 4
    counter = ClipRuns(1)
    for start in range(0, 20, 4):  # blocks of 4 split every run
        counter.feed(start, at[start : start + 4, None])
    assert (counter.runs, counter.samples, counter.first) == (2, 7, 3)


def test_decode_notice_kinds():
    assert decode_notice("") is None
    short = "truncated or corrupt audio: decoded 1.49 s of the 4.00 s the file promises (37 %)"
    assert decode_notice(short)["kind"] == "truncated"
    assert decode_notice("truncated or corrupt audio: decoded 2.00 s (decoder error: x)")[
        "kind"
    ] == ("corrupt")
    assert decode_notice("corrupt audio: 3 Ogg pages fail their CRC")["kind"] == "corrupt"


def test_timeline_warnings_per_song_and_top_level_fresh_and_cached(tmp_path, capsys):
    folder = tmp_path / "m"
    folder.mkdir()
    y = musical_signal(sample_rate=RATE, duration_s=3.0, seed=1) * 0.3
    write_stereo(folder / "dc.flac", y + 0.3, y + 0.3)
    noise = 1e-4 * np.random.default_rng(0).standard_normal(y.size)
    write_stereo(folder / "flip.flac", y, -y + noise)
    write_stereo(folder / "clean.flac", y, y)
    for year, name in enumerate(("dc", "flip", "clean")):
        tag(folder / f"{name}.flac", year=2000 + year, title=name)
    cache = tmp_path / "cache"
    seen = []
    for _ in range(2):  # computed, then every song from the cache
        out = tmp_path / "t.ply"
        status, err = run(["timeline", folder, "-o", out, "--cache-dir", cache, *FAST], capsys)
        assert status == 0, err
        meta = read_ply(out)[1]
        check_metadata(meta, n_points=meta["point_count"])
        songs = {s["title"]: s for s in meta["songs"]}
        assert [w["kind"] for w in songs["dc"]["warnings"]] == ["dc_offset"]
        assert [w["kind"] for w in songs["flip"]["warnings"]] == ["channels_cancel"]
        assert "warnings" not in songs["clean"]
        assert meta["warnings"] == [
            {**w, "path": s["path"]} for s in meta["songs"] for w in s.get("warnings", [])
        ]
        for item in meta["warnings"]:
            assert f"warning: {item['path']}: {item['message']}" in err
        seen.append(meta["warnings"])
    assert "from cache" in err and seen[0] == seen[1]


@pytest.mark.parametrize(
    ("warnings", "timeline", "problem"),
    [
        ({"kind": "x"}, False, "must be an array"),
        (["text"], False, "must be an object"),
        ([{"kind": "x"}], False, ".message must be a string"),
        ([{"kind": "x", "message": "a\nb"}], False, "one line"),
        ([{"kind": "x", "message": "m"}], True, ".path must be a string"),
    ],
)
def test_contract_refuses_malformed_warnings(warnings, timeline, problem):
    assert problem in warnings_problem(warnings, with_path=timeline)
    meta = {
        "format_version": 2,
        "mode": "timeline" if timeline else "song",
        "point_count": 0,
        "axes": {n: {"min": 0.0, "max": 1.0} for n in ("x", "y", "z", "scalar", "hp")},
        "warnings": warnings,
    }
    with pytest.raises(ExtractError, match="warnings"):
        check_metadata(meta, n_points=0)
    meta["warnings"] = [{"kind": "new_kind", "message": "m", "path": "p"}]
    check_metadata(meta, n_points=0)  # any kind is fine


def test_format_fixtures_with_warnings_pass_the_contract():
    import os

    from loudscape_fixtures.formats import NON_UTF8_TIMELINE_PATH, SONG_WARNINGS

    folder = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "fixtures", "format")
    points, song = read_ply(os.path.join(folder, "song_v2_warnings.ply"))
    check_metadata(song, n_points=points.shape[0])
    assert song["warnings"] == SONG_WARNINGS
    points, timeline = read_ply(os.path.join(folder, "timeline_v2_warnings.ply"))
    check_metadata(timeline, n_points=points.shape[0])
    paths = [w["path"] for w in timeline["warnings"]]
    assert paths[1:] == [os.fsdecode(NON_UTF8_TIMELINE_PATH)] * 2  # kept byte for byte


def test_export_and_report_show_the_warnings_a_cloud_carries(tmp_path, capsys):
    import os

    from loudscape_fixtures.formats import SONG_WARNINGS

    folder = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "fixtures", "format")
    song = os.path.join(folder, "song_v2_warnings.ply")
    status, err = run(["export", song, "-o", tmp_path / "s.vtp", "-q"], capsys)
    assert status == 0, err
    source = read_ply(song)[1]["source"]["path"]
    assert warning_lines(err) == [
        f"loudscape-extract: warning: {source}: {w['message']}" for w in SONG_WARNINGS
    ]
    timeline = os.path.join(folder, "timeline_v2_warnings.ply")
    status, err = run(["report", timeline, "-o", tmp_path / "r.png", "-q"], capsys)
    assert status == 0, err
    expected = read_ply(timeline)[1]["warnings"]
    assert len(warning_lines(err)) == len(expected) == 3
    assert all(f"{w['path']}: {w['message']}" in err for w in expected[:1])
