"""The notebook API (``import loudscape``): pictures drawn by the ``loudscape`` binary.

The binary is ``$LOUDSCAPE_BIN`` (``make test-mesh`` sets ``target/debug/loudscape``), which
the package itself honours; the pictures come from the same ``loudscape render`` the commands
run, so these tests check the wiring (arguments, inputs, outputs, errors), not the drawing.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import soundfile

import loudscape
import loudscape.api as api
from loudscape_extract import ExtractError, read_ply, write_ply
from loudscape_fixtures.song import SAMPLE_RATE, fixture_signal

ROOT = Path(__file__).resolve().parents[2]
SONG = ROOT / "data" / "demo_song.ply"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape")).absolute()


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


# --- warnings: said once, as LoudscapeWarning, and kept on the picture ----------------------


def _rendered_with_warnings(source, **options):
    """render(source) with every LoudscapeWarning recorded (none filtered as seen before)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        picture = loudscape.render(source, size=(160, 100), **options)
    said = [str(w.message) for w in caught if issubclass(w.category, loudscape.LoudscapeWarning)]
    return picture, said


def _song(path: Path, stereo: np.ndarray) -> Path:
    soundfile.write(path, stereo, SAMPLE_RATE)
    return path


def _long_fixture() -> np.ndarray:
    return np.tile(fixture_signal(), (6, 1))  # 3 s, stereo


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("LOUDSCAPE_CACHE_DIR", str(tmp_path / "cache"))


def test_a_truncated_flac_warns_once_and_the_picture_keeps_it(tmp_path, cache):
    whole = (ROOT / "data" / "demo_song.flac").read_bytes()
    cut = tmp_path / "trunc.flac"
    cut.write_bytes(whole[: len(whole) // 2])
    for attempt in ("extracted", "from the cache"):
        picture, said = _rendered_with_warnings(cut)
        assert len(said) == 1, (attempt, said)
        assert said[0].startswith(f"{cut}: truncated or corrupt audio: decoded "), said
        assert picture.warnings == tuple(said), attempt
        assert "1 warning" in repr(picture)
    # A name that is not UTF-8: said once too, the name as given (bad bytes shown as U+FFFD).
    odd = tmp_path / os.fsdecode(b"trunc\xff.flac")
    odd.write_bytes(cut.read_bytes())
    picture, said = _rendered_with_warnings(odd)
    shown = os.fsencode(str(odd)).decode("utf-8", "replace")
    assert len(said) == 1 and said[0].startswith(f"{shown}: truncated or corrupt"), said


def test_corrupt_ogg_and_antiphase_input_warn(tmp_path, cache):
    ogg = _song(tmp_path / "damaged.ogg", _long_fixture())
    data = bytearray(ogg.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 64] = bytes(b ^ 0xFF for b in data[middle : middle + 64])
    ogg.write_bytes(bytes(data))
    picture, said = _rendered_with_warnings(ogg)
    assert len(said) == 1 and said[0].startswith(f"{ogg}: "), said
    assert "corrupt" in said[0] and picture.warnings == tuple(said)

    left = _long_fixture()[:, 0]
    antiphase = _song(tmp_path / "antiphase.wav", np.stack([left, -left], axis=1))
    picture, said = _rendered_with_warnings(antiphase)
    assert len(said) == 1 and said[0].startswith(f"{antiphase}: "), said
    assert "cancel" in said[0] and picture.warnings == tuple(said)


def test_a_clean_song_says_nothing(tmp_path, cache):
    picture, said = _rendered_with_warnings(_song(tmp_path / "clean.wav", _long_fixture()))
    assert said == [] and picture.warnings == ()


def test_a_clouds_own_warnings_are_said_once_naming_its_source_not_a_temporary(tmp_path):
    points, metadata = read_ply(SONG)
    metadata = {
        **metadata,
        "source": {**metadata.get("source", {}), "path": "song.flac"},
        "warnings": [{"kind": "truncated", "message": "decoded 14.12 s of the 30.00 s"}],
    }
    expected = ["song.flac: decoded 14.12 s of the 30.00 s"]
    picture, said = _rendered_with_warnings((points, metadata))
    assert said == expected and list(picture.warnings) == expected
    # The same cloud as a file: its warnings name the file as given.
    cloud = tmp_path / "warned.ply"
    write_ply(cloud, points=points, metadata=metadata)
    picture, said = _rendered_with_warnings(cloud)
    assert said == [f"{cloud}: decoded 14.12 s of the 30.00 s"], said
    assert loudscape.read_cloud(cloud).warnings == tuple(expected)


def test_a_file_named_like_an_option_is_drawn(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("-i.ply", "--help.ply", "-"):
        (tmp_path / name).write_bytes(SONG.read_bytes())
        picture = loudscape.render(name, size=(160, 100))
        assert _drawn(picture.to_numpy()) > 20, name


def test_values_that_look_like_options_reach_the_renderer():
    # A negative azimuth and the smallest point size pass as values, not options.
    picture = loudscape.render(SONG, size=(160, 100), camera=(-35, -10, 4), point_size=0.5)
    assert _drawn(picture.to_numpy()) > 20


@pytest.mark.parametrize(
    ("argument", "option"),
    [
        ("view", "view"),
        ("method", "method"),
        ("colormap", "colormap"),
        ("background", "background"),
        ("freq_axis", "freq-axis"),
    ],
)
def test_the_names_checked_in_python_are_the_renderers(tmp_path, argument, option):
    """The lists render checks its names against are the binary's own (its usage error
    lists the possible values), so the two cannot drift apart."""
    if argument == "view":
        # The views of one cloud: the window's --view (render's also takes the compare's).
        command = [str(BINARY), "--view=bogus", str(SONG)]
    else:
        command = [str(BINARY), "--quiet", "render", f"--{option}=bogus", "--size=64x64"]
        command += [f"--output={tmp_path / 'x.png'}", "--", str(SONG)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stderr
    listed = done.stderr.rsplit("[possible values: ", 1)[1].split("]", 1)[0]
    known = {
        "view": api.VIEWS,
        "method": api.METHODS,
        "colormap": api.COLORMAPS,
        "background": api.BACKGROUNDS,
        "freq_axis": api.FREQ_AXES,
    }[argument]
    assert tuple(listed.split(", ")) == known, done.stderr
