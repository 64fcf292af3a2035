"""Ctrl-C and SIGTERM, the same everywhere (``srenv`` and ``python -m agents``): one line, exit 130, every
``finally`` run, and worker processes that leave the reporting to their driver."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

EXIT_INTERRUPTED = 130


def raise_on_sigterm(signum: int, frame: object) -> None:
    """SIGTERM handler: an exception, so that every ``finally`` runs (temporary files removed, worker pools
    and Ray shut down): a killed command leaves nothing behind."""
    raise KeyboardInterrupt(f"signal {signum}")


@contextlib.contextmanager
def workers_ignore_sigint() -> Iterator[None]:
    """Start worker processes inside this block (keep it short: the start calls only): SIGINT is ignored
    meanwhile, and a spawned Python inherits an ignored SIGINT and keeps it, so the workers never see the
    Ctrl-C the terminal sends to the whole group (no traceback from a worker, even one still importing);
    the driver reports it. A Ctrl-C that arrives during the block itself (milliseconds) is lost."""
    if threading.current_thread() is not threading.main_thread():  # only the main thread may set handlers
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
