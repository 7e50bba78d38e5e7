"""The command line's allocator settings: freed memory kept for the next block.

The extractor works block by block on arrays of a few to a few tens of MB (spectrogram spans,
padded median inputs, FFT segments, float64 sums). glibc's malloc gives blocks that large
back to the kernel when they are freed (``munmap``, or trimming the heap's top), so the next
block's arrays come back as fresh pages the kernel must zero first: on the 3:30 bench song
8 % of the CPU samples (``perf``) were the kernel clearing pages. :func:`keep_freed_memory`
raises glibc's limits (``mallopt``) so freed blocks stay in the heap and are reused: the same
peak memory (about 330 MB on that song), system time 0.38-0.50 s where it was 0.63-0.88 s.

Only the command line calls it (a process setting, not the library's to change under a
notebook). Elsewhere than glibc (macOS, musl) it does nothing.
"""

from __future__ import annotations

import ctypes
import sys

__all__ = ["keep_freed_memory"]

# glibc's <malloc.h> parameter numbers.
_M_TRIM_THRESHOLD = -1
_M_TOP_PAD = -2
_M_MMAP_THRESHOLD = -3

#: Arrays up to this size come from the heap, not from their own mapping (glibc's largest).
MMAP_THRESHOLD_BYTES = 32 << 20
#: Free memory at the heap's top kept up to this much instead of given back.
TRIM_THRESHOLD_BYTES = 1 << 30
#: Extra heap asked of the kernel each time it grows.
TOP_PAD_BYTES = 64 << 20


def keep_freed_memory() -> bool:
    """Keep freed memory in the process for reuse (glibc only); whether it was set.

    Examples
    --------
    >>> keep_freed_memory() in (True, False)
    True
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    settings = (
        (_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES),
        (_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES),
        (_M_TOP_PAD, TOP_PAD_BYTES),
    )
    return all(mallopt(number, value) == 1 for number, value in settings)
