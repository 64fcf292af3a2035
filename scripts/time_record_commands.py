"""Time ``srenv classify RECORD.json`` and ``srenv diagnose RECORD.json`` in one process (docs/field.md, "A dynacard
record describes its well"): the median of 7 runs after one warm-up, per command, on the two records in
tests/data/field/. Prints one JSON line. Run: ``PYTHONPATH=. python scripts/time_record_commands.py``."""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

from srenv.tools.cli import main

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
RUNS = 7


def median_ms(argv: list[str]) -> float:
    times = []
    for i in range(RUNS + 1):
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(argv) == 0
        if i:  # the first run warms the caches (imports, numba)
            times.append(1e3 * (time.perf_counter() - t0))
    return sorted(times)[RUNS // 2]


def run() -> dict:
    out = {}
    with tempfile.TemporaryDirectory() as work:
        for well in ("7699227", "11708328"):
            rec = str(DATA / f"{well}.json")
            out[f"classify_{well}_ms"] = median_ms(["classify", rec])
            out[f"classify_{well}_pump_ms"] = median_ms(["classify", rec, "--card", "pump"])
            out[f"diagnose_{well}_ms"] = median_ms(["diagnose", rec, "--out", f"{work}/pump.csv"])
    return {k: round(v, 1) for k, v in out.items()}


if __name__ == "__main__":
    print(json.dumps(run()))
