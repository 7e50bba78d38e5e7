"""Preloaded into each worker of the local Dask cluster (``--dask``): the worker ignores
SIGINT, so a Ctrl+C sent to the whole process group is left to the parent, which stops the
run and closes the cluster (see :mod:`loudscape_extract.timeline.engine`); and the worker's
``distributed`` loggers say only what is critical, as the parent's do: a song's failure is
reported once, by the parent, in our words, and a run stopped by SIGTERM or Ctrl+C must not
print the tracebacks of a worker's heartbeat or tasks cut off by the cluster closing."""

from __future__ import annotations

import logging
import signal


def dask_setup(worker) -> None:
    """Dask's preload hook, run in the worker process when the worker starts."""
    del worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
