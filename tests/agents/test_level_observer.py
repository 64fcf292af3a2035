"""The annulus-level observer and the classifier's condition (agents/policies/level_observer.py) and their use in
estimated_mpc's twin: a known-answer annulus, the corrections, the condition rule, and that the policy with both
on still never reads the played well's hidden state."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.envs import make_env
from agents.policies.estimated_mpc import EstimatedMPCPolicy
from agents.policies.level_observer import GAIN_RANGE, PROD_GAIN, LevelObserver, condition_estimate
from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.task.events import EVENTS

AREA, DEPTH, DT = 0.008, 1500.0, 300.0  # m2, m, s: a 5-min interval


def _truth(level: float, q: float, pumped: float) -> float:
    """The annulus as srenv books it at constant inflow ``q`` (m3/s): clipped at the pump and at its depth."""
    return min(max(level + (q * DT - pumped) / AREA, 0.0), DEPTH)


def test_constant_inflow_known_answer_and_deliverability_learnt():
    """A constant-inflow annulus whose reservoir gives 1.6 x the model's IPR. Known answer: between shots the
    level error grows by |1.6 - prod| * q * dt / area per interval (7.5 m at prod 0: the balance is exact but
    for the deliverability); each shot-to-shot balance halves the deliverability's error (gain 0.5), so the error
    over each 4-h window halves: <= 216 m, 108 m, 54 m (+ the shot's residual)."""
    q_model, m_true, pumped = 2.0e-4, 1.6, 0.08  # m3/s; 0.08 m3 per interval drawn
    ob = LevelObserver(AREA, DEPTH, lambda h: q_model, level_m=300.0)
    true, errs, prods = 300.0, [], []
    for k in range(1, 145):
        true = _truth(true, m_true * q_model, pumped)
        ob.advance(DT, pumped)
        errs.append(abs(ob.level_m - true))
        if k % 48 == 0:
            ob.shot(true)
            assert ob.level_m == pytest.approx(true, abs=2.0)  # the shot corrects the level (its small variance)
            prods.append(ob.prod)
    np.testing.assert_allclose(prods, [1.3, 1.45, 1.525], rtol=1e-9)
    step = q_model * DT / AREA
    for w, (prod, bound) in enumerate(zip([1.0, 1.3, 1.45], [216.0, 108.0, 54.0])):
        window = errs[48 * w:48 * (w + 1)]
        assert max(window) == pytest.approx(bound, abs=2.0)
        assert max(window) <= abs(m_true - prod) * step * 48 + 2.0


def test_balance_exact_when_the_model_is_right():
    """The model's IPR is the reservoir's: the observer follows the level exactly and its deliverability stays 1."""
    ipr = lambda h: 1.0e-4 * (1.0 - h / DEPTH)  # a level-dependent IPR
    ob = LevelObserver(AREA, DEPTH, ipr, level_m=200.0)
    true = 200.0
    for k in range(1, 97):
        true = min(max(true + (ipr(true) * DT - 0.02) / AREA, 0.0), DEPTH)
        ob.advance(DT, 0.02)
        if k % 48 == 0:
            ob.shot(true)
        assert abs(ob.level_m - true) < 1e-6
    assert ob.prod == pytest.approx(1.0, abs=1e-6)


def test_pound_and_full_cards_correct_the_level():
    ob = LevelObserver(AREA, DEPTH, lambda h: 1.0e-4, level_m=400.0, floor_m=30.0)
    ob.var_m2 = 1.0e4  # long since the last shot
    ob.card(fillage_est=0.6, idle_s=0.0, pounded=0.9, full=0.98)
    assert ob.level_m < 10.0  # a pounding card: the pump is at the liquid, whatever the balance said
    ob.card(fillage_est=1.0, idle_s=0.0, pounded=0.9, full=0.98)
    assert ob.level_m == 30.0  # a full card: the intake is submerged, at least to the floor
    before = ob.level_m
    ob.card(fillage_est=0.95, idle_s=0.0, pounded=0.9, full=0.98)
    assert ob.level_m == before  # neither pounding nor full: no correction


def test_observer_refuses_nonsense():
    with pytest.raises(ValueError, match="area"):
        LevelObserver(0.0, DEPTH, lambda h: 0.0, level_m=10.0)
    with pytest.raises(ValueError, match="level"):
        LevelObserver(AREA, DEPTH, lambda h: 0.0, level_m=math.nan)


def test_condition_estimate():
    names = ["avg_spm", "prob_full", "prob_fluid_pound", "prob_gas_interference", "prob_parted_rods",
             "prob_tagging_up"]
    assert condition_estimate(np.array([0.5, 0.1, 0.9, 0.0, 0.0, 0.0]), names, 0.6) == (None, 0.0)  # normal
    label, sev = condition_estimate(np.array([0.5, 0.0, 0.1, 0.7, 0.2, 0.0]), names, 0.6)
    assert label == "gas_interference" and sev == pytest.approx(0.5 * sum(EVENTS["gas_interference"].severity))
    assert condition_estimate(np.array([0.5, 0.0, 0.1, 0.55, 0.0, 0.0]), names, 0.6) == (None, 0.0)  # below
    assert condition_estimate(np.array([0.5, 0.0, 0.0, 0.0, 0.99, 0.0]), names, 0.6) == (None, 0.0)  # parted: not put
    assert condition_estimate(np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.8]), names, 0.6) == ("tagging_up", 0.5)


def test_nominal_inflow_is_the_ipr_and_reads_no_state():
    env = SuckerRodV2Env(scenario="train", observation="field")
    env.reset(seed=30017)
    ann = env.sim.annulus
    v, m = ann.volume_m3, ann.rate_multiplier
    ann.rate_multiplier = 1.0
    assert ann.nominal_inflow_m3_s(ann.level_m) == ann.inflow_m3_s()
    assert ann.nominal_inflow_m3_s(0.0) > ann.nominal_inflow_m3_s(ann.pump_md_m) >= 0.0  # drawdown drives inflow
    assert ann.volume_m3 == v
    ann.rate_multiplier = m


ENV = "srenv/SuckerRod-v2"
KW = {"observation": "field", "episode_hours": 0.5, "interval_s": 300.0}
PARAMS = {"horizon": 2, "replan_every": 2, "observer": True, "condition_prob": 0.6,
          "policies": [["pump_off", {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0}]]}


HIDDEN = ("well", "sim", "cfg", "_schedule", "_condition", "_parting", "runner", "inflow_multiplier")


def _episode(pol, seed: int, n: int = 6) -> tuple[list, list]:
    """``pol``'s actions on episode ``seed`` and the observations it saw."""
    env = make_env(ENV, scenario="train", **KW)
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    acts, seen = [], []
    for k in range(n):
        a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
        acts.append(np.asarray(a).copy())
        seen.append(np.asarray(obs).copy())
        obs, _, term, trunc, _ = env.step(a)
        if term or trunc:
            break
    return acts, seen


def _blind(pol, seed: int, seen: list) -> list:
    """``pol`` reset on episode ``seed``, then everything hidden of the env set to None, fed ``seen``: its actions."""
    blind = make_env(ENV, scenario="train", **KW)
    blind.reset(seed=seed)
    pol.reset(blind)
    for name in HIDDEN:
        setattr(blind.unwrapped, name, None)
    return [np.asarray(pol.predict(o, episode_start=np.array([k == 0]))[0]) for k, o in enumerate(seen)]


def test_observer_policy_never_reads_the_hidden_state():
    """As tests/agents/test_estimated_mpc.py: with the observer and the condition on, the same observations give
    the same actions when the env's well, simulator, config, schedule, condition, parting clock and inflow are
    None after reset."""
    acts, seen = _episode(EstimatedMPCPolicy(**PARAMS), 20003)
    pol2 = EstimatedMPCPolicy(**PARAMS)
    np.testing.assert_array_equal(np.array(acts), np.array(_blind(pol2, 20003, seen)))
    assert pol2._obs_level is not None and pol2.sim_steps > len(seen)


def test_twin_takes_the_level_and_the_condition():
    env = make_env(ENV, scenario="train", **KW)
    obs, _ = env.reset(seed=20003)
    pol = EstimatedMPCPolicy(**PARAMS)
    pol.reset(env)
    pol.track(np.asarray(obs, np.float64))
    assert pol._twin.sim.annulus.level_m == pytest.approx(pol._obs_level.level_m, abs=1e-9)  # the twin is set to it
    pol._set_condition("gas_interference", 0.6)
    assert pol._twin._condition == ("gas_interference", 0.6)
    assert pol._twin.sim.cfg.pump.intake_gas_fraction > env.unwrapped.cfg.pump.intake_gas_fraction
    pol._set_condition(None, 0.0)
    assert pol._twin._condition == (None, 0.0)


@pytest.mark.parametrize("bad", [{"observer": 1}, {"observer": "yes"}, {"condition_prob": 0.0},
                                 {"condition_prob": 1.0}, {"condition_prob": True}, {"condition_prob": "0.6"}])
def test_bad_options_refused(bad):
    with pytest.raises(ValueError) as exc:
        EstimatedMPCPolicy(**{**PARAMS, **bad})
    assert next(iter(bad)) in str(exc.value) and "\n" not in str(exc.value)


@pytest.mark.parametrize("args", [["--wells", "5", "10"], ["--wells", "30", "20"], ["--wells", "16", "200"]])
def test_pilot_refuses_validation_wells_with_one_line(tmp_path, args):
    """The observer stage plays training wells 16..199 only (0..15 are the tuning and validation wells)."""
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "scripts/level_observer_pilot.py", "--stage", "observer", "--out",
                        str(tmp_path / "o"), *args], check=False, capture_output=True, text=True, cwd=repo,
                       timeout=120, env={"PYTHONPATH": str(repo), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--wells" in lines[0] and "16..199" in lines[0]
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------- observer_gain, twin: described + observer (t24c)
def test_gain_weighs_each_shots_deliverability():
    """Known answer: a constant-inflow annulus whose reservoir gives 1.6 x the model's IPR; the first shot's
    balance says 1.6 exactly, so the estimate after it is 1 + gain x 0.6 (gain 1: 1.6 at once)."""
    for gain, want in ((PROD_GAIN, 1.3), (0.75, 1.45), (1.0, 1.6)):
        ob = LevelObserver(AREA, DEPTH, lambda h: 2.0e-4, level_m=300.0, gain=gain)
        true = 300.0
        for _ in range(48):
            true = _truth(true, 1.6 * 2.0e-4, 0.08)
            ob.advance(DT, 0.08)
        ob.shot(true)
        assert ob.prod == pytest.approx(want, rel=1e-9)


def _bad_gains() -> list:
    lo, hi = GAIN_RANGE  # generated from the declaration: the open low end, past the high end, non-numbers
    return [lo, lo - 0.1, hi + 1e-9, hi + 1.0, math.nan, True, "0.5", None]


@pytest.mark.parametrize("bad", _bad_gains())
def test_bad_gain_refused_in_one_line(bad):
    with pytest.raises(ValueError, match="gain") as exc:
        LevelObserver(AREA, DEPTH, lambda h: 0.0, level_m=10.0, gain=bad)
    assert "\n" not in str(exc.value)
    if bad is not None:  # None is the policy's "the observer's default"
        with pytest.raises(ValueError, match="estimated_mpc observer_gain") as exc:
            EstimatedMPCPolicy(**PARAMS, observer_gain=bad)
        assert "\n" not in str(exc.value) and repr(bad) in str(exc.value)


def test_observer_gain_needs_the_observer():
    with pytest.raises(ValueError, match="observer_gain = 0.75: expected None without observer"):
        EstimatedMPCPolicy(**{**PARAMS, "observer": False}, observer_gain=0.75)
    assert "observer_gain" not in EstimatedMPCPolicy(**PARAMS).params()
    assert EstimatedMPCPolicy(**PARAMS, observer_gain=1.0).params()["observer_gain"] == 1.0


DESCRIBED = {**PARAMS, "twin": "described"}


def test_described_twin_with_the_observer_never_reads_the_hidden_state():
    """twin: described + observer: it runs (the twin is the described well, the observer on its annulus and IPR),
    and the same observations give the same actions when everything hidden of the env is None after reset."""
    pol = EstimatedMPCPolicy(**DESCRIBED, observer_gain=1.0)
    acts, seen = _episode(pol, 20410)
    assert pol.model_well == -1 and pol._obs_level is not None and pol._obs_level.gain == 1.0
    assert pol.sim_steps > len(seen) and pol.params()["twin"] == "described" and pol.params()["observer"] is True
    again = _blind(EstimatedMPCPolicy(**DESCRIBED, observer_gain=1.0), 20410, seen)
    np.testing.assert_array_equal(np.array(acts), np.array(again))


def test_a_shot_sets_the_twins_deliverability_to_the_estimate_at_once():
    """The deliverability the observer re-estimates at a shot is the one the plans made at that shot draw at
    (freeze_future keeps the twin's present multiplier), not the previous interval's."""
    from agents.policies.causal_oracle import freeze_future

    env = make_env(ENV, scenario="train", **KW)
    obs, _ = env.reset(seed=20410)
    pol = EstimatedMPCPolicy(**DESCRIBED, observer_gain=1.0)
    pol.reset(env)
    names = list(env.unwrapped.obs_names)
    first = np.asarray(obs, np.float64).copy()
    first[names.index("level_shot_age")] = 0.01  # the first card's shot, 0.01 of a shot period old
    pol.track(first)
    pol.played(np.array([0.0, 0.3], np.float32))
    shot = first.copy()
    shot[names.index("level_shot_age")] = 0.0  # a new shot, much higher than the balance: inflow beyond nominal
    shot[names.index("level_shot")] = min(1.0, shot[names.index("level_shot")] + 0.02)
    before = pol._obs_level.prod
    pol.track(shot)
    ann = pol._twin.sim.annulus
    assert pol._obs_level.prod > before and ann.rate_multiplier == pol._obs_level.prod
    model = freeze_future(pol._model())
    assert model.inflow_multiplier(0.0) == pol._obs_level.prod


def test_described_design_with_the_observer_off_plays_as_before():
    """The pre-registered round-1 design (configs/benchmark/v2_described_mpc.yaml: twin described, observer off)
    plays bit for bit as before the observer options were added (digest computed on the code before them, on
    numpy's AVX2 kernels: conftest.run_on_avx2_numpy)."""
    from conftest import run_on_avx2_numpy

    out = run_on_avx2_numpy(DIGEST_CODE).split()
    assert out == ["e36f478b9e099129", "114", "0"]


DIGEST_CODE = """
import hashlib
import numpy as np, yaml
from agents.envs import make_env
from agents.policies.factory import make_baseline
params = yaml.safe_load(open("configs/benchmark/v2_described_mpc.yaml"))["designs"]["described_mpc"]["params"]
env = make_env("srenv/SuckerRod-v2", scenario="train", observation="field", episode_hours=1.0, interval_s=600.0)
h = hashlib.sha256()
for seed in (20410, 20414):
    pol = make_baseline("estimated_mpc", params, env.unwrapped.obs_names)
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    for k in range(6):
        a, _ = pol.predict(obs, episode_start=np.array([k == 0]))
        obs, r, term, trunc, _ = env.step(a)
        h.update(np.asarray(a, np.float32).tobytes()); h.update(np.float64(r).tobytes())
        if term or trunc:
            break
print(h.hexdigest()[:16], pol.sim_steps, pol.guarded_intervals)
"""
