"""The extractor's compiled running median (crates/median), loaded with ctypes when built.

``pip install .`` from the checkout builds it into this package (``_median`` with the
interpreter's extension suffix); ``make native`` builds it for the development venv
(``_median.so``, ``.dylib`` or ``.dll``). Without it (``pip install preprocess/`` alone) the
HPSS medians come from scipy, the same bits, slower. ``LOUDSCAPE_NATIVE=0`` leaves it unused.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
import os
import sys

import numpy as np

from loudscape_extract.errors import ExtractError

__all__ = ["available", "library_path", "median_columns", "median_rows"]

_PLATFORM_SUFFIX = {"win32": ".dll", "darwin": ".dylib"}.get(sys.platform, ".so")
_ERRORS = {
    1: "a null pointer",
    2: "an even or zero window size",
    3: "a row shorter than the window",
    4: "a shape too large",
    5: "an internal failure",
}

_library: ctypes.CDLL | None = None
_loaded = False


def library_path() -> str | None:
    """The kernel's file in this package, or None when it was not built."""
    folder = os.path.dirname(os.path.abspath(__file__))
    for suffix in (_PLATFORM_SUFFIX, *importlib.machinery.EXTENSION_SUFFIXES):
        path = os.path.join(folder, "_median" + suffix)
        if os.path.isfile(path):
            return path
    return None


def _load() -> ctypes.CDLL | None:
    global _library, _loaded
    if _loaded:
        return _library
    _loaded = True
    if os.environ.get("LOUDSCAPE_NATIVE") == "0":
        return None
    path = library_path()
    if path is None:
        return None
    try:
        library = ctypes.CDLL(path)
        for name in ("loudscape_median_rows", "loudscape_median_columns"):
            function = getattr(library, name)
            function.argtypes = [
                ctypes.c_void_p,
                ctypes.c_size_t,
                ctypes.c_size_t,
                ctypes.c_size_t,
                ctypes.c_void_p,
            ]
            function.restype = ctypes.c_int
    except (OSError, AttributeError):
        # A file of another platform or an older build: scipy does the work.
        return None
    _library = library
    return _library


def available() -> bool:
    """Whether the compiled running median is loaded (and not turned off)."""
    return _load() is not None


def _call(name: str, keys: np.ndarray, outer: int, inner: int, size: int, shape) -> np.ndarray:
    library = _load()
    if library is None:
        raise ExtractError("the compiled running median is not loaded")
    keys = np.ascontiguousarray(keys, dtype=np.uint32)
    out = np.empty(shape, dtype=np.uint32)
    code = getattr(library, name)(keys.ctypes.data, outer, inner, size, out.ctypes.data)
    if code != 0:
        reason = _ERRORS.get(code, f"error {code}")
        raise ExtractError(f"the running median refused {keys.shape} (size {size}): {reason}")
    return out


def median_rows(padded: np.ndarray, size: int) -> np.ndarray:
    """Running medians (odd window ``size``) along each row of the 2-D ``uint32`` array
    ``padded``: for a row of length ``n``, the ``n - size + 1`` medians of the windows fully
    inside it."""
    rows, length = padded.shape
    return _call("loudscape_median_rows", padded, rows, length, size, (rows, length - size + 1))


def median_columns(padded: np.ndarray, size: int) -> np.ndarray:
    """:func:`median_rows` down each column of ``padded``."""
    length, columns = padded.shape
    return _call(
        "loudscape_median_columns", padded, length, columns, size, (length - size + 1, columns)
    )
