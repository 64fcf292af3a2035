"""Reliability: the solver retry chain, SolverFailure handling (simulator, CLI, env) and the energy balance.

Solver failures are injected with ``StepQP.fail_injector`` (a backend "fails" when it returns True) or by
making a backend raise / return NaN, on the Fig. 4 well with ``always_qp=True`` so that every step of a
stroke goes through the chain.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import qpsolvers

import srenv  # registers the envs
from srenv.config import load_config
from srenv.errors import NumericFailure, SolverFailure
from srenv.numerics.step_qp import StepQP
from srenv.simulation.simulator import RunResult, Simulator
from srenv.tools.cli import EXIT_SOLVER, main

FIG3 = "paper_fig3_vertical"
FIG4 = "paper_fig4_deviated"
TRACE_KEYS = ("polished_rod_load_n", "polished_rod_position_m", "pump_position_m", "pump_velocity_m_s",
              "pump_load_n")
ENERGY_RTOL = 1e-6


def _max_rel_diff(a: RunResult, b: RunResult) -> float:
    """Largest difference over the traced signals, each relative to its own peak magnitude."""
    return max(float(np.max(np.abs(a.trace[k] - b.trace[k])) / np.max(np.abs(a.trace[k]))) for k in TRACE_KEYS)


def _qp_stroke(injector: Callable[[str], bool] | None = None, *, polish: bool = True,
               persistent: bool = False) -> tuple[RunResult, Simulator]:
    sim = Simulator(load_config(FIG4), always_qp=True, persistent_qp=persistent)
    sim.polish = polish
    sim.qp.fail_injector = injector
    return sim.run_stroke(), sim


@pytest.fixture(scope="module")
def reference() -> RunResult:
    """One Fig. 4 stroke with ProxSuite solving every step, nothing injected."""
    result, sim = _qp_stroke()
    assert sim.qp.stats.by_solver == {"proxqp": result.n_steps} and sim.qp.stats.retries == 0
    return result


@pytest.fixture(scope="module")
def reference_raw() -> RunResult:
    """As `reference` but keeping the solver's own velocities (no active-set polish)."""
    return _qp_stroke(polish=False)[0]


# ------------------------------------------------------------------------------------------ retry chain
def test_proxqp_failing_falls_back_to_another_backend(reference: RunResult) -> None:
    result, sim = _qp_stroke(lambda name: name == "proxqp")
    stats = sim.qp.stats
    assert "proxqp" not in stats.by_solver and sum(stats.by_solver.values()) == result.n_steps
    # each step: proxqp, proxqp tighter, then the first other backend that works
    assert stats.retries == 2 * result.n_steps
    assert _max_rel_diff(result, reference) < 1e-8


def test_fallback_answer_itself_is_accurate_without_polish(reference_raw: RunResult) -> None:
    """With the exact active-set polish off, the trajectory is the backends' own answers: the fallback
    (proxqp and clarabel failing -> osqp with polishing) still matches ProxSuite's to 1e-8."""
    if "osqp" not in qpsolvers.available_solvers:
        pytest.skip("osqp not installed")
    result, sim = _qp_stroke(lambda name: name in ("proxqp", "clarabel"), polish=False)
    assert set(sim.qp.stats.by_solver) == {"osqp"}
    assert _max_rel_diff(result, reference_raw) < 1e-8


def test_tighter_retry_of_the_same_solver_is_tried_first(reference: RunResult) -> None:
    calls = {"n": 0}

    def every_other(name: str) -> bool:  # fails the first attempt of every step, not the retry
        calls["n"] += 1
        return calls["n"] % 2 == 1

    result, sim = _qp_stroke(every_other)
    assert sim.qp.stats.by_solver == {"proxqp": result.n_steps}
    assert sim.qp.stats.retries == result.n_steps
    assert _max_rel_diff(result, reference) < 1e-8


def test_persistent_proxqp_recovers_from_intermittent_failures(reference: RunResult) -> None:
    """The warm-started persistent QP is dropped after a failure and rebuilt cold at the next step."""
    calls = {"n": 0}

    def sometimes(name: str) -> bool:
        calls["n"] += 1
        return name == "proxqp" and calls["n"] % 7 == 0

    result, sim = _qp_stroke(sometimes, persistent=True)
    assert sim.qp.stats.retries > 0
    assert _max_rel_diff(result, reference) < 1e-8


@pytest.mark.parametrize("fault", ["raises", "nan"])
def test_backend_raising_or_returning_nan_counts_as_failure(fault: str, reference: RunResult,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    real = qpsolvers.solve_problem

    def faulty(problem: qpsolvers.Problem, solver: str, **kw: object) -> qpsolvers.Solution:
        if solver != "proxqp":
            return real(problem, solver=solver, **kw)
        if fault == "raises":
            raise RuntimeError("backend crashed")
        sol = real(problem, solver=solver, **kw)
        sol.x = np.full_like(sol.x, np.nan)  # "found", but garbage
        return sol

    monkeypatch.setattr(qpsolvers, "solve_problem", faulty)
    result, sim = _qp_stroke()
    assert "proxqp" not in sim.qp.stats.by_solver
    assert _max_rel_diff(result, reference) < 1e-8


def test_all_backends_failing_raises_solver_failure_then_reset_recovers(reference: RunResult) -> None:
    sim = Simulator(load_config(FIG4), always_qp=True)
    sim.qp.fail_injector = lambda name: True
    with pytest.raises(SolverFailure) as err:
        sim.run_stroke()
    assert err.value.step == 0 and math.isfinite(err.value.time_s)
    tried = str(err.value)
    assert "proxqp (default)" in tried and "proxqp (tight)" in tried
    for other in qpsolvers.available_solvers:
        assert other in tried
    # the simulator is usable again after a reset
    sim.qp.fail_injector = None
    sim.reset()
    assert _max_rel_diff(sim.run_stroke(), reference) < 1e-8


def test_cli_reports_solver_failure_without_traceback_or_output(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str],
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(StepQP, "_solve_once", lambda self, prob, name, tight: None)
    out, plot = tmp_path / "o.csv", tmp_path / "o.png"
    rc = main(["simulate", FIG4, "--strokes", "1", "--always-qp", "--out", str(out), "--plot", str(plot)])
    cap = capsys.readouterr()
    assert rc == EXIT_SOLVER
    assert "Traceback" not in cap.err and len(cap.err.strip().splitlines()) == 1
    assert "step QP failed at step 0" in cap.err
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------ env
def test_env_ends_episode_on_solver_failure_and_reset_works(monkeypatch: pytest.MonkeyPatch) -> None:
    """The default env forced through the QP at every step; every backend fails during one env step."""
    env = gym.make("srenv/SuckerRod-v0", overrides={"simulation.always_qp": True})
    env.reset(seed=3)
    monkeypatch.setattr(StepQP, "_solve_once", lambda self, prob, name, tight: None)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert terminated and not truncated
    assert "step QP failed" in str(info["failure"])
    assert math.isfinite(float(reward))
    assert env.observation_space.contains(obs) and np.all(np.isfinite(obs))
    # once the solver works again, a reset starts a normal episode
    monkeypatch.undo()
    env.reset(seed=4)
    obs, reward, terminated, _, info = env.step(env.action_space.sample())
    assert not terminated and "failure" not in info
    assert math.isfinite(float(reward)) and np.all(np.isfinite(obs))
    env.close()


def test_soak_script_smoke() -> None:
    """scripts/soak.py on a few hundred strokes: every check passes and memory is sampled as asked."""
    spec = importlib.util.spec_from_file_location("soak", Path(__file__).parents[2] / "scripts" / "soak.py")
    soak = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(soak)
    summary = soak.soak(strokes=250, seed=0, checkpoint=50, config=None)
    assert summary["ok"], summary["problems"]
    assert summary["strokes"] == 250 and len(summary["rss_mb"]) == 5
    assert 0 < summary["max_energy_residual_rel"] <= ENERGY_RTOL


# ------------------------------------------------------------------------------------------ energy
def _per_stroke(results: list[RunResult]) -> list[dict]:
    """Energy terms of each stroke: RunResult.energy_j is accumulated since reset."""
    out, prev = [], {k: 0.0 for k in results[0].energy_j}
    for r in results:
        out.append({k: r.energy_j[k] - prev[k] for k in r.energy_j})
        prev = r.energy_j
    return out


@pytest.mark.parametrize("config", [FIG3, FIG4])
def test_energy_balance_closes_per_stroke_for_trapezoidal_newmark(config: str) -> None:
    sim = Simulator(load_config(config))
    for e in _per_stroke(sim.run_strokes(2, record=False)):
        work = e["polished_rod_work_j"]
        assert work > 1e4  # the unit lifts fluid: tens of kJ per stroke
        assert e["viscous_dissipation_j"] > 0 and e["friction_and_pump_work_j"] < 0
        supplied = work + e["gravity_work_j"] + e["friction_and_pump_work_j"] - e["viscous_dissipation_j"]
        assert e["residual_j"] == pytest.approx(e["stored_energy_change_j"] - supplied, abs=1e-9 * work)
        assert abs(e["residual_j"]) <= ENERGY_RTOL * work


def test_energy_balance_does_not_close_for_dissipative_newmark() -> None:
    """gamma > 1/2 adds numerical damping that no physical term accounts for: the residual is negative
    (energy lost) and far above round-off - the balance test above can tell the schemes apart."""
    sim = Simulator(load_config(FIG4, ["simulation.newmark_gamma=0.6", "simulation.newmark_beta=0.3025"]))
    for e in _per_stroke(sim.run_strokes(2, record=False)):
        assert e["residual_j"] < -100 * ENERGY_RTOL * e["polished_rod_work_j"]


def test_energy_balance_closes_on_the_qp_path(reference: RunResult) -> None:
    e = reference.energy_j
    assert abs(e["residual_j"]) <= ENERGY_RTOL * e["polished_rod_work_j"]


def test_randomised_reset_redraws_a_well_whose_warm_up_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    """Auto-reset inside a training loop must not raise: the first two wells drawn fail, the third runs."""
    from srenv.envs import sucker_rod_v0 as mod

    env = gym.make("srenv/SuckerRod-v0", overrides={"simulation.always_qp": True}).unwrapped
    built = {"n": 0}
    real = StepQP._solve_once

    class CountingSim(mod.Simulator):
        def __init__(self, *a, **k) -> None:
            super().__init__(*a, **k)
            built["n"] += 1

    monkeypatch.setattr(mod, "Simulator", CountingSim)
    monkeypatch.setattr(StepQP, "_solve_once",
                        lambda self, p, n, t: None if built["n"] <= 2 else real(self, p, n, t))
    obs, info = env.reset(seed=0)
    assert built["n"] == 3 and np.all(np.isfinite(obs)) and "failure" not in info
    # without randomisation there is nothing to redraw: the failure is reported
    built["n"] = 0
    with pytest.raises(SolverFailure):
        env.reset(seed=0, options={"randomize": False})


@pytest.mark.parametrize("exc", [srenv.ConfigError("surface.spm", [1, 2], "a number in 1/min"),
                                 srenv.SolverFailure(7, 0.25, "no backend converged"),
                                 NumericFailure("trace", "nan in load")])
def test_typed_errors_cross_a_process_boundary_whole(exc: Exception) -> None:
    """A worker's error comes back pickled (ProcessPoolExecutor: sweep, benchmark runner): it must unpickle as the
    same type with the same fields and one-line message, not as a TypeError from __init__ (a 'broken' pool)."""
    import pickle

    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is type(exc) and str(back) == str(exc)
    assert {k: getattr(back, k) for k in exc._fields} == {k: getattr(exc, k) for k in exc._fields}
