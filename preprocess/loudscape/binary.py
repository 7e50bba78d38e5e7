"""Finding the ``loudscape`` binary the Python API drives."""

from __future__ import annotations

import os
import shutil
import sys
import sysconfig
from pathlib import Path

from loudscape_extract.errors import ExtractError

__all__ = ["candidates", "find_binary"]

NAME = "loudscape.exe" if sys.platform == "win32" else "loudscape"


def candidates() -> list[Path]:
    """Every place looked in without ``$LOUDSCAPE_BIN``, in order.

    Returns
    -------
    list of Path
        The scripts folder of this Python environment (where ``pip install`` puts the binary);
        a checkout's ``target/release`` and ``target/debug`` builds, the newer first, when this
        package is imported from a checkout; then every folder on ``PATH``.
    """
    places = [Path(sysconfig.get_path("scripts")) / NAME]
    checkout = Path(__file__).resolve().parents[2]
    builds = [checkout / "target" / kind / NAME for kind in ("release", "debug")]
    builds.sort(key=lambda p: p.stat().st_mtime if p.is_file() else 0.0, reverse=True)
    places.extend(builds)
    places.extend(Path(d) / NAME for d in os.environ.get("PATH", "").split(os.pathsep) if d)
    return places


def find_binary() -> Path:
    """The ``loudscape`` binary: ``$LOUDSCAPE_BIN`` when set (and then only there), else the
    first of :func:`candidates` that exists.

    Returns
    -------
    Path

    Raises
    ------
    ExtractError
        No binary was found, or ``$LOUDSCAPE_BIN`` names no file.
    """
    explicit = os.environ.get("LOUDSCAPE_BIN")
    if explicit:
        if Path(explicit).is_file():
            return Path(explicit)
        raise ExtractError("$LOUDSCAPE_BIN names no file", path=explicit)
    for place in candidates():
        if place.is_file():
            return place
    found = shutil.which("loudscape")
    if found:
        return Path(found)
    raise ExtractError(
        "the loudscape binary was not found in this environment's scripts folder, a checkout's "
        "target/ or PATH: install with `pip install .` or build with `cargo build`"
    )
