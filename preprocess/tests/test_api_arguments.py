"""The notebook API's arguments (``loudscape.render``, ``show``, ``read_cloud``): every bad one
is the package's one exception, ExtractError, raised before the binary runs, in one line that
names the argument and its value (never ValueError from inside json or numpy, never the
binary's "For more information, try '--help'").

``$LOUDSCAPE_BIN`` is a stand-in that fails loudly if it is ever run, so an argument that
slips through to the binary fails these tests; no renderer is needed.
"""

from __future__ import annotations

import math
import os
import re
import stat
import sys

import numpy as np
import pytest

import loudscape
from loudscape import ExtractError, LoudscapeWarning

POINTS = np.full((4, 5), 0.5, np.float32)


@pytest.fixture(autouse=True)
def _stand_in_binary(tmp_path, monkeypatch):
    script = tmp_path / "loudscape-stand-in"
    script.write_text(
        f"#!{sys.executable}\nimport sys\n"
        "print('error: the binary was run with bad arguments', file=sys.stderr)\nsys.exit(2)\n"
    )
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("LOUDSCAPE_BIN", str(script))


def _refused(call, *words: str) -> str:
    with pytest.raises(ExtractError) as caught:
        call()
    message = str(caught.value)
    assert "\n" not in message and "--help" not in message and "binary was run" not in message
    for word in words:
        assert word in message, (word, message)
    return message


@pytest.mark.parametrize(
    "size",
    [
        (math.nan, 10),
        "640x480",
        (640,),
        (640, 480, 3),
        (640.5, 480),
        (0, 480),
        (640, -1),
        (True, 480),
        None,
        (1e10, 480),
        ("640", "480"),
        640,
    ],
    ids=repr,
)
def test_a_bad_size_names_size_and_its_value(size):
    message = _refused(lambda: loudscape.render(POINTS, size=size), "size must be")
    assert repr(size)[:20] in message


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("point_size", -1),
        ("point_size", math.nan),
        ("point_size", "3"),
        ("point_size", 0),
        ("point_size", 1000),
        ("iso", math.nan),
        ("iso", 2.0),
        ("iso", "0.5"),
        ("camera", (0, 0, math.nan)),
        ("camera", "1,2,3"),
        ("camera", (0, 0, -1)),
        ("camera", (0, 0)),
        ("labels", "no"),
        ("legend", None),
        ("timeout", -1),
        ("timeout", math.nan),
        ("timeout", "10"),
    ],
    ids=repr,
)
def test_a_bad_number_names_the_argument_and_its_value(argument, value):
    _refused(lambda: loudscape.render(POINTS, **{argument: value}), argument, repr(value)[:20])


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        ("view", "sideways"),
        ("view", "POINTS"),
        ("view", None),
        ("view", 3),
        ("method", "marching"),
        ("colormap", "jet"),
        ("background", "grey"),
        ("freq_axis", "bark"),
    ],
    ids=repr,
)
def test_an_unknown_name_is_listed_with_the_known_ones(argument, value):
    _refused(
        lambda: loudscape.render(POINTS, **{argument: value}),
        f"{argument}={value!r}",
        "is not one of",
    )


def test_show_checks_its_arguments_too():
    _refused(lambda: loudscape.show(POINTS, view="sideways"), "view='sideways'")
    _refused(lambda: loudscape.show(POINTS, wait="yes"), "wait")


@pytest.mark.parametrize(
    "metadata",
    [
        {"axes": {"x": {"min": math.nan, "max": 1}}},
        {"duration_s": math.inf},
        {"songs": [{"year": np.float64("nan")}]},
    ],
    ids=repr,
)
def test_nan_metadata_names_where_it_is(metadata):
    message = _refused(lambda: loudscape.render(POINTS, metadata=metadata), "metadata[", "NaN")
    assert "JSON" in message
    # The same metadata in a (points, metadata) pair, a Cloud.
    _refused(lambda: loudscape.render((POINTS, metadata)), "source's metadata[")
    _refused(lambda: loudscape.render(loudscape.Cloud(POINTS, metadata)), "source's metadata[")


@pytest.mark.parametrize(
    ("metadata", "words"),
    [
        ([1, 2], ("metadata must be a dict", "list")),
        ("axes", ("metadata must be a dict",)),
        ({1: "a"}, ("key 1", "strings")),
        ({"when": object()}, ("metadata['when']", "not JSON")),
        ({"raw": b"\x00"}, ("metadata['raw']", "bytes")),
    ],
    # Without the object's address, so that every test process names the cases alike.
    ids=lambda value: re.sub(r" at 0x[0-9a-f]+", "", repr(value)),
)
def test_metadata_that_is_not_json_is_refused(metadata, words):
    _refused(lambda: loudscape.render(POINTS, metadata=metadata), *words)


@pytest.mark.parametrize(
    "points",
    [
        np.full((4, 5), "a"),
        np.full((4, 5), "0.5"),  # numbers as text are refused too, not parsed
        np.full((4, 5), 0.5, complex),
        np.full((4, 5), True),
        [[0.5] * 5, [0.5] * 4],  # ragged
        [["a", "b", "c", "d", "e"]],
    ],
    ids=lambda p: type(p).__name__ + str(getattr(p, "dtype", "")),
)
def test_arrays_that_are_not_numbers_are_refused(points):
    _refused(lambda: loudscape.render(points), "points must")


def test_numpy_numbers_in_metadata_are_written_as_numbers(tmp_path, monkeypatch):
    # json.dumps refuses numpy's int64 and float32 (TypeError); the API writes them as the
    # numbers they are. The binary is a stand-in that keeps the cloud it is given.
    import loudscape.api as api
    from loudscape_extract.ply import read_ply

    kept = {}

    def keep(command, *, timeout):
        kept["metadata"] = read_ply(command[-1])[1]
        raise ExtractError("stop here")

    monkeypatch.setattr(api, "_run", keep)
    metadata = {"count": np.int64(3), "level": np.float32(1.5), "flag": np.bool_(True)}
    _refused(lambda: loudscape.render(POINTS, metadata=metadata), "stop here")
    assert {k: kept["metadata"][k] for k in metadata} == {"count": 3, "level": 1.5, "flag": True}
    _refused(lambda: loudscape.render(POINTS, metadata={"x": np.float32("nan")}), "metadata['x']")


def test_arrays_out_of_float32_range_are_refused():
    _refused(lambda: loudscape.render(np.full((4, 5), 1e300)), "NaN or infinite")


def test_read_cloud_refuses_what_is_not_a_file_name(tmp_path):
    _refused(lambda: loudscape.read_cloud(42), "path must be a file name", "42")
    _refused(lambda: loudscape.read_cloud(None), "path must be a file name")
    _refused(lambda: loudscape.read_cloud(tmp_path / "a.flac"), "read_cloud reads .ply")


def test_a_missing_source_is_named_before_the_binary_runs(tmp_path):
    _refused(lambda: loudscape.render(tmp_path / "-i.ply"), "no such file", "-i.ply")
    fifo = tmp_path / "pipe.ply"
    os.mkfifo(fifo)
    _refused(lambda: loudscape.render(fifo), "FIFO", "pipe.ply")


def test_cloud_warnings_are_the_metadatas():
    metadata = {
        "source": {"path": "song.flac"},
        "warnings": [
            {"kind": "truncated", "message": "decoded 14.12 s of the 30.00 s"},
            {"kind": "dc_offset", "message": "DC offset", "path": "other.flac"},
            "not an object",
        ],
    }
    cloud = loudscape.Cloud(POINTS, metadata)
    assert cloud.warnings == (
        "song.flac: decoded 14.12 s of the 30.00 s",
        "other.flac: DC offset",
    )
    points, meta = cloud  # still the pair
    assert meta is metadata
    assert loudscape.Cloud(POINTS, {}).warnings == ()


def test_the_warning_class_is_exported():
    assert issubclass(LoudscapeWarning, UserWarning)
    assert "LoudscapeWarning" in loudscape.__all__
