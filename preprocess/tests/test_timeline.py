"""Timeline mode: inputs (tags, manifests), layout, cache, failures and bad inputs."""

import os

import mutagen.flac
import mutagen.id3
import mutagen.oggvorbis
import numpy as np
import pytest
import soundfile

from loudscape_extract import timeline
from loudscape_extract.audio import Audio
from loudscape_extract.cli import main
from loudscape_extract.features import track_features
from loudscape_extract.ply import read_ply
from loudscape_extract.timeline import (
    SongEntry,
    SongFrames,
    percentile_map,
    read_tags,
    sample_frames,
    song_spans,
    timeline_points,
)
from loudscape_extract.timeline.layout import x_axis as x_axis_of

from conftest import musical_signal

RATE = 8000
FAST = ["--n-fft", "256", "--hop", "128", "--jobs", "1"]


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def write_song(path, *, seed=0, duration_s=1.5, gain=0.5):
    y = musical_signal(sample_rate=RATE, duration_s=duration_s, seed=seed) * gain
    soundfile.write(str(path), y.astype(np.float32), RATE)


def tag(path, *, year=None, title="", artist="", id3_v23=False):
    path = str(path)
    if path.endswith(".flac") or path.endswith(".ogg"):
        audio = (
            mutagen.flac.FLAC(path) if path.endswith(".flac") else mutagen.oggvorbis.OggVorbis(path)
        )
        if year is not None:
            audio["date"] = str(year)
        audio["title"], audio["artist"] = title, artist
        audio.save()
    elif path.endswith(".mp3"):
        tags = mutagen.id3.ID3()
        if year is not None:
            tags.add(
                mutagen.id3.TYER(text=str(year)) if id3_v23 else mutagen.id3.TDRC(text=str(year))
            )
        tags.add(mutagen.id3.TIT2(text=title))
        tags.add(mutagen.id3.TPE1(text=artist))
        tags.save(path, v2_version=3 if id3_v23 else 4)


def tagged_folder(folder, years, ext=".flac"):
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, year in enumerate(years):
        path = folder / f"song{i}{ext}"
        write_song(path, seed=i)
        tag(path, year=year, title=f"Title {i}", artist=f"Artist {i % 2}")
        paths.append(path)
    return paths


def cli_timeline(args, out, capsys, cache):
    return run(["timeline", *args, "-o", out, "--cache-dir", cache, *FAST], capsys)


# ----------------------------------------------------------------------------- tags


@pytest.mark.parametrize(
    ("ext", "id3_v23"), [(".flac", False), (".ogg", False), (".mp3", False), (".mp3", True)]
)
def test_read_tags(tmp_path, ext, id3_v23):
    path = tmp_path / f"a{ext}"
    write_song(path)
    tag(
        path,
        year="1987-05-01" if not id3_v23 else 1987,
        title="Song",
        artist="Band",
        id3_v23=id3_v23,
    )
    assert read_tags(str(path)) == {"year": 1987, "title": "Song", "artist": "Band", "error": None}


def test_read_tags_untagged_and_corrupt(tmp_path):
    plain = tmp_path / "plain.wav"
    write_song(plain)
    assert read_tags(str(plain))["year"] is None and read_tags(str(plain))["error"] is None
    bad = tmp_path / "bad.flac"
    bad.write_bytes(b"not audio at all" * 10)
    assert read_tags(str(bad))["error"]


# ----------------------------------------------------------------------------- layout


def fake_song(n, *, rms=-20.0, crest=10.0):
    return SongFrames(
        rms_dbfs=np.full(n, rms, np.float32),
        crest_db=np.linspace(crest - 3, crest + 3, n).astype(np.float32),
        loudness_a_db=np.full(n, -30.0, np.float32),
        hp_mean=np.full(n, 0.25, np.float32),
        n_frames_total=n + 2,
        metrics={"integrated_lufs": -14.0, "hp_mean": 0.25},
        psr_db=np.full(n, crest + 1.0, np.float32),
        crest_3s_db=np.full(n, crest + 2.0, np.float32),
        momentary_lufs=np.full(n, rms - 2.0, np.float32),
        short_term_lufs=np.full(n, rms - 3.0, np.float32),
    )


def test_sample_frames():
    assert sample_frames(5, 10).tolist() == [0, 1, 2, 3, 4]
    index = sample_frames(1000, 4)
    assert index.tolist() == [0, 333, 666, 999]
    assert len(sample_frames(100000, 1024)) == 1024


def test_percentile_map_clamps():
    values = np.array([-5.0, 0.0, 5.0, 10.0, 20.0])
    assert percentile_map(values, 0.0, 10.0).tolist() == [-1.0, -1.0, 0.0, 1.0, 1.0]
    assert percentile_map(values, 3.0, 3.0).tolist() == [0.0] * 5


def test_layout_order_spans_and_axes():
    entries = [
        SongEntry("c", 2001, "Z", "B"),
        SongEntry("a", 1980, "A", "A"),
        SongEntry("b", 2001, "A", "B"),
        SongEntry("d", 1995, "", ""),
    ]
    songs = {e.path: fake_song(50 + i * 10) for i, e in enumerate(entries)}
    songs["d"] = fake_song(50, rms=-90.0, crest=40.0)  # below -60 dBFS, crest outlier
    points, layout = timeline_points(
        entries, songs, frames_per_song=20, x_by="year", z_measure="crest-frame"
    )
    described = layout["songs"]
    assert [s["path"] for s in described] == ["a", "d", "b", "c"]  # year, artist, title
    assert points.shape == (80, 5) and all(s["point_count"] == 20 for s in described)
    # Songs of 2001 share the year's span side by side; x grows with the order.
    assert described[2]["x_max"] == described[3]["x_min"]
    assert np.all(np.diff(points[:, 0]) > 0)
    x_axis = layout["axes"]["x"]
    assert (x_axis["min"], x_axis["max"], x_axis["unit"]) == (1980, 2002, "year")
    assert [t["label"] for t in x_axis["ticks"]] == ["1980", "1985", "1990", "1995", "2000"]
    assert x_axis["ticks"][0]["at"] == -1.0
    # y: momentary loudness on an absolute -60 .. 0 scale, clamped; z: 1st-99th percentiles
    # over the drawn frames.
    d = points[20:40]
    assert np.all(d[:, 1] == -1.0)
    assert np.allclose(points[:20, 1], 2 * (-22 + 60) / 60 - 1)
    assert layout["axes"]["y"]["unit"] == "LUFS" and layout["axes"]["y"]["measure"] == "momentary"
    for measure, level in (("short-term", -23.0), ("rms", -20.0), ("a-weighted", -30.0)):
        other, _ = timeline_points(
            entries, songs, frames_per_song=20, z_measure="crest-frame", y_measure=measure
        )
        assert np.allclose(other[:20, 1], 2 * (level + 60) / 60 - 1), measure
    z_axis = layout["axes"]["z"]
    all_crest = np.concatenate(
        [songs[p].crest_db[sample_frames(songs[p].crest_db.shape[0], 20)] for p in "adbc"]
    )
    assert z_axis["min"] == pytest.approx(np.percentile(all_crest, 1), abs=1e-5)
    assert z_axis["max"] == pytest.approx(np.percentile(all_crest, 99), abs=1e-5)
    assert points[:, 2].min() == -1.0 and points[:, 2].max() == 1.0
    assert np.allclose(points[:, 3], 0.7) and np.allclose(points[:, 4], 0.25)
    assert described[0]["metrics"]["integrated_lufs"] == -14.0


def test_a_span_of_years_has_several_year_ticks():
    """Songs from 1996 to 2009 tick every 2 years, not "2000" alone; each tick where its year
    begins; at most 8 ticks whatever the span."""
    entries = [SongEntry(str(year), year, "", "") for year in (1996, 2001, 2009)]
    axis = x_axis_of(entries, song_spans(entries, "year"), "year")
    labels = [t["label"] for t in axis["ticks"]]
    assert labels == ["1996", "1998", "2000", "2002", "2004", "2006", "2008"]
    for tick in axis["ticks"]:
        assert tick["at"] == pytest.approx(2 * (int(tick["label"]) - 1996) / 14 - 1, abs=1e-6)
    by_order = x_axis_of(entries, song_spans(entries, "order"), "order")
    assert [t["label"] for t in by_order["ticks"]] == ["1996", "2000", "2008"]
    for first, last in ((1996, 2009), (1900, 2024), (1980, 2001), (1, 3000)):
        years = [SongEntry("a", first, "", ""), SongEntry("b", last, "", "")]
        count = len(x_axis_of(years, song_spans(years, "year"), "year")["ticks"])
        assert 2 <= count <= 8, (first, last, count)


def test_order_mode_equal_spans():
    entries = [SongEntry(str(i), year, "", "") for i, year in enumerate((1970, 1970, 2010))]
    spans = song_spans(entries, "order")
    assert np.allclose([b - a for a, b in spans], 2 / 3)
    songs = {e.path: fake_song(30) for e in entries}
    _, layout = timeline_points(
        entries, songs, frames_per_song=8, x_by="order", z_measure="crest-frame"
    )
    axis = layout["axes"]["x"]
    assert (axis["min"], axis["max"]) == (1970, 2010)
    assert [(t["label"], round(t["at"], 4)) for t in axis["ticks"]] == [
        ("1970", -1.0),
        ("2010", 0.3333),
    ]


# ----------------------------------------------------------------------------- end to end


def test_timeline_from_tags(tmp_path, capsys):
    tagged_folder(tmp_path / "music" / "sub", [1999, 1975, 1988])
    out = tmp_path / "t.ply"
    status, err = cli_timeline(
        [tmp_path / "music", "--frames-per-song", 16], out, capsys, tmp_path / "c"
    )
    assert status == 0, err
    points, meta = read_ply(out)
    assert meta["mode"] == "timeline" and meta["point_count"] == points.shape[0] == 48
    assert [s["year"] for s in meta["songs"]] == [1975, 1988, 1999]
    assert [s["title"] for s in meta["songs"]] == ["Title 1", "Title 2", "Title 0"]
    assert set(meta["songs"][0]["metrics"]) == set(timeline.METRIC_KEYS)
    assert np.all(np.abs(points[:, :3]) <= 1) and np.all(
        (points[:, 3:] >= 0) & (points[:, 3:] <= 1)
    )
    assert meta["axes"]["z"]["label"] == "PSR (true peak - short-term loudness, 3 s)"
    assert meta["axes"]["z"]["measure"] == meta["extraction"]["z_measure"] == "psr"


def test_manifest_and_fewer_frames(tmp_path, capsys):
    (tmp_path / "audio").mkdir()
    write_song(tmp_path / "audio" / "one.wav", seed=1, duration_s=0.5)
    write_song(tmp_path / "audio" / "two.wav", seed=2)
    manifest = tmp_path / "songs.csv"
    manifest.write_text(
        "path,year,title,artist\naudio/two.wav,2012,Two,X\naudio/one.wav,1971,One,Y\n"
    )
    out = tmp_path / "t.ply"
    status, err = cli_timeline(
        ["--manifest", manifest, "--frames-per-song", 50], out, capsys, tmp_path / "c"
    )
    assert status == 0
    _, meta = read_ply(out)
    assert [(s["title"], s["year"]) for s in meta["songs"]] == [("One", 1971), ("Two", 2012)]
    assert meta["songs"][0]["point_count"] == meta["songs"][0]["frames_non_silent"] < 50
    assert "fewer than 50" in err


def test_cache_hit_does_not_decode(tmp_path, capsys, monkeypatch):
    tagged_folder(tmp_path / "m", [1990, 2000])
    out = tmp_path / "t.ply"
    assert cli_timeline([tmp_path / "m"], out, capsys, tmp_path / "cache")[0] == 0
    first = out.read_bytes()
    assert len(os.listdir(tmp_path / "cache")) == 2

    def no_decode(path, **_options):
        raise AssertionError(f"decoded {path} despite the cache")

    monkeypatch.setattr(timeline.frames, "stream_track", no_decode)
    status, err = cli_timeline([tmp_path / "m"], out, capsys, tmp_path / "cache")
    assert status == 0 and "2 from cache" in err
    assert out.read_bytes() == first
    # A changed parameter is a different key: it decodes again (and fails here, reported).
    status, err = run(
        [
            "timeline",
            tmp_path / "m",
            "-o",
            out,
            "--cache-dir",
            tmp_path / "cache",
            "--n-fft",
            512,
            "--hop",
            128,
            "--jobs",
            1,
        ],
        capsys,
    )
    assert status == 1 and "despite the cache" in err


def test_parallel_jobs_match_serial(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990, 2000, 1980])
    a, b = tmp_path / "a.ply", tmp_path / "b.ply"
    for out, jobs in [(a, 1), (b, 2)]:
        argv = ["timeline", tmp_path / "m", "-o", out, "--no-cache"]
        argv += ["--n-fft", 256, "--hop", 128, "--jobs", jobs]
        assert run(argv, capsys)[0] == 0
    assert a.read_bytes() == b.read_bytes()


def test_corrupt_song_is_skipped(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990, 2000])
    broken = tmp_path / "m" / "broken.flac"  # good tags, audio frames overwritten with noise
    write_song(broken)
    tag(broken, year=1995, title="Broken")
    data = broken.read_bytes()
    noise = np.random.default_rng(0).integers(0, 256, len(data) - len(data) // 3, np.uint8)
    broken.write_bytes(data[: len(data) // 3] + noise.tobytes())
    out = tmp_path / "t.ply"
    status, err = cli_timeline([tmp_path / "m"], out, capsys, tmp_path / "c")
    assert status == 1
    assert "broken.flac" in err and "failed" in err
    _, meta = read_ply(out)
    assert len(meta["songs"]) == 2
    assert [s["path"] for s in meta["extraction"]["skipped"]] == [str(broken)]
    # Through a manifest the file is decoded and fails there.
    (tmp_path / "m" / "broken.wav").write_bytes(b"RIFF" + b"\x00" * 100)
    manifest = tmp_path / "m" / "songs.csv"
    manifest.write_text("path,year\nsong0.flac,1990\nbroken.wav,1995\n")
    status, err = cli_timeline(["--manifest", manifest], out, capsys, tmp_path / "c")
    assert status == 1 and "broken.wav" in err and "decode" in err
    assert len(read_ply(out)[1]["songs"]) == 1


def test_no_year_is_left_out(tmp_path, capsys):
    tagged_folder(tmp_path / "m", [1990])
    write_song(tmp_path / "m" / "untagged.wav")
    out = tmp_path / "t.ply"
    status, err = cli_timeline([tmp_path / "m"], out, capsys, tmp_path / "c")
    assert status == 0 and "untagged.wav: no year" in err and "left out 1" in err
    assert len(read_ply(out)[1]["songs"]) == 1


def test_compressed_song_is_louder_with_less_crest():
    rng = np.random.default_rng(3)
    y = musical_signal(sample_rate=RATE, duration_s=4.0, seed=3) * 0.4
    y *= 0.3 + 0.7 * np.abs(np.sin(np.linspace(0, 3 * np.pi, y.size)))  # dynamic sections
    y += 0.001 * rng.standard_normal(y.size)
    squashed = np.clip(np.tanh(8 * y) / np.tanh(8 * np.abs(y).max()), -0.9, 0.9)

    def metrics(x):
        audio = Audio(samples=x[:, None].astype(np.float32), sample_rate=RATE, path="x")
        return track_features(audio, n_fft=256, hop_length=128).metrics

    original, loud = metrics(y), metrics(squashed)
    assert loud["crest_median_db"] < original["crest_median_db"] - 2
    assert loud["integrated_lufs"] > original["integrated_lufs"] + 3


# ----------------------------------------------------------------------------- bad inputs


def assert_one_line_error(status, err, out, *names):
    assert status == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("loudscape-extract: error: "), err
    for name in names:
        assert str(name) in lines[0]
    assert not os.path.exists(out)


def test_bad_inputs(tmp_path, capsys):
    out = tmp_path / "t.ply"
    empty = tmp_path / "empty"
    empty.mkdir()
    assert_one_line_error(
        *cli_timeline([empty], out, capsys, tmp_path / "c"), out, empty, "no audio"
    )
    assert_one_line_error(
        *cli_timeline([tmp_path / "nope"], out, capsys, tmp_path / "c"), out, "nope"
    )
    plain = tmp_path / "plain"
    plain.mkdir()
    write_song(plain / "a.wav")
    status, err = cli_timeline([plain], out, capsys, tmp_path / "c")
    assert_one_line_error(status, err, out, plain, "year")
    manifest = tmp_path / "songs.csv"
    manifest.write_text("path,year\nplain/a.wav,1980\nplain/missing.wav,1990\n")
    status, err = cli_timeline(["--manifest", manifest], out, capsys, tmp_path / "c")
    assert_one_line_error(status, err, out, manifest, "line 3", "missing.wav")
    manifest.write_text("path,year\nplain/a.wav,the eighties\n")
    status, err = cli_timeline(["--manifest", manifest], out, capsys, tmp_path / "c")
    assert_one_line_error(status, err, out, manifest, "line 2", "the eighties")
    manifest.write_text("file,when\nplain/a.wav,1980\n")
    status, err = cli_timeline(["--manifest", manifest], out, capsys, tmp_path / "c")
    assert_one_line_error(status, err, out, manifest, "path")
    missing_dir = tmp_path / "no-such-dir" / "t.ply"
    status, err = cli_timeline([plain], missing_dir, capsys, tmp_path / "c")
    assert_one_line_error(status, err, missing_dir, "does not exist")


def test_bad_flags_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["timeline", str(tmp_path), "--x-by", "decade"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main(["timeline", str(tmp_path), "--frames-per-song", "0"])
    assert exc.value.code == 2


def test_progress_line_on_a_tty(tmp_path, capsys, monkeypatch):
    tagged_folder(tmp_path / "m", [1990, 2000])
    monkeypatch.setattr("sys.stderr.isatty", lambda: True)
    status, err = cli_timeline(
        [tmp_path / "m", "--x-by", "order"], tmp_path / "t.ply", capsys, tmp_path / "c"
    )
    assert status == 0 and "\r" in err and "[2/2]" in err
    _, meta = read_ply(tmp_path / "t.ply")
    assert [s["x_min"] for s in meta["songs"]] == [-1.0, 0.0]
    assert meta["extraction"]["x_by"] == "order"


# ----------------------------------------------------------------------------- dynamics options


def test_order_mode_places_songs_without_a_year_last(tmp_path, capsys):
    paths = tagged_folder(tmp_path / "m", [1990, 1980])
    write_song(tmp_path / "m" / "untagged.wav", seed=7)
    out = tmp_path / "t.ply"
    status, err = cli_timeline([tmp_path / "m", "--x-by", "order"], out, capsys, tmp_path / "c")
    assert status == 0, err
    assert "no year" not in err
    _, meta = read_ply(out)
    assert [s["year"] for s in meta["songs"]] == [1980, 1990, None]
    assert meta["songs"][2]["path"].endswith("untagged.wav")
    assert [t["label"] for t in meta["axes"]["x"]["ticks"]] == ["1980", "1990"]
    assert meta["extraction"]["skipped"] == []
    # No year at all: the songs still make a timeline by order.
    for path in paths:
        path.unlink()
    status, err = cli_timeline([tmp_path / "m", "--x-by", "order"], out, capsys, tmp_path / "c")
    assert status == 0, err
    _, meta = read_ply(out)
    assert meta["axes"]["x"]["label"] == "song" and len(meta["songs"]) == 1


@pytest.mark.parametrize(
    ("measure", "label"),
    [("crest-3s", "crest factor (3 s)"), ("crest-frame", "crest factor (frame)")],
)
def test_z_measure_option(tmp_path, capsys, measure, label):
    tagged_folder(tmp_path / "m", [1990, 2000])
    out = tmp_path / "t.ply"
    status, err = cli_timeline(
        [tmp_path / "m", "--z-measure", measure], out, capsys, tmp_path / "c"
    )
    assert status == 0, err
    _, meta = read_ply(out)
    assert meta["axes"]["z"]["label"] == label
    assert meta["axes"]["z"]["measure"] == meta["extraction"]["z_measure"] == measure


def test_dc_offset_is_warned_about_and_highpass_recorded(tmp_path, capsys):
    folder = tmp_path / "m"
    folder.mkdir()
    y = musical_signal(sample_rate=RATE, duration_s=1.5, seed=1) * 0.3 + 0.3
    soundfile.write(str(folder / "dc.flac"), y.astype(np.float32), RATE)
    tag(folder / "dc.flac", year=1999, title="DC")
    out = tmp_path / "t.ply"
    status, err = cli_timeline([folder, "--highpass"], out, capsys, tmp_path / "c")
    assert status == 0, err
    assert "dc.flac: DC offset 0.3" in err and "warning" in err
    _, meta = read_ply(out)
    assert meta["songs"][0]["metrics"]["dc_offset"] == pytest.approx(0.3, abs=0.01)
    assert meta["extraction"]["highpass_hz"] == 20.0 and meta["extraction"]["dc_removed"]
    # A full-scale sine's A-weighted frame level is 0 dB in both modes: the scalar references
    # agree (the timeline's used to read 3.01 dB lower).
    assert meta["axes"]["scalar"]["label"] == "A-weighted level"
