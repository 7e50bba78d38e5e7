"""Per-stage progress lines on stderr."""

from __future__ import annotations

import sys
import time

from loudscape_extract.version import PROG

__all__ = ["Progress"]


class Progress:
    """Per-stage progress lines on stderr, only when enabled (stderr is a TTY and not quiet)."""

    def __init__(self, *, enabled: bool) -> None:
        self.enabled = enabled
        self.start = time.perf_counter()

    def __call__(self, message: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            print(f"{PROG}: [{elapsed:6.2f} s] {message}", file=sys.stderr, flush=True)
