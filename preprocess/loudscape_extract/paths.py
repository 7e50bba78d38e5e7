"""Checks on the files a command is about to write."""

from __future__ import annotations

import os

from loudscape_extract.errors import ExtractError

__all__ = ["check_output_path"]


def check_output_path(output: str) -> None:
    """Fail early when the output cannot be created (missing directory, or a directory)."""
    directory = os.path.dirname(os.path.abspath(output))
    if os.path.isdir(output):
        raise ExtractError("output path is a directory", path=output)
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=output)
    if not os.access(directory, os.W_OK):
        raise ExtractError(f"output directory {directory!r} is not writable", path=output)
