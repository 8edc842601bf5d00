"""Reading input files safely and writing output files atomically.

Every file tactile_kb reads (rule files, finger layouts, exploration records) goes through
:func:`read_text`: only a regular file is read (a device such as ``/dev/zero`` or a named pipe
is refused at once, without blocking), at most ``max_bytes`` of it, and text that is not UTF-8
is reported at the line and column of the first bad byte.

Every file tactile_kb writes (pictures, records, reports) goes through :func:`atomic_write`: the
bytes go to a fresh temporary file in the target's directory (a unique name, so a symlink
planted at a predictable name is never followed), are flushed to disk, and only then replace
the target with one rename. A failure or a kill at any point leaves the old target as it was.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> atomic_write(d / "a.txt", lambda f: f.write(b"hello\\n"))
>>> read_text(d / "a.txt", max_bytes=100)
'hello\\n'
>>> read_text(d, max_bytes=100)
Traceback (most recent call last):
...
tactile_kb.files.InputFileError: not a regular file (a directory)
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO

__all__ = [
    "MAX_RECORD_BYTES",
    "MAX_YAML_BYTES",
    "InputFileError",
    "atomic_write",
    "decode_utf8",
    "read_bytes",
    "read_text",
]

MAX_YAML_BYTES = 4 * 1024 * 1024
"""The largest rule file or finger layout read (4 MiB; the packaged rule files are < 10 KiB)."""

MAX_RECORD_BYTES = 256 * 1024 * 1024
"""The largest exploration record read (256 MiB; a 140-contact record is about 100 KiB)."""


class InputFileError(Exception):
    """A file that cannot be read as text; ``line`` and ``column`` (1-based) locate a bad byte."""

    def __init__(self, message: str, line: int = 0, column: int = 0) -> None:
        self.message = message
        self.line = line
        self.column = column
        super().__init__(message)


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a file"


def _size(n: int) -> str:
    return f"{n / (1024 * 1024):g} MiB" if n >= 1024 * 1024 else f"{n} bytes"


def read_bytes(path: str | Path, *, max_bytes: int) -> bytes:
    """The content of the regular file ``path``, refused if it is larger than ``max_bytes``.

    Raises :class:`InputFileError` (one-line message, no file name) for a missing or unreadable
    file, a directory, device, pipe or socket, or a file that is too large.
    """
    p = str(path)
    if not p:
        raise InputFileError("no file name given")
    try:
        # O_NONBLOCK: opening a named pipe with no writer must not wait for one.
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        if exc.errno == errno.EISDIR:
            raise InputFileError("not a regular file (a directory)") from None
        raise InputFileError(f"cannot read: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise InputFileError(f"not a regular file ({_kind(info.st_mode)})")
        if info.st_size > max_bytes:
            raise InputFileError(
                f"file too large ({_size(info.st_size)}; at most {_size(max_bytes)} is read)"
            )
        chunks: list[bytes] = []
        total = 0
        while True:  # the size may change while reading: never read past the cap
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if total > max_bytes:
                raise InputFileError(f"file too large (at most {_size(max_bytes)} is read)")
        return b"".join(chunks)
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def decode_utf8(data: bytes) -> str:
    """``data`` as UTF-8 text (a leading BOM dropped); a bad byte raises
    :class:`InputFileError` located at its line and column."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        before = data[: exc.start].decode("utf-8-sig", errors="replace")
        line = before.count("\n") + 1
        column = len(before) - (before.rfind("\n") + 1) + 1
        raise InputFileError(
            f"not UTF-8 text: byte 0x{data[exc.start]:02x} cannot be decoded", line, column
        ) from None


def read_text(path: str | Path, *, max_bytes: int) -> str:
    """The UTF-8 text of the regular file ``path`` (see :func:`read_bytes`, :func:`decode_utf8`)."""
    return decode_utf8(read_bytes(path, max_bytes=max_bytes))


def atomic_write(path: str | Path, write: Callable[[IO[bytes]], object]) -> None:
    """Call ``write`` on a new temporary file beside ``path``, then put it in place.

    The temporary file has a unique name in the target's directory, is flushed and fsynced
    before ``os.replace`` renames it onto ``path``; on any failure it is removed and the
    exception propagates (``path`` is untouched). A ``path`` that is a directory or another
    non-regular file raises :class:`IsADirectoryError` / :class:`OSError` before writing.
    """
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "is a directory", str(target))
    if target.exists() and not target.is_file():
        raise OSError(errno.EINVAL, "not a regular file", str(target))
    directory = target.parent
    tmp = tempfile.NamedTemporaryFile(  # noqa: SIM115 - closed below, then renamed
        dir=directory, prefix=f".{target.name}.", suffix=".tmp", delete=False
    )
    try:
        with tmp:
            write(tmp)
            tmp.flush()
            os.fsync(tmp.fileno())
        # Keep the usual permissions of a new file (mkstemp makes it 0600).
        umask = os.umask(0)
        os.umask(umask)
        with contextlib.suppress(OSError):
            os.chmod(tmp.name, 0o666 & ~umask)
        os.replace(tmp.name, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp.name)
        raise
    if hasattr(os, "O_DIRECTORY"):  # make the rename itself durable
        with contextlib.suppress(OSError):
            dfd = os.open(directory or ".", os.O_RDONLY | os.O_DIRECTORY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)
