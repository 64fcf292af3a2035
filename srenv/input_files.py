"""Opening a file a command reads as data: a regular file only, checked on the open descriptor.

A path test first (``is_file()``) and ``open()`` after it both follow the name, and ``open()`` of a FIFO
blocks until a writer appears (a command that hangs forever); a device reads without end. Here the file is
opened without blocking (``O_NONBLOCK``: an open FIFO returns at once), then ``fstat`` of that descriptor
must say a regular file, so what is read is what was checked. Any problem is one ConfigError naming the
field and the path (docs/reliability.md).
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path
from typing import Any, BinaryIO

from .errors import ConfigError, short_repr


def open_regular(path: str | Path, field: str, what: str) -> BinaryIO:
    """``path`` opened for binary reading, refused unless it is a readable regular file (symbolic links to
    one are followed); ``what`` names the kind of file in the message ("YAML file", "model file")."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the path
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ConfigError(field, str(path), f"a readable {what} ({reason})") from None
    try:
        mode = os.fstat(fd).st_mode
    except OSError as exc:
        os.close(fd)
        raise ConfigError(field, str(path), f"a readable {what} ({exc.strerror or exc})") from None
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = "a directory" if stat.S_ISDIR(mode) else "a special file (FIFO, device or socket)"
        raise ConfigError(field, str(path), f"a regular {what} (this is {kind})")
    return os.fdopen(fd, "rb")


def read_regular(path: str | Path, field: str, what: str, max_bytes: int) -> bytes:
    """The bytes of a regular file of at most ``max_bytes``: its size on the open descriptor first (a huge file is
    refused unread), then read at most one byte more (a file growing meanwhile is refused too)."""
    with open_regular(path, field, what) as fh:
        if os.fstat(fh.fileno()).st_size > max_bytes:
            raise ConfigError(field, str(path), f"a {what} of at most {max_bytes} bytes")
        try:
            raw = fh.read(max_bytes + 1)
        except OSError as exc:
            raise ConfigError(field, str(path), f"a readable {what} ({exc.strerror or exc})") from None
    if len(raw) > max_bytes:
        raise ConfigError(field, str(path), f"a {what} of at most {max_bytes} bytes")
    return raw


def read_json(path: str | Path, field: str, what: str, max_bytes: int) -> Any:
    """The JSON value of a regular file of at most ``max_bytes`` (``json``: data only). Not UTF-8, not JSON or
    nested deeper than the parser's recursion allows: one ConfigError naming the field and the path."""
    return parse_json(read_regular(path, field, what, max_bytes), field, str(path), what)


def parse_json(raw: bytes, field: str, source: str, what: str) -> Any:
    """The JSON value of ``raw`` (a file's bytes, a zip member's): one ConfigError naming the field and the
    source when it is not UTF-8, not JSON, or nested deeper than the parser's recursion allows."""
    try:
        return json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:  # RecursionError: [[[[...]]]] a million deep
        detail = ("nested too deeply" if isinstance(exc, RecursionError) else "not UTF-8 text"
                  if isinstance(exc, UnicodeDecodeError) else f"not JSON: {short_repr(str(exc), 120)}")
        raise ConfigError(field, source, f"a readable JSON {what} ({type(exc).__name__}: {detail})") from None
