"""Output files: checked before any work, written atomically (a reader or a crash never sees a partial
file, and nothing is left behind)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from .errors import ConfigError


def check_output_path(flag: str, path: str | None, suffixes: tuple[str, ...]) -> None:
    """Refuse an output path before any work: wrong suffix, a directory, a missing or unwritable parent
    directory, or an existing file that cannot be replaced."""
    if path is None:
        return
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ConfigError(flag, path, "a file name ending in " + " or ".join(suffixes))
    if p.is_dir():
        raise ConfigError(flag, path, "a file path (this is a directory)")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(flag, path, "a path in an existing directory")
    if p.exists() and not p.is_file():
        raise ConfigError(flag, path, "a regular file path (this is a special file)")
    try:  # the one reliable test of writability (permissions, read-only mounts, root on /proc)
        fd, probe = tempfile.mkstemp(dir=parent, prefix=f".{p.name}.", suffix=".probe")
        os.close(fd)
        os.remove(probe)
    except OSError as exc:
        raise ConfigError(flag, path, f"a path in a writable directory ({exc.strerror or exc})") from None


def atomic_write(path: str | Path, write: Callable[[str], object]) -> None:
    """Write through a temporary file in the target directory, then rename: never a partial file.

    The temporary file is removed on any exit (an error, Ctrl-C, SIGTERM once :func:`main` installed its
    handler); the result gets the usual permissions (0666 minus the umask), not mkstemp's 0600.
    """
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".", prefix=f".{path.name}.",
                                   suffix=".tmp" + path.suffix)
    except OSError as exc:
        raise ConfigError("output", str(path), f"a writable path ({exc.strerror or exc})") from None
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(exc, OSError):  # disk full, the directory vanished, ...: one line, not a traceback
            raise ConfigError("output", str(path), f"a writable path ({exc.strerror or exc})") from None
        raise
