"""One BLAS thread for the command line.

numpy's OpenBLAS starts a thread per core and, after each call it shares out (Song and
Timeline mode's per-frame A-weighted power is one matrix-vector product per spectral block),
keeps those threads spinning while they wait for the next: on the 3:30 bench song about 4 %
of the CPU samples (``perf``) were ``blas_thread_server`` with nothing to do. The products are
small, so :func:`one_blas_thread` runs them on the calling thread. A Song file is byte-identical
either way; a timeline's hp and scalar values can move by float32 rounding (at most 2.4e-6 on
the eight-track bench timeline), because OpenBLAS sums a product's terms in an order that
depends on its thread count: with one thread they no longer depend on the machine's number of
cores. Only the command line calls it; the library leaves a notebook's BLAS alone.
"""

from __future__ import annotations

import ctypes

__all__ = ["one_blas_thread"]

_SETTERS = (
    "scipy_openblas_set_num_threads64_",
    "scipy_openblas_set_num_threads",
    "openblas_set_num_threads64_",
    "openblas_set_num_threads",
)


def one_blas_thread() -> int:
    """Set every OpenBLAS loaded in the process (numpy's, scipy's) to one thread; how many.

    Reads ``/proc/self/maps`` (Linux); elsewhere, or with another BLAS, it does nothing.

    Examples
    --------
    >>> one_blas_thread() >= 0
    True
    """
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = {line.split()[-1] for line in maps if "openblas" in line.lower()}
    except OSError:
        return 0
    count = 0
    for path in sorted(p for p in paths if p.startswith("/")):
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for name in _SETTERS:
            setter = getattr(library, name, None)
            if setter is not None:
                setter.argtypes = [ctypes.c_int]
                setter.restype = None
                setter(1)
                count += 1
                break
    return count
