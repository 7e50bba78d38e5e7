"""Checks on the files a command reads and writes, made before any work.

- :func:`check_output_path`: the output can be created, has the right extension, is not a
  special file, and is none of the inputs (same path, or the same file through a symbolic or
  hard link: ``os.stat`` device and inode compared), so no command writes over its input.
- :func:`check_regular_input`: an input is an existing regular file (a FIFO or a device would
  block a decoder forever).
- :func:`open_regular_input`: the same check made on the opened file (no window between the
  check and the open), without ever blocking on a FIFO.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
from collections.abc import Iterable

from loudscape_extract.errors import ExtractError

__all__ = [
    "atomic_output",
    "check_output_path",
    "check_regular_input",
    "fsync_directory",
    "fsync_path",
    "open_regular_input",
    "same_file",
    "write_failure",
]


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def check_regular_input(path: str, *, what: str = "file") -> os.stat_result:
    """``os.stat`` of ``path``; :class:`ExtractError` unless it is a readable regular file.

    The OS error is reported once (``no such file``, ``permission denied``), and a FIFO or
    device is refused at once instead of blocking on it.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise ExtractError(f"no such {what}", path=path) from None
    except OSError as exc:
        raise ExtractError(f"cannot open {what} ({exc.strerror or exc})", path=path) from None
    if not stat.S_ISREG(info.st_mode):
        raise ExtractError(f"is {_kind(info.st_mode)}, not a regular {what}", path=path)
    if not os.access(path, os.R_OK):
        raise ExtractError("permission denied", path=path)
    return info


def open_regular_input(path: str, *, what: str = "file"):
    """``path`` opened for reading in binary, refused unless it is a regular file.

    The file is opened without blocking (``O_NONBLOCK``: a FIFO with no writer opens at once)
    and checked with ``fstat`` on the open descriptor, so a FIFO, a device (a link to
    ``/dev/zero``), a socket or a directory is one clear :class:`ExtractError` at once, and
    nothing is read from it.

    Returns
    -------
    io.BufferedReader
        The open file; the caller closes it.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        descriptor = os.open(path, flags)
    except FileNotFoundError:
        raise ExtractError(f"no such {what}", path=path) from None
    except IsADirectoryError:
        raise ExtractError(f"is a directory, not a regular {what}", path=path) from None
    except OSError as exc:
        raise ExtractError(f"cannot open {what} ({exc.strerror or exc})", path=path) from None
    try:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise ExtractError(f"is {_kind(mode)}, not a regular {what}", path=path)
        if hasattr(os, "set_blocking"):
            os.set_blocking(descriptor, True)
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def same_file(a: str, b: str) -> bool:
    """True when ``a`` and ``b`` name one file: same normalized path, or same device and inode
    (symbolic links followed, hard links included). False when either does not exist."""
    if os.path.normcase(os.path.abspath(a)) == os.path.normcase(os.path.abspath(b)):
        return True
    try:
        first, second = os.stat(a), os.stat(b)
    except OSError:
        return False
    return (first.st_dev, first.st_ino) == (second.st_dev, second.st_ino)


def check_output_path(
    output: str,
    *,
    inputs: Iterable[str] = (),
    extensions: tuple[str, ...] = (".ply",),
    flag: str = "-o",
) -> None:
    """Fail before any work when ``output`` cannot or must not be written.

    Parameters
    ----------
    output : str
        The file the command will write.
    inputs : iterable of str
        Files the command reads; ``output`` must be none of them.
    extensions : tuple of str
        Accepted extensions (lower case, with the dot); empty accepts any.
    flag : str
        The option that sets ``output``, named in the message.

    Raises
    ------
    ExtractError
        Wrong extension, the output is one of the inputs, is a directory or another non-regular
        file, or its directory is missing or not writable.
    """
    for source in inputs:
        if same_file(output, source):
            same = "is the input" if output == source else f"is the same file as input {source}"
            raise ExtractError(
                f"refusing to write over an input: the output {same}; "
                f"choose another name with {flag}",
                path=output,
            )
    extension = os.path.splitext(output)[1].lower()
    if extensions and extension not in extensions:
        wanted = " or ".join(extensions)
        raise ExtractError(
            f"output must end with {wanted} (got {extension or 'no extension'!r}); "
            f"choose another name with {flag}",
            path=output,
        )
    try:
        info = os.stat(output)
    except OSError:
        info = None
    if info is not None and not stat.S_ISREG(info.st_mode):
        raise ExtractError(f"output path is {_kind(info.st_mode)}", path=output)
    directory = os.path.dirname(os.path.abspath(output))
    if not os.path.isdir(directory):
        raise ExtractError(f"output directory {directory!r} does not exist", path=output)
    if not os.access(directory, os.W_OK):
        raise ExtractError(f"output directory {directory!r} is not writable", path=output)


@contextlib.contextmanager
def atomic_output(output: str):
    """Yield a temporary path beside ``output``; on success it replaces ``output``, on any
    error or interrupt (SIGTERM included, see :mod:`loudscape_extract.interrupts`) it is
    removed, so ``output`` is never left half written."""
    directory = os.path.dirname(os.path.abspath(output))
    base, extension = os.path.splitext(os.path.basename(output))
    temporary = os.path.join(directory, f".{base}.{os.getpid()}.tmp{extension}")
    try:
        yield temporary
        os.chmod(temporary, 0o666 & ~_umask())
        fsync_path(temporary)
        os.replace(temporary, output)
        fsync_directory(directory)
    except OSError as exc:
        raise ExtractError(write_failure(exc, directory=directory), path=output) from exc
    finally:
        with contextlib.suppress(OSError):
            os.unlink(temporary)


def fsync_path(path: str) -> None:
    """Flush a written file's data to the disk (before it is renamed into place, so a power
    cut cannot leave a renamed file whose data never arrived)."""
    descriptor = os.open(path, os.O_RDONLY)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


def fsync_directory(directory: str) -> None:
    """Flush a folder's entries (a rename into it) to the disk; best effort: a file system
    that cannot sync a folder does not fail the write."""
    with contextlib.suppress(OSError):
        descriptor = os.open(directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)


def write_failure(exc: OSError, *, directory: str) -> str:
    """The one-line reason a write into ``directory`` failed: a full disk or quota says so
    plainly (numpy's "N requested and M written" becomes "no space left")."""
    full = exc.errno in (errno.ENOSPC, errno.EDQUOT) or "requested and" in str(exc)
    if full:
        try:
            stats = os.statvfs(directory)
            free = f", {stats.f_bavail * stats.f_frsize:,} bytes free"
        except OSError:
            free = ""
        what = "disk quota exceeded" if exc.errno == errno.EDQUOT else "no space left"
        return f"{what} on the device of {directory!r}{free}; nothing was written"
    return f"cannot write file ({exc.strerror or exc})"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
