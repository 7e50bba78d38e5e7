"""The package's one exception type."""

from __future__ import annotations

__all__ = ["ExtractError"]


class ExtractError(Exception):
    """Bad input or an impossible request: the message says what and names the offending value.

    Parameters
    ----------
    message : str
        What is wrong, with the offending value.
    path : str, optional
        The file the problem is about (input audio or output point cloud), when known. The CLI
        prints it at the start of its one-line error message.
    """

    def __init__(self, message: str, *, path: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.path = path

    def __str__(self) -> str:
        return f"{self.path}: {self.message}" if self.path else self.message
