"""A tagged song carries its title and artist (docs/FORMAT.md, `source`), so the app names it
by its tag in Song mode as the timeline does."""

import shutil
import subprocess

import pytest

from loudscape_extract import extract_song
from loudscape_extract.ply import read_ply_metadata

from conftest import musical_signal


@pytest.fixture
def flac(tmp_path):
    import soundfile

    path = tmp_path / "plain.flac"
    soundfile.write(path, musical_signal(sample_rate=8000, duration_s=3.0), 8000)
    return path


def test_title_and_artist_come_from_the_tags(flac, tmp_path):
    assert shutil.which("ffmpeg"), "ffmpeg is needed (scripts/setup-system.sh installs it)"
    tagged = tmp_path / "tagged.flac"
    subprocess.run(
        ["ffmpeg", "-v", "error", "-y", "-i", str(flac), "-metadata", "title=  Blue   Monday ",
         "-metadata", "artist=New Order", str(tagged)],
        check=True,
    )  # fmt: skip
    extract_song(str(tagged), str(tmp_path / "tagged.ply"))
    source = read_ply_metadata(str(tmp_path / "tagged.ply"))["source"]
    assert source["title"] == "Blue Monday"
    assert source["artist"] == "New Order"


def test_an_untagged_song_has_no_title(flac, tmp_path):
    extract_song(str(flac), str(tmp_path / "plain.ply"))
    source = read_ply_metadata(str(tmp_path / "plain.ply"))["source"]
    assert "title" not in source and "artist" not in source
