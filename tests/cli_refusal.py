"""One check for the CLI's bad-input contract, shared by the tests of each command that reads a file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def assert_cli_refuses(args: list[str], out: Path, *needles: str) -> str:
    """``python -m srenv.cli ARGS`` exits 2 with one stderr line holding every needle, and writes no ``out``."""
    p = subprocess.run([sys.executable, "-m", "srenv.cli", *args], check=False, capture_output=True, text=True)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and all(n in lines[0] for n in needles), p.stderr
    assert not out.exists()
    return lines[0]
