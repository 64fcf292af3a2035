"""`srenv sweep`: parameter sets, critical velocity, outputs, bad input, and local processes == serial."""

from __future__ import annotations

import csv
import json
import pickle
from pathlib import Path

import pytest

from srenv.config import read_raw
from srenv.errors import ConfigError
from srenv.tools.cli import main
from srenv.tools.sweep import (
    SET_COLUMN,
    _run_case_portable,
    _unwrap,
    column_names,
    critical_values,
    parameter_sets,
    parse_case,
    parse_grid,
)

FIG7 = "configs/wells/paper_fig7_pullout.yaml"
# 8 s runs, metrics after 30 %: 5.6 s = 8 natural periods of the 1.46 Hz string, enough for the moving
# average; 0.05 m/s sticks from the first load-up on, 10 m/s never sticks after the start (test_nonmonotone)
TINY = [FIG7, "--param", "surface.pull_velocity_m_s", "--values", "0.05,10", "--duration-s", "8",
        "--grid", "pump.reference_velocity_m_s=0.5,1"]


def _run(capsys: pytest.CaptureFixture, args: list[str]) -> tuple[int, dict | None, str]:
    rc = main(["sweep", *args])
    out, err = capsys.readouterr()
    lines = [ln for ln in out.splitlines() if ln.startswith("{")]
    return rc, (json.loads(lines[-1]) if lines else None), err


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_serial_and_two_local_workers_give_identical_files(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture) -> None:
    rc_s, js_s, _ = _run(capsys, [*TINY, "--serial", "--out", str(tmp_path / "s.csv"),
                                   "--plot", str(tmp_path / "s.png")])
    rc_r, js_r, _ = _run(capsys, [*TINY, "--workers", "2", "--out", str(tmp_path / "r.csv")])
    assert rc_s == rc_r == 0
    assert js_s["backend"] == "serial" and js_r["backend"] == "processes" and js_r["workers"] == 2
    # every case is a deterministic function of its config and floats are written with repr
    assert (tmp_path / "s.csv").read_bytes() == (tmp_path / "r.csv").read_bytes()
    assert js_s["sets"] == js_r["sets"]
    rows = _rows(tmp_path / "s.csv")
    assert len(rows) == 4 and (tmp_path / "s.png").stat().st_size > 10_000
    assert list(rows[0])[:3] == [SET_COLUMN, "reference_velocity_m_s", "pull_velocity_m_s"]
    for col in rows[0]:
        assert col in (SET_COLUMN, "qp_steps") or col.endswith(("_m_s", "_m", "_n", "_s", "_episodes",
                                                                "_per_step")), col
    for s in js_s["sets"]:  # sticking at 0.05, none at 10 for both v0
        assert s["critical_pull_velocity_m_s"] == 10.0 and s["last_sticking_pull_velocity_m_s"] == 0.05
    by_v = {float(r["pull_velocity_m_s"]): r for r in rows if r["reference_velocity_m_s"] == "1.0"}
    assert int(by_v[0.05]["plunger_stick_episodes"]) >= 3 and int(by_v[10.0]["plunger_stick_episodes"]) == 0
    assert float(by_v[0.05]["slip_amplitude_m"]) > 1e-3


def test_worker_errors_cross_the_process_boundary_as_themselves() -> None:
    """ConfigError's 3-argument constructor does not survive Ray's exception pickling, so a worker returns
    its error as plain data and the driver re-raises it (checked here through a pickle round trip)."""
    raw = read_raw(FIG7)
    raw["pump"]["law"] = "sometimes"
    shipped = pickle.loads(pickle.dumps(_run_case_portable(raw, 8.0, 0.3)))
    with pytest.raises(ConfigError, match="pump.law"):
        _unwrap(shipped)


def test_critical_value_is_the_lowest_value_from_which_on_nothing_sticks() -> None:
    def row(s: int, v: float, n: int) -> dict:
        return {SET_COLUMN: s, "pull_velocity_m_s": v, "plunger_extra_stick_episodes": n}
    # set 0: a non-sticking value below a sticking one does not count as critical
    rows = [row(0, v, n) for v, n in [(3.0, 0), (0.5, 7), (1.0, 0), (2.0, 4), (4.0, 0)]]
    rows += [row(1, v, 2) for v in (1.0, 2.0)] + [row(2, v, 0) for v in (1.0, 2.0)]
    crit = critical_values(rows, "pull_velocity_m_s")
    assert [(c["critical_pull_velocity_m_s"], c["last_sticking_pull_velocity_m_s"]) for c in crit] == [
        (3.0, 2.0), (None, 2.0), (1.0, None)]


def test_parameter_sets_grid_product_times_cases_and_column_names() -> None:
    grid = parse_grid(["pump.reference_velocity_m_s=0.5,1", "pump.dynamic_load_n=7090,9090"])
    cases = parse_case(["pump.upstroke_load_n=11090", "pump.upstroke_load_n=13090,friction.coefficient=0.2"])
    sets = parameter_sets(grid, cases)
    assert len(sets) == 8 and sets[0] == {"pump.reference_velocity_m_s": 0.5, "pump.dynamic_load_n": 7090.0,
                                          "pump.upstroke_load_n": 11090.0}
    assert parameter_sets([], []) == [{}]
    assert column_names(["pump.reference_velocity_m_s", "friction.reference_velocity_m_s", "a.x_n"]) == {
        "pump.reference_velocity_m_s": "pump.reference_velocity_m_s",
        "friction.reference_velocity_m_s": "friction.reference_velocity_m_s", "a.x_n": "x_n"}


@pytest.mark.parametrize("bad, field", [
    (["--values", "0.05,fast"], "--values"),
    (["--values", "0.05,0.05"], "--values"),
    (["--values", "-1"], "surface.pull_velocity_m_s"),
    (["--param", "surface.pull_speed_m_s"], "surface.pull_speed_m_s"),
    (["--grid", "pump.reference_velocity_m_s"], "--grid"),
    (["--grid", "surface.pull_velocity_m_s=1,2"], "--param"),
    (["--set", "pump.law=sometimes"], "pump.law"),
    (["--duration-s", "1"], "--duration-s"),
    (["--settle-fraction", "1.5"], "--settle-fraction"),
    (["--set", "surface.motion=harmonic"], "surface.motion"),
    (["--out", "/nonexistent/dir/x.csv"], "--out"),
    (["--workers", "0"], "--workers"),
    (["--address", "127.0.0.1:1"], "--address"),  # nothing listens on port 1: fail fast, not retry
])
def test_bad_input_gives_one_error_line_exit_2_and_no_file(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                           bad: list[str], field: str) -> None:
    args = {"--param": "surface.pull_velocity_m_s", "--values": "0.05", "--duration-s": "8",
            "--out": str(tmp_path / "x.csv")}
    extra = []
    for i in range(0, len(bad), 2):
        if bad[i] in args:
            args[bad[i]] = bad[i + 1]
        else:
            extra += bad[i:i + 2]
    backend = [] if "--address" in bad else ["--serial"]
    argv = ["sweep", FIG7, *backend, *[x for kv in args.items() for x in kv], *extra]
    if field in ("--workers", "--settle-fraction"):  # rejected by argparse itself (declared flags), status 2
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
    else:
        assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("srenv: error:") and field in err
    assert list(tmp_path.iterdir()) == []

