"""Real FFTs from scipy's pocketfft without importing ``scipy.fft``.

``scipy.fft`` is the extractor's FFT (the STFT, the K-weighting and true-peak convolutions),
but importing it costs about 0.2 s of wall time and 0.3 CPU-seconds (its array-API layer and
backend machinery), a tenth of a 3-minute song's whole extraction. The transforms themselves
are one compiled module, ``scipy.fft._pocketfft.pypocketfft``; :func:`rfft` and :func:`irfft`
call it as ``scipy.fft.rfft`` and ``scipy.fft.irfft`` do (the same arguments after the same
checks), so the results are the same bits (``preprocess/tests/test_fft.py``). The module is
loaded from scipy's installed files under its own name in ``sys.modules``, so a later
``import scipy.fft`` in the same process uses this one copy. Where it cannot be found (another
scipy layout), ``scipy.fft`` itself is used.

>>> import numpy as np
>>> float(irfft(rfft(np.array([1.0, 2.0, 3.0, 4.0])), 4)[2])
3.0
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys

import numpy as np

__all__ = ["rfft", "irfft"]

_NAME = "scipy.fft._pocketfft.pypocketfft"


def _load_pocketfft():
    """scipy's compiled pocketfft module, or None where it is not where scipy 1.x keeps it."""
    loaded = sys.modules.get(_NAME)
    if loaded is not None:
        return loaded
    spec = importlib.util.find_spec("scipy")  # a top-level spec: scipy is not imported
    if spec is None or not spec.submodule_search_locations:
        return None
    for root in spec.submodule_search_locations:
        folder = os.path.join(root, "fft", "_pocketfft")
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, "pypocketfft" + suffix)
            if not os.path.isfile(path):
                continue
            loader = importlib.machinery.ExtensionFileLoader(_NAME, path)
            module_spec = importlib.util.spec_from_file_location(_NAME, path, loader=loader)
            if module_spec is None:
                continue
            try:
                module = importlib.util.module_from_spec(module_spec)
                loader.exec_module(module)
            except ImportError:
                return None
            if not (hasattr(module, "r2c") and hasattr(module, "c2r")):
                return None
            sys.modules[_NAME] = module
            return module
    return None


_POCKETFFT = _load_pocketfft()


def _as_float(x) -> np.ndarray:
    """As ``scipy.fft``'s ``_asfarray``: float16 to float32, non-float to float64, native byte
    order, aligned."""
    x = np.asarray(x)
    if x.dtype == np.float16:
        return np.asarray(x, np.float32)
    if x.dtype.kind not in "fc":
        return np.asarray(x, np.float64)
    dtype = x.dtype.newbyteorder("=")
    return np.array(x, dtype=dtype, copy=None if x.flags["ALIGNED"] else True)


def _fit(x: np.ndarray, n: int, axis: int) -> np.ndarray:
    """``x`` cut or zero-padded to ``n`` along ``axis`` (``scipy.fft``'s ``_fix_shape_1d``)."""
    if n < 1:
        raise ValueError(f"invalid number of data points ({n}) specified")
    if x.shape[axis] >= n:
        index = [slice(None)] * x.ndim
        index[axis] = slice(0, n)
        return x[tuple(index)]
    shape = list(x.shape)
    shape[axis] = n
    z = np.zeros(shape, x.dtype)
    index = [slice(None)] * x.ndim
    index[axis] = slice(0, x.shape[axis])
    z[tuple(index)] = x
    return z


def rfft(x, n: int | None = None, axis: int = -1) -> np.ndarray:
    """``scipy.fft.rfft(x, n, axis)``: the same bits."""
    if _POCKETFFT is None:
        import scipy.fft

        return scipy.fft.rfft(x, n, axis=axis)
    tmp = _as_float(x)
    if not np.isrealobj(tmp):
        raise TypeError("x must be a real sequence")
    if n is not None:
        tmp = _fit(tmp, n, axis)
    elif tmp.shape[axis] < 1:
        raise ValueError(f"invalid number of data points ({tmp.shape[axis]}) specified")
    # Forward, no scaling ("backward" normalization), one worker: scipy.fft's defaults.
    return _POCKETFFT.r2c(tmp, (axis,), True, 0, None, 1)


def irfft(x, n: int | None = None, axis: int = -1) -> np.ndarray:
    """``scipy.fft.irfft(x, n, axis)``: the same bits."""
    if _POCKETFFT is None:
        import scipy.fft

        return scipy.fft.irfft(x, n, axis=axis)
    tmp = _as_float(x)
    if np.isrealobj(tmp):
        tmp = tmp + 0.0j
    if n is None:
        n = (tmp.shape[axis] - 1) * 2
        if n < 1:
            raise ValueError(f"Invalid number of data points ({n}) specified")
    else:
        tmp = _fit(tmp, n // 2 + 1, axis)
    # Inverse, scaled by 1/n ("backward" normalization), one worker.
    return _POCKETFFT.c2r(tmp, (axis,), n, False, 2, None, 1)
