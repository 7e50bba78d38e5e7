"""The notebook API (``import loudscape``): pictures drawn by the ``loudscape`` binary.

The binary is ``$LOUDSCAPE_BIN`` (``make test-mesh`` sets ``target/debug/loudscape``), which
the package itself honours; the pictures come from the same ``loudscape render`` the commands
run, so these tests check the wiring (arguments, inputs, outputs, errors), not the drawing.
"""

from __future__ import annotations

import os
import stat
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import soundfile

import loudscape
from loudscape_extract import ExtractError, read_ply
from loudscape_extract.fixtures import SAMPLE_RATE, fixture_signal

ROOT = Path(__file__).resolve().parents[2]
SONG = ROOT / "data" / "demo_song.ply"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape"))


@pytest.fixture(autouse=True)
def _binary(monkeypatch):
    if not BINARY.is_file():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    monkeypatch.setenv("LOUDSCAPE_BIN", str(BINARY))


def _drawn(pixels: np.ndarray) -> int:
    """Distinct colours of a picture (a blank one has one or two)."""
    return len(np.unique(pixels.reshape(-1, pixels.shape[-1]), axis=0))


def test_render_a_cloud_file_gives_a_picture_jupyter_shows():
    picture = loudscape.render(SONG, size=(320, 200))
    assert (picture.width, picture.height) == (320, 200)
    assert picture._repr_png_().startswith(b"\x89PNG\r\n\x1a\n")
    pixels = picture.to_numpy()
    assert pixels.shape == (200, 320, 4) and pixels.dtype == np.uint8
    assert (pixels[..., 3] == 255).all()
    assert _drawn(pixels) > 100


def test_arrays_render_as_the_file_does():
    from_file = loudscape.render(SONG, size=(240, 160), labels=False, legend=False)
    cloud = loudscape.read_cloud(SONG)
    from_cloud = loudscape.render(cloud, size=(240, 160), labels=False, legend=False)
    points, metadata = read_ply(SONG)
    from_pair = loudscape.render((points, metadata), size=(240, 160), labels=False, legend=False)
    assert np.array_equal(from_cloud.to_numpy(), from_file.to_numpy())
    assert np.array_equal(from_pair.to_numpy(), from_file.to_numpy())


def test_the_options_reach_the_renderer():
    points = loudscape.render(SONG, size=(240, 160)).to_numpy()
    light = loudscape.render(SONG, size=(240, 160), background="light").to_numpy()
    volume = loudscape.render(SONG, view="volume", size=(240, 160)).to_numpy()
    assert light[..., :3].mean() > points[..., :3].mean() + 50
    assert not np.array_equal(volume, points)
    assert _drawn(volume) > 100


def test_render_takes_audio_and_extracts_it(tmp_path, monkeypatch):
    monkeypatch.setenv("LOUDSCAPE_CACHE_DIR", str(tmp_path / "cache"))
    song = tmp_path / "tone.wav"
    # The extractor's fixture signal, looped to 3 s so the default FFT has frames to show.
    soundfile.write(song, np.tile(fixture_signal(), (6, 1)), SAMPLE_RATE)
    picture = loudscape.render(song, size=(320, 200))
    assert _drawn(picture.to_numpy()) > 20
    assert list((tmp_path / "cache").glob("*.ply")), "the binary extracted nothing"


def test_save_writes_the_png_and_nothing_else(tmp_path):
    picture = loudscape.render(SONG, size=(160, 100))
    target = tmp_path / "shot.png"
    picture.save(target)
    assert target.read_bytes() == picture.png
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shot.png"]
    with pytest.raises(ExtractError, match="png"):
        picture.save(tmp_path / "shot.jpg")
    with pytest.raises(ExtractError, match="does not exist"):
        picture.save(tmp_path / "missing" / "shot.png")


def test_read_cloud_is_the_extractors_reader():
    cloud = loudscape.read_cloud(SONG)
    points, metadata = read_ply(SONG)
    assert np.array_equal(cloud.points, points) and cloud.metadata == metadata
    assert cloud.points.shape[1] == 5 and cloud.points.dtype == np.float32
    with pytest.raises(ExtractError, match="read_cloud reads .ply"):
        loudscape.read_cloud(ROOT / "data" / "demo_song.flac")


def test_bad_input_is_one_clear_error(tmp_path):
    with pytest.raises(ExtractError, match="no such file") as missing:
        loudscape.render(tmp_path / "nothing.ply")
    assert "nothing.ply" in str(missing.value)
    with pytest.raises(ExtractError, match="not one of"):
        loudscape.render(SONG, view="sideways")
    with pytest.raises(ExtractError, match="shape"):
        loudscape.render(np.zeros((10, 3), np.float32))
    with pytest.raises(ExtractError, match="NaN"):
        loudscape.render(np.full((10, 5), np.nan, np.float32))
    with pytest.raises(ExtractError, match="source must be"):
        loudscape.render(42)
    # The renderer's own error comes back as one line, naming the file.
    broken = tmp_path / "broken.ply"
    broken.write_text("not a cloud\n")
    with pytest.raises(ExtractError) as refused:
        loudscape.render(broken)
    assert "broken.ply" in str(refused.value) and "\n" not in str(refused.value)


def test_a_missing_binary_is_named(monkeypatch, tmp_path):
    monkeypatch.setenv("LOUDSCAPE_BIN", str(tmp_path / "no-such-loudscape"))
    with pytest.raises(ExtractError, match="LOUDSCAPE_BIN"):
        loudscape.render(SONG)


def _recording_binary(tmp_path: Path) -> Path:
    """A stand-in for the window: records its arguments and whether its input existed."""
    script = tmp_path / "fake-loudscape"
    log = tmp_path / "argv.txt"
    script.write_text(
        f"#!{sys.executable}\n"
        "import os, sys\n"
        f"with open({str(log)!r}, 'w') as f:\n"
        "    f.write('\\n'.join(sys.argv[1:] + [str(os.path.isfile(sys.argv[1]))]))\n"
    )
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    return script


def test_show_opens_the_window_on_the_source(tmp_path, monkeypatch):
    monkeypatch.setenv("LOUDSCAPE_BIN", str(_recording_binary(tmp_path)))
    loudscape.show(SONG, view="surface")
    assert (tmp_path / "argv.txt").read_text().split("\n") == [
        str(SONG),
        "--view",
        "surface",
        "True",
    ]
    # Arrays are written to a temporary cloud that exists while the window runs, then goes.
    process = loudscape.show(loudscape.read_cloud(SONG), wait=False)
    assert process.wait(timeout=30) == 0
    first, *_, existed = (tmp_path / "argv.txt").read_text().split("\n")
    assert first.endswith(".ply") and existed == "True"
    folder = Path(first).parent
    for _ in range(100):
        if not folder.exists():
            break
        time.sleep(0.05)
    assert not folder.exists()
