"""scripts/speed_budget.py (issue 25): the budget's arithmetic on fixed numbers (a 10x step's cost, the resets'
share, the strokes left at the floor; zero strokes when the resets take it all), its inverse (the frontier), the
benchmark's env-step count, the report from fixed measurements, and bad flags refused in one line with exit 2.
No timed assertion: the measuring runs are not called here."""

from __future__ import annotations

import math
import runpy
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

REPO = Path(__file__).resolve().parents[3]
SCRIPT = REPO / "scripts" / "speed_budget.py"


@pytest.fixture(scope="module")
def mod():  # the script's names (its main not run: run_name is not "__main__")
    return SimpleNamespace(**runpy.run_path(str(SCRIPT), run_name="speed_budget"))


def test_the_budget_on_fixed_numbers(mod):
    # v1 at 100 env steps/s: a 10x step may cost 1 ms; 2 resets of 6 ms over 24 steps take 0.5 ms of it
    b = mod.budget(100.0, 6.0, 0.25)
    assert b["step_budget_ms"] == pytest.approx(1.0)
    assert b["resets_ms_per_step"] == pytest.approx(0.5)
    assert b["left_ms_per_step"] == pytest.approx(0.5)
    assert b["max_exact_strokes_per_step"] == pytest.approx(2.0)
    assert mod.budget(100.0, 0.0, 0.25)["max_exact_strokes_per_step"] == pytest.approx(4.0)
    assert mod.budget(50.0, 6.0, 0.25, speedup=5.0)["max_exact_strokes_per_step"] == pytest.approx(14.0)


def test_the_budget_admits_zero_strokes_when_the_resets_take_it(mod):
    b = mod.budget(100.0, 20.0, 0.25)  # 2 x 20 ms / 24 = 1.67 ms of resets a step against a 1 ms step
    assert b["left_ms_per_step"] == pytest.approx(1.0 - 40.0 / 24.0)
    assert b["max_exact_strokes_per_step"] == 0.0
    assert mod.budget(100.0, 12.0, 0.25)["max_exact_strokes_per_step"] == 0.0  # exactly used up


def test_the_frontier_is_the_budgets_inverse(mod):
    assert mod.rate_multiple(100.0, 6.0, 0.25, 2.0) == pytest.approx(10.0)
    for k in (0.5, 1.0, 3.0):
        x = mod.rate_multiple(100.0, 6.0, 0.25, k)
        assert mod.budget(100.0, 6.0, 0.25, speedup=x)["max_exact_strokes_per_step"] == pytest.approx(k)


def test_the_benchmark_count_on_a_fixed_config(mod):
    cfg = {"tuning": {"seeds": list(range(10))}, "validation": {"seeds": list(range(8))},
           "test": {"seeds": list(range(100))}, "baselines": {"best_constant": {}, "oracle": {}},
           "agents": {"runs": {
               "ppo": {"config": "p.yaml", "seeds": [0, 1, 2]},
               "sac": {"config": "s.yaml", "seeds": [0], "overrides": {"n_timesteps": 7}},
               "student": {"config": "p.yaml", "seeds": [0, 1], "ensemble": True,
                           "teacher": {"iterations": 3, "episodes": 5}}}}}
    n = mod.benchmark_env_steps(cfg, {"p.yaml": 1000, "s.yaml": 99}, tuning_candidates=4, steps_per_episode=10)
    assert n == {"tuning": 4 * 10 * 10, "training": 1000 * 3 + 7 * 1 + 1000 * 2, "distillation": 3 * 5 * 2 * 10,
                 "validation": 6 * 8 * 10, "test": (3 + 6 + 1) * 100 * 10,
                 "total": 400 + 5007 + 300 + 480 + 10000}


def _measured(kernel_ms_per_step: float, exact: float) -> dict:
    return {"rates": {"v1@91adcce": [90.0, 100.0], "srenv/SuckerRod-v2": [250.0, 260.0],
                      "srenv/SuckerRod-v1 (this tree)": [140.0, 150.0]},
            "split": {"reset_ms_each": 6.0, "exact_strokes_per_step": exact, "steps_kernel_ms_per_step": kernel_ms_per_step,
                      "steps_python_ms_per_step": 0.7,
                      "kernel_ms_per_exact_stroke": kernel_ms_per_step / exact if exact else None},
            "floor": {"floor_ms_per_exact_stroke": 0.25, "strokes_per_step": 60.0, "wells": []}}


def test_the_report_from_fixed_measurements(mod):
    s = mod.summarise("full_speed", _measured(1.0, 2.0), "srenv/SuckerRod-v2")
    assert s["budget"]["max_exact_strokes_per_step"] == pytest.approx(2.0)  # v1's best round, the resets measured
    assert s["budget_kernel_goal"]["max_exact_strokes_per_step"] == pytest.approx(2.0 / 1.5)
    assert s["budget_kernel_today"]["max_exact_strokes_per_step"] == pytest.approx(1.0)  # 0.5 ms a stroke
    # the most generous: v1's slowest round (1.11 ms a step), each reset one stroke at the floor
    assert s["budget_generous"]["max_exact_strokes_per_step"] == pytest.approx((1e3 / 900 - 0.5 / 24) / 0.25)
    assert s["frontier_at_floor"]["every stroke"]["over_v1_resets_today"] == pytest.approx(
        24e3 / (24 * 60 * 0.25 + 12.0) / 100.0)
    assert s["new_over_v1_best"] == pytest.approx(2.6) and s["v1_here_rate_best"] == 150.0
    none = mod.summarise("vsd_minimum", _measured(0.0, 0.0), "srenv/SuckerRod-v2")  # no exact stroke ran
    assert none["budget_kernel_today"] is None
    res = {"env_id": "srenv/SuckerRod-v2", "repeats": 2, "actions": {"full_speed": s, "vsd_minimum": none},
           "benchmark": {"env_steps": {"total": 1000, "training": 600}, "cores": 2, "goal_s": 1200.0,
                         "needed_rate_per_core": 0.42, "v1_rates_per_core": {"v1@91adcce": 100.0},
                         "lower_bound_s": {"v1@91adcce": 5.0}}}
    lines = mod.report_lines(res)
    assert any("at most 2.00 exact strokes" in x for x in lines) and any("today's kernel nan" in x for x in lines)
    assert not any(math.isnan(v) for v in (s["budget"]["step_budget_ms"], s["new_exact_strokes_per_step"]))


def _old_tree(tmp_path: Path) -> Path:
    old = tmp_path / "old"
    (old / "srenv" / "envs").mkdir(parents=True)
    (old / "srenv" / "__init__.py").write_text("")
    return old


def test_bad_flags_are_one_line_and_exit_2(mod, capsys, tmp_path):
    old = _old_tree(tmp_path)
    for text in mod.FLAGS["--repeats"].bad_texts():
        with pytest.raises(SystemExit) as ex:
            mod.main(["--old", str(old), "--repeats", text])
        err = capsys.readouterr().err.strip().splitlines()
        assert ex.value.code == 2 and len(err) == 1 and "--repeats" in err[0] and "expected" in err[0], (text, err)
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "target.json")
    cases = ([["--old", str(tmp_path / "nowhere")], "--old"], [["--old", str(tmp_path)], "--old"],
             [["--old", str(old), "--out", str(link)], "symbolic link"],
             [["--old", str(old), "--out", str(tmp_path / "x.csv")], ".json"],
             [["--old", str(old), "--out", str(tmp_path / "no" / "x.json")], "--out"], [[], "--old"])
    for argv, word in cases:
        with pytest.raises(SystemExit) as ex:
            mod.main(argv)
        err = capsys.readouterr().err.strip().splitlines()
        assert ex.value.code == 2 and len(err) == 1 and word in err[0], (argv, err)
    assert not (tmp_path / "target.json").exists() and not (tmp_path / "x.csv").exists()
    p = subprocess.run([sys.executable, str(SCRIPT), "--old", str(old), "--repeats", "0"], capture_output=True,
                       text=True, check=False, timeout=120, cwd=REPO, env={"PYTHONPATH": str(REPO), "PATH": ""})
    assert p.returncode == 2 and p.stderr.strip().splitlines() == [
        "speed_budget.py: error: argument --repeats: --repeats = '0': expected a positive integer at most 20"]
