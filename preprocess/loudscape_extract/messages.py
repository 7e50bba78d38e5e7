"""One-line messages: collapse whitespace, escape control characters, cap the length."""

from __future__ import annotations

__all__ = ["MAX_MESSAGE_CHARS", "one_line", "shorten"]

#: Longest line the command line prints (an echoed value is shortened to fit).
MAX_MESSAGE_CHARS = 400


def one_line(text: object, *, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` on one line: whitespace runs become one space, other control characters are
    escaped, and anything past ``limit`` characters is cut with an ellipsis."""
    flat = " ".join(str(text).split())
    flat = "".join(c if c.isprintable() else repr(c)[1:-1] for c in flat)
    if len(flat) > limit:
        flat = flat[: limit - 3] + "..."
    return flat


def shorten(value: object, limit: int = 80) -> str:
    """An echoed value (a path, a manifest cell) as ``repr``, cut in the middle past ``limit``."""
    text = repr(str(value))
    if len(text) <= limit:
        return text
    half = (limit - 3) // 2
    return text[:half] + "..." + text[-half:]
