"""SIGTERM as an exception, so ``finally`` blocks run: temporaries removed, workers stopped."""

from __future__ import annotations

import contextlib
import signal

__all__ = ["Terminated", "sigterm_raises"]


class Terminated(KeyboardInterrupt):
    """Raised in the main thread when the process receives SIGTERM.

    A :class:`KeyboardInterrupt`, so every cleanup path written for Ctrl+C covers it too.
    """


def _raise_terminated(signum, _frame):
    raise Terminated(f"received signal {signum}")


@contextlib.contextmanager
def sigterm_raises():
    """While active, SIGTERM raises :class:`Terminated` (the previous handler is restored)."""
    try:
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
