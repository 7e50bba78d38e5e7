"""``--progress json``: the lines a program reads while the extractor runs."""

import json
import os

import numpy as np
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.progress import STAGES, JsonProgress

from conftest import musical_signal

RATE = 8000


def lines_of(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_song_progress_is_json_lines_ending_in_done(tmp_path, capsys):
    source = tmp_path / "track.wav"
    soundfile.write(source, musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5, RATE)
    out = tmp_path / "track.ply"
    status = main(["song", str(source), "-o", str(out), "--n-fft", "256", "--hop", "128",
                   "--progress", "json"])  # fmt: skip
    captured = capsys.readouterr()
    assert status == 0 and out.exists()
    records = lines_of(captured.out)
    assert records[-1] == {"done": str(out)}
    stages = [r["stage"] for r in records[:-1]]
    for stage in ("decode", "spectrogram", "hpss", "frame features", "points", "write"):
        assert stage in stages
    fractions = [r["fraction"] for r in records[:-1]]
    assert fractions == sorted(fractions) and 0.0 <= fractions[0] and fractions[-1] < 1.0
    assert all(0.0 <= f <= 1.0 for f in fractions)


def test_song_progress_error_is_the_last_line(tmp_path, capsys):
    source = tmp_path / "silent.wav"
    soundfile.write(source, np.zeros(RATE, dtype=np.float32), RATE)
    out = tmp_path / "silent.ply"
    status = main(["song", str(source), "-o", str(out), "--progress", "json"])
    captured = capsys.readouterr()
    assert status == 1 and not out.exists()
    last = lines_of(captured.out)[-1]
    assert set(last) == {"error"} and "silent" in last["error"] and str(source) in last["error"]
    assert "error" in captured.err  # the usual one line on stderr as well


def test_fractions_only_grow_and_unknown_messages_keep_the_stage(capsys):
    progress = JsonProgress()
    progress("decoding x.wav")
    progress("3.0 s, 44100 Hz, 2 channel(s)")
    progress("harmonic-percussive separation")
    progress("spectrogram")  # out of order: the fraction does not go back
    records = lines_of(capsys.readouterr().out)
    assert [r["stage"] for r in records] == ["decode", "decode", "hpss", "spectrogram"]
    hpss = {stage: fraction for _, stage, fraction in STAGES}["hpss"]
    assert hpss > 0.0
    assert [r["fraction"] for r in records] == [0.0, 0.0, hpss, hpss]
    assert [f for _, _, f in STAGES] == sorted(f for _, _, f in STAGES)


def test_timeline_progress_is_one_line_a_song_then_left_out_then_done(tmp_path, capsys):
    import mutagen.flac

    folder = tmp_path / "music"
    folder.mkdir()
    for i, year in enumerate([1999, 1975, None]):
        path = folder / f"song{i}.flac"
        soundfile.write(path, musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5, RATE)
        if year is not None:
            tags = mutagen.flac.FLAC(path)
            tags["date"] = str(year)
            tags.save()
    out = tmp_path / "t.ply"
    status = main(["timeline", str(folder), "-o", str(out), "--cache-dir", str(tmp_path / "c"),
                   "--n-fft", "256", "--hop", "128", "--jobs", "1", "--frames-per-song", "8",
                   "--progress", "json"])  # fmt: skip
    captured = capsys.readouterr()
    assert status == 0 and out.exists(), captured.err
    records = lines_of(captured.out)
    songs = [r for r in records if r.get("stage") == "songs"]
    assert [r["songs_done"] for r in songs] == [1, 2]
    assert {r["songs_total"] for r in songs} == {2}
    assert [r["fraction"] for r in songs] == [0.5, 1.0]
    assert sorted(os.path.basename(r["song"]) for r in songs) == ["song0.flac", "song1.flac"]
    assert records[-2] == {"without_year": [str(folder / "song2.flac")], "failed": {}}
    assert records[-1] == {"done": str(out)}
    assert all("done" not in r and "error" not in r for r in records[:-1])


def test_the_installed_version_is_the_programs():
    """The app reads the version from the installed metadata (pyproject's): the same."""
    from importlib.metadata import version

    from loudscape_extract.version import __version__

    assert version("loudscape-extract") == __version__


def test_list_songs_gives_each_song_its_tags_and_writes_nothing(tmp_path, capsys):
    import mutagen.flac

    folder = tmp_path / "music"
    folder.mkdir()
    for i, year in enumerate([1984, None]):
        path = folder / f"song{i}.flac"
        soundfile.write(path, musical_signal(sample_rate=RATE, duration_s=0.5, seed=i) * 0.5, RATE)
        if year is not None:
            tags = mutagen.flac.FLAC(path)
            tags["date"], tags["title"] = str(year), "Title"
            tags.save()
    status = main(["timeline", str(folder), "--list-songs", "--progress", "json"])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    records = lines_of(captured.out)
    assert records[-1] == {"done": ""}
    by_name = {os.path.basename(r["song"]): r for r in records[:-1]}
    assert by_name["song0.flac"]["year"] == 1984 and by_name["song0.flac"]["title"] == "Title"
    assert by_name["song1.flac"]["year"] is None
    assert all(r["tag_error"] is None for r in records[:-1])
    assert sorted(os.listdir(folder)) == ["song0.flac", "song1.flac"]
