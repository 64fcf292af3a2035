"""Output files: checked before any work, written atomically (a reader or a crash never sees a partial
file, and nothing is left behind), all of a run's files or none of them; and the strict JSON summary line.

Symbolic links: an output path that is a symbolic link is refused before any work (``srenv`` and ``agents``
alike, docs/reliability.md §5): writing through it would change the link's target, a file the user did not
name, and silently replacing the link would lose it. The rename onto the final path never follows a link.
"""

from __future__ import annotations

import json
import math
import os
import secrets
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from .errors import ConfigError, NumericFailure

_NO_LINK = "a path that is not a symbolic link (an output is never written through a link nor replaces one; " \
           "name the target itself)"


def check_output_path(flag: str, path: str | None, suffixes: tuple[str, ...]) -> None:
    """Refuse an output path before any work: wrong suffix, a symbolic link, a directory, a missing or
    unwritable parent directory, or an existing file that cannot be replaced."""
    if path is None:
        return
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ConfigError(flag, path, "a file name ending in " + " or ".join(suffixes))
    if p.is_symlink():
        raise ConfigError(flag, path, _NO_LINK)
    if p.is_dir():
        raise ConfigError(flag, path, "a file path (this is a directory)")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(flag, path, "a path in an existing directory")
    if p.exists() and not p.is_file():
        raise ConfigError(flag, path, "a regular file path (this is a special file)")
    check_writable(flag, path, parent)


def check_writable(flag: str, path: str, directory: Path) -> None:
    """``directory`` (where ``path`` will be written) takes a new file: a temporary one is made and removed,
    the one reliable test of writability (permissions, read-only mounts, root on /proc)."""
    made: list[str] = []
    try:
        _new_file(directory, f".{Path(path).name}.", ".probe", made)
    except OSError as exc:
        raise ConfigError(flag, path, f"a path in a writable directory ({exc.strerror or exc})") from None
    finally:
        _remove_existing(made)


def _new_file(directory: Path, prefix: str, suffix: str, made: list[str]) -> None:
    """Create a new empty file (mode 0600) named ``prefix + random + suffix`` in ``directory``, entering its name
    in ``made`` *before* creating it: an interruption (Ctrl-C, SIGTERM) at any instant leaves nothing the caller's
    cleanup of ``made`` misses. (``tempfile.mkstemp`` names the file only once it exists, and a signal in between
    left the file behind; seen once in CI.) Never follows a link; OSError as raised."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    while True:
        name = os.path.join(directory, f"{prefix}{secrets.token_hex(6)}{suffix}")
        made.append(name)
        try:
            fd = os.open(name, flags, 0o600)
        except FileExistsError:  # another file's name (not ours to remove): draw again
            made.pop()
            continue
        os.close(fd)
        return


def _remove_existing(names: list[str]) -> None:
    for name in names:
        if os.path.lexists(name):
            os.remove(name)


def check_output_dir(out: Path, names: tuple[str, ...], flag: str = "--out-dir", parents: bool = True) -> None:
    """The files a command will write under ``out`` (given by ``flag``), checked before any work: ``out`` a
    directory (or absent, under a directory; with ``parents`` False its parent must exist, for commands that make
    only the folder itself), no file a directory, a symbolic link or a special file (outputs never write through
    nor replace a link). The one check of every command's output folder (``srenv cards``; agents' train,
    quickstart, benchmark and its --evaluate-only), made before any file is read for the work."""
    if out.is_symlink():
        raise ConfigError(flag, str(out), "a directory path that is not a symbolic link (name the target itself)")
    if out.exists() and not out.is_dir():
        raise ConfigError(flag, str(out), "a directory (this is a file)")
    if not parents and not out.exists() and not (out.parent if str(out.parent) else Path(".")).is_dir():
        raise ConfigError(flag, str(out), "a path in an existing directory")
    if not out.exists() and any(p.exists() and not p.is_dir() for p in out.parents):
        raise ConfigError(flag, str(out), "a path under directories (a parent is a file)")
    check_writable(flag, str(out), next(p for p in (out, *out.parents) if p.exists()))  # where it will be made
    for name in names:
        p = out / name
        if p.is_symlink():
            raise ConfigError(flag, str(p), "no symbolic link among the outputs (an output is never "
                              "written through a link nor replaces one)")
        if p.is_dir():
            raise ConfigError(flag, str(p), "a file path for this output (it is a directory)")
        if p.exists() and not p.is_file():
            raise ConfigError(flag, str(p), "a regular file path for this output (this is a special file)")


def check_outputs(outputs: dict[str, tuple[str | None, tuple[str, ...]]]) -> None:
    """Check every output of a command (flag -> (path, suffixes)) and that no two name the same file
    (one would overwrite the other)."""
    seen: dict[str, str] = {}
    for flag, (path, suffixes) in outputs.items():
        check_output_path(flag, path, suffixes)
        if path is None:
            continue
        key = os.path.realpath(os.path.abspath(path))
        if key in seen:
            raise ConfigError(flag, path, f"a file other than {seen[key]}'s (both would write the same file)")
        seen[key] = flag


def _temporary(path: Path, temps: list[str]) -> None:
    """The temporary beside ``path``, entered in ``temps`` before it exists (see :func:`_new_file`)."""
    try:
        _new_file(path.parent if str(path.parent) else Path("."), f".{path.name}.", ".tmp" + path.suffix, temps)
    except OSError as exc:
        raise ConfigError("output", str(path), f"a writable path ({exc.strerror or exc})") from None


def atomic_write_all(items: Iterable[tuple[str | Path, Callable[[str], object]]]) -> None:
    """Write every (path, writer) through a temporary file in its directory, then rename them all: a
    failure, Ctrl-C or SIGTERM (once :func:`main` installed its handler) during any writer leaves none of
    the files and no temporary; the results get the usual permissions (0666 minus the umask)."""
    items = [(Path(p), w) for p, w in items]
    for path, _ in items:  # the policy holds for every writer, whether or not it checked its paths first
        if path.is_symlink():
            raise ConfigError("output", str(path), _NO_LINK)
    temps: list[str] = []
    renamed: list[Path] = []
    at = items[0][0] if items else Path(".")  # the file being written, for the error line
    try:
        for path, write in items:
            at = path
            _temporary(path, temps)
            write(temps[-1])
        umask = os.umask(0)
        os.umask(umask)
        for tmp in temps:
            os.chmod(tmp, 0o666 & ~umask)
        for (path, _), tmp in zip(items, temps):
            at = path
            os.replace(tmp, path)
            renamed.append(path)
    except BaseException as exc:
        _remove_existing(temps)
        if len(renamed) < len(items):  # all or nothing: a run that failed leaves none of its outputs
            for path in renamed:
                path.unlink(missing_ok=True)
        if isinstance(exc, OSError):  # disk full, the directory vanished, ...: one line, not a traceback
            raise ConfigError("output", str(at), f"a writable path ({exc.strerror or exc})") from None
        raise


def atomic_write(path: str | Path, write: Callable[[str], object]) -> None:
    """Write one file through a temporary file in the target directory, then rename: never a partial file."""
    atomic_write_all([(path, write)])


def json_line(obj: Any) -> str:
    """The summary as strict JSON (no NaN/Infinity, which are not JSON): a non-finite number is a
    ``NumericFailure`` naming its key; a quantity that may be undefined must be given as None (null)."""
    def walk(key: str, v: Any) -> Any:
        if isinstance(v, dict):
            return {k: walk(str(k), w) for k, w in v.items()}
        if isinstance(v, (list, tuple)):
            return [walk(key, w) for w in v]
        if hasattr(v, "item") and not isinstance(v, (str, bytes)):  # numpy scalars
            v = v.item()
        if isinstance(v, float) and not math.isfinite(v):
            raise NumericFailure(key, f"{v} is not a finite number; check the input's magnitudes")
        return v
    return json.dumps(walk("summary", obj), allow_nan=False, default=str)
