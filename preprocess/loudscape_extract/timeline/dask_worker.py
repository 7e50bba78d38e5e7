"""Preloaded into each worker of the local Dask cluster (``--dask``): the worker ignores
SIGINT, so a Ctrl+C sent to the whole process group is left to the parent, which stops the
run and closes the cluster (see :mod:`loudscape_extract.timeline.engine`)."""

from __future__ import annotations

import signal


def dask_setup(worker) -> None:
    """Dask's preload hook, run in the worker process when the worker starts."""
    del worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)
