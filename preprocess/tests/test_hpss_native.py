"""The compiled running median (crates/median) against scipy.ndimage.median_filter, bit for bit.

``make native`` builds it into the package; ``make test-py`` sets LOUDSCAPE_REQUIRE_NATIVE=1,
under which a missing kernel fails these tests instead of leaving them to the scipy path.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from loudscape_extract import median_filter_axis, native, stft_magnitude
from loudscape_extract.errors import ExtractError

from conftest import musical_signal

scipy_ndimage = pytest.importorskip("scipy.ndimage")

REQUIRED = os.environ.get("LOUDSCAPE_REQUIRE_NATIVE") == "1"


@pytest.fixture
def kernel():
    if not native.available():
        if REQUIRED:
            pytest.fail(
                f"LOUDSCAPE_REQUIRE_NATIVE=1 but the compiled running median is not loaded "
                f"(file: {native.library_path()}; `make native` builds it)"
            )
        pytest.skip("the compiled running median is not built (make native)")


@pytest.fixture
def scipy_only(monkeypatch):
    """median_filter_axis as without the compiled kernel."""
    monkeypatch.setattr(native, "_loaded", True)
    monkeypatch.setattr(native, "_library", None)
    assert not native.available()


def test_kernel_is_loaded_where_required():
    if REQUIRED:
        assert native.available(), native.library_path()
    else:
        # Without the requirement either path is right; the answer must still be a bool.
        assert native.available() in (True, False)


def _reference(data, size, axis):
    shape = [1, 1]
    shape[axis] = size
    return scipy_ndimage.median_filter(data, size=shape, mode="reflect")


def _assert_bits_equal(data, size, axis):
    expected = _reference(data, size, axis)
    ours = median_filter_axis(data, size=size, axis=axis)
    assert ours.dtype == data.dtype and ours.shape == data.shape
    assert ours.flags.c_contiguous
    np.testing.assert_array_equal(ours.view(np.uint32), expected.view(np.uint32))


def _cases(rng, shape):
    """Random magnitudes, runs of a few values (ties), zeros, +inf and the smallest floats."""
    random = (rng.random(shape) ** 3).astype(np.float32)
    random[rng.random(shape) < 0.05] = 0.0
    ties = rng.integers(0, 3, shape).astype(np.float32) * np.float32(0.25)
    runs = np.repeat(rng.integers(0, 4, (shape[0], shape[1] // 5 + 1)), 5, axis=1)
    runs = runs[:, : shape[1]].astype(np.float32)
    extremes = rng.choice(
        np.array([0.0, np.inf, 1e-45, 3.4e38, 1.0], dtype=np.float32), size=shape
    ).astype(np.float32)
    return {"random": random, "ties": ties, "runs": runs, "extremes": extremes}


@pytest.mark.parametrize("size", [1, 3, 31, 33])
@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("shape", [(45, 67), (17, 23), (9, 40), (40, 9), (1, 50), (50, 1)])
def test_kernel_equals_scipy(kernel, shape, axis, size, rng):
    # Row counts that are not multiples of the 16 lanes; lengths below half a kernel (the
    # short axis of (9, 40), (1, 50), (50, 1) with sizes 31 and 33) padded by numpy's pad.
    for name, data in _cases(rng, shape).items():
        try:
            _assert_bits_equal(data, size, axis)
        except AssertionError as error:
            raise AssertionError(f"{name}: {error}") from None


@pytest.mark.parametrize("axis", [0, 1])
def test_kernel_equals_scipy_on_a_spectrogram(kernel, axis):
    magnitude = stft_magnitude(musical_signal(), n_fft=512, hop_length=128)
    assert magnitude.dtype == np.float32
    _assert_bits_equal(magnitude, 31, axis)
    # A view that is not contiguous (every other frame) gives the same as its copy.
    view = magnitude[:, ::2]
    np.testing.assert_array_equal(
        median_filter_axis(view, size=31, axis=axis), _reference(view, 31, axis)
    )


@pytest.mark.parametrize("axis", [0, 1])
def test_scipy_fallback_equals_the_kernel(kernel, axis, rng, monkeypatch):
    data = _cases(rng, (37, 53))["random"]
    with_kernel = median_filter_axis(data, size=31, axis=axis)
    monkeypatch.setattr(native, "_library", None)
    monkeypatch.setattr(native, "_loaded", True)
    np.testing.assert_array_equal(median_filter_axis(data, size=31, axis=axis), with_kernel)


@pytest.mark.parametrize("axis", [0, 1])
def test_without_the_kernel_scipy_gives_the_same(scipy_only, axis, rng):
    for data in _cases(rng, (21, 34)).values():
        _assert_bits_equal(data, 31, axis)


def test_negative_and_nan_floats_take_scipy(kernel, rng):
    # Negative floats (and NaN) do not sort as their bits: the float path answers.
    data = rng.standard_normal((20, 30)).astype(np.float32)
    np.testing.assert_array_equal(median_filter_axis(data, size=5, axis=1), _reference(data, 5, 1))


def test_kernel_refuses_bad_shapes(kernel):
    keys = np.arange(20, dtype=np.uint32).reshape(2, 10)
    with pytest.raises(ExtractError, match="even or zero"):
        native.median_rows(keys, 4)
    with pytest.raises(ExtractError, match="shorter than the window"):
        native.median_rows(keys, 11)
    np.testing.assert_array_equal(native.median_rows(keys, 3), keys[:, 1:-1])
    np.testing.assert_array_equal(native.median_columns(keys.T.copy(), 3), keys[:, 1:-1].T)


def test_a_kernel_run_does_not_import_scipy_ndimage(kernel):
    code = (
        "import sys, numpy as np\n"
        "from loudscape_extract import median_filter_axis, native\n"
        "assert native.available()\n"
        "median_filter_axis(np.ones((40, 50), np.float32), size=31, axis=0)\n"
        "median_filter_axis(np.ones((40, 50), np.float32), size=31, axis=1)\n"
        "assert 'scipy.ndimage' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
