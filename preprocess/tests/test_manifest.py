"""Manifests: errors name the manifest and the line; CSV commas as the csv module reads them;
duplicates (another path, a symlink, a hard link) reported and kept once; implausible years
refused."""

import datetime
import os

import numpy as np
import pytest
import soundfile

from loudscape_extract.cli import main
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import read_ply
from loudscape_extract.timeline.inputs import read_manifest

from conftest import musical_signal

RATE = 8000
FAST = ["--n-fft", "256", "--hop", "128", "--jobs", "1", "--no-cache"]


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


@pytest.fixture
def songs(tmp_path):
    for i in range(3):
        y = musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5
        soundfile.write(tmp_path / f"s{i}.wav", y.astype(np.float32), RATE)
    return tmp_path


def timeline(folder, text, capsys):
    manifest = folder / "songs.csv"
    manifest.write_text(text)
    out = folder / "t.ply"
    if out.exists():
        out.unlink()
    status, err = run(["timeline", "--manifest", manifest, "-o", out, *FAST], capsys)
    return status, err, manifest, out


def assert_manifest_error(status, err, out, manifest, *needles):
    assert status == 1 and not out.exists(), err
    assert err.count("\n") == 1 and f"error: {manifest}: line " in err
    assert "internal error" not in err
    for needle in needles:
        assert needle in err


def test_trailing_commas_are_ignored(songs, capsys):
    status, err, _, out = timeline(songs, "path,year,\ns0.wav,1990,\ns1.wav,1991,,\n", capsys)
    assert status == 0, err
    assert len(read_ply(out)[1]["songs"]) == 2


def test_quoted_comma_is_a_value_and_unquoted_comma_is_explained(songs, capsys):
    text = 'path,year,title\ns0.wav,1990,"Hello, World"\n'
    status, err, _, out = timeline(songs, text, capsys)
    assert status == 0 and read_ply(out)[1]["songs"][0]["title"] == "Hello, World"
    text = "path,year,title\ns0.wav,1990,Fine\ns1.wav,1991,Hello, World\n"
    status, err, manifest, out = timeline(songs, text, capsys)
    assert_manifest_error(status, err, out, manifest, "line 3", "4 values", "3 columns", "quote")


def test_line_numbers_count_blank_lines_and_multiline_values(songs, capsys):
    text = 'path,year,title\n\ns0.wav,1990,"two"\n\ns1.wav,17\n'
    status, err, manifest, out = timeline(songs, text, capsys)
    assert_manifest_error(status, err, out, manifest, "line 5", "year 17")
    with pytest.raises(ExtractError, match="line 5: year 17"):
        read_manifest(str(manifest))  # the library refuses it the same way
    # A value over several lines is refused (it is what an unbalanced quote looks like).
    text = 'path,year,title\n\ns0.wav,1990,"two\nlines"\ns1.wav,17\n'
    status, err, manifest, out = timeline(songs, text, capsys)
    assert_manifest_error(status, err, out, manifest, "line 3:", "lines 3-4")
    with pytest.raises(ExtractError, match="line 3: a quoted value runs over lines 3-4"):
        read_manifest(str(manifest))


@pytest.mark.parametrize("year", [1700, 1859, 3000])
def test_implausible_years_are_refused_with_the_line(songs, capsys, year):
    status, err, manifest, out = timeline(songs, f"path,year\ns0.wav,1990\ns1.wav,{year}\n", capsys)
    next_year = datetime.date.today().year + 1
    assert_manifest_error(status, err, out, manifest, "line 3", f"year {year}", f"1860-{next_year}")


def test_plausible_edges_are_accepted(songs, capsys):
    next_year = datetime.date.today().year + 1
    status, err, _, out = timeline(songs, f"path,year\ns0.wav,1860\ns1.wav,{next_year}\n", capsys)
    assert status == 0, err


def test_duplicates_through_paths_and_links_are_kept_once(songs, capsys):
    (songs / "sub").mkdir()
    (songs / "link.wav").symlink_to(songs / "s0.wav")
    os.link(songs / "s1.wav", songs / "hard.wav")
    text = "path,year\ns0.wav,1990\nsub/../s0.wav,1990\nlink.wav,1991\ns1.wav,1992\nhard.wav,1993\n"
    status, err, manifest, out = timeline(songs, text, capsys)
    assert status == 0, err
    notes = [line for line in err.splitlines() if "kept once" in line]
    assert len(notes) == 3
    assert f"{manifest}: line 3:" in notes[0] and "line 2" in notes[0]
    assert "line 4:" in notes[1] and "line 2 (" in notes[1]
    assert "line 6:" in notes[2] and "line 5 (" in notes[2]
    assert all(len(line) < 400 for line in err.splitlines())
    assert [s["path"] for s in read_ply(out)[1]["songs"]] == [
        str(songs / "s0.wav"),
        str(songs / "s1.wav"),
    ]


def test_duplicates_among_folder_inputs_are_kept_once(tmp_path, capsys):
    import mutagen.flac

    folder = tmp_path / "m"
    folder.mkdir()
    for i in range(2):
        y = musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5
        path = folder / f"s{i}.flac"
        soundfile.write(path, y.astype(np.float32), RATE)
        tags = mutagen.flac.FLAC(path)
        tags["date"] = str(1990 + i)
        tags.save()
    (folder / "again.flac").symlink_to(folder / "s0.flac")
    out = tmp_path / "t.ply"
    status, err = run(["timeline", folder, folder / "s1.flac", "-o", out, *FAST], capsys)
    assert status == 0, err
    assert sum("kept once" in line for line in err.splitlines()) == 2
    assert len(read_ply(out)[1]["songs"]) == 2


def test_tag_year_outside_the_range_is_skipped_with_the_reason(tmp_path, capsys):
    import mutagen.flac

    for i, year in enumerate((1990, 3000)):
        y = musical_signal(sample_rate=RATE, duration_s=1.0, seed=i) * 0.5
        path = tmp_path / f"s{i}.flac"
        soundfile.write(path, y.astype(np.float32), RATE)
        tags = mutagen.flac.FLAC(path)
        tags["date"] = str(year)
        tags.save()
    out = tmp_path / "t.ply"
    status, err = run(["timeline", tmp_path, "-o", out, *FAST], capsys)
    assert status == 1 and out.exists()
    assert any("s1.flac" in line and "year 3000" in line for line in err.splitlines())
    assert len(read_ply(out)[1]["songs"]) == 1


def test_other_manifest_problems_name_the_line(songs, capsys):
    cases = [
        ("path,year\ns0.wav,1990\n,1991\n", "line 3", "empty path"),
        ("path,year\ns0.wav,1990\nmissing.wav,1991\n", "line 3", "missing.wav"),
        ("file,when\ns0.wav,1990\n", "line 1", "needs columns path and year"),
        # An unclosed quote is named with its line and what it starts.
        ('path,year\ns0.wav,1990\n"s1.wav,1991\n', "line 3", "'\"s1.wav,1991'"),
    ]
    for text, line, needle in cases:
        status, err, manifest, out = timeline(songs, text, capsys)
        assert_manifest_error(status, err, out, manifest, line, needle)


def test_unbalanced_quote_is_an_error_naming_its_line(songs, capsys):
    # Lenient CSV read the next two rows into the title: one song, exit 0, in silence.
    text = 'path,year,title\ns0.wav,2001,"Unterminated title,a\ns1.wav,2002,B\ns2.wav,2003,C\n'
    status, err, manifest, out = timeline(songs, text, capsys)
    assert_manifest_error(status, err, out, manifest, "line 2:", "never closed", "Unterminated")


def test_quoted_value_over_several_lines_is_an_error(songs, capsys):
    text = 'path,year,title\ns0.wav,2001,"Two\nlines"\ns1.wav,2002,B\n'
    status, err, manifest, out = timeline(songs, text, capsys)
    assert_manifest_error(status, err, out, manifest, "line 2:", "lines 2-3", "one line")


def test_a_balanced_quote_with_a_doubled_quote_is_fine(songs, capsys):
    text = 'path,year,title\ns0.wav,2001,"Say ""hi"", then go"\ns1.wav,2002,B\n'
    status, err, _, out = timeline(songs, text, capsys)
    assert status == 0, err
    assert [s["title"] for s in read_ply(out)[1]["songs"]] == ['Say "hi", then go', "B"]


def test_blank_year_places_the_song_last_by_order_and_is_an_error_by_year(songs, capsys):
    manifest = songs / "songs.csv"
    manifest.write_text("path,year\ns0.wav,\ns1.wav,1990\ns2.wav,1980\n")
    out = songs / "t.ply"
    status, err = run(
        ["timeline", "--manifest", manifest, "-o", out, "--x-by", "order", *FAST], capsys
    )
    assert status == 0, err
    songs_meta = read_ply(out)[1]["songs"]
    assert [(os.path.basename(s["path"]), s["year"]) for s in songs_meta] == [
        ("s2.wav", 1980),
        ("s1.wav", 1990),
        ("s0.wav", None),
    ]
    status, err, _, out = timeline(songs, manifest.read_text(), capsys)
    assert_manifest_error(status, err, out, manifest, "line 2: no year", "--x-by order")


def test_broken_symlink_and_fifo_in_a_folder_are_reported(tmp_path, capsys):
    from test_timeline import tag

    folder = tmp_path / "m"
    folder.mkdir()
    y = musical_signal(sample_rate=RATE, duration_s=1.0) * 0.5
    soundfile.write(folder / "s.flac", y.astype(np.float32), RATE)
    tag(folder / "s.flac", year=1990, title="S")
    (folder / "gone.flac").symlink_to(folder / "moved-away.flac")
    os.mkfifo(folder / "pipe.ogg")
    out = tmp_path / "t.ply"
    status, err = run(["timeline", folder, "-o", out, *FAST, "-q"], capsys)
    assert status == 1 and out.exists()
    lines = err.splitlines()
    assert f"loudscape-extract: skipped: {folder / 'gone.flac'}: broken symbolic link" in err
    assert "moved-away.flac" in err
    assert f"skipped: {folder / 'pipe.ogg'}: not a regular file: a FIFO" in err
    assert "2 song(s) failed and were skipped" in lines[-1]
    skipped = read_ply(out)[1]["extraction"]["skipped"]
    assert sorted(os.path.basename(s["path"]) for s in skipped) == ["gone.flac", "pipe.ogg"]
    status, err = run(["timeline", "--list-songs", folder], capsys)
    assert status == 0 and "skipped:" in err and "gone.flac" in err
