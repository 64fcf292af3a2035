"""A student that sees the last K field observations (agents/policies/history.py, issue 24 task h24): K = 1 is
today's student input bit for bit, K = 3 stacks oldest first and pads an episode's first intervals with its first
observation, a bad K is refused, and the evaluation's residual policy feeds a distilled K = 3 student exactly the
inputs it was trained on."""

from __future__ import annotations

import numpy as np
import pytest

import srenv  # noqa: F401
from agents.envs import make_env
from agents.evaluation.agent import build_policy
from agents.evaluation.rollout import Runner
from agents.policies.history import History, check_history
from agents.policies.residual import augment
from agents.training.oracle_distill import distill_oracle, oracle_episode_job, oracle_jobs

ENV = "srenv/SuckerRod-v2"
KW = {"observation": "field", "episode_hours": 0.5, "event_rate_scale": 0.0, "scenario": "train"}
PO = {"threshold": 0.9, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0}
FPI = {"setpoint": 0.95, "kp": 0.5, "ki": 0.2, "a_stroke": 0.0}
ORACLE = {"horizon": 2, "replan_every": 2, "steps": [0.3], "policies": [["pump_off", PO], ["fillage_pi", FPI]]}
RES = {"base": "pump_off", "params": PO, "scale": 0.5}


def test_k1_is_the_observation_and_k3_stacks_oldest_first_padded_with_the_first():
    o = [np.full(2, i, np.float32) for i in range(4)]
    h1 = History(1)
    assert all(np.array_equal(h1.push(x), x) and h1.push(x).shape == x.shape for x in o)
    h3 = History(3)
    got = [h3.push(x) for x in o]
    assert got[0].tolist() == [0, 0, 0, 0, 0, 0]  # padded with the first observation, not zeros
    assert got[1].tolist() == [0, 0, 0, 0, 1, 1]
    assert got[2].tolist() == [0, 0, 1, 1, 2, 2]
    assert got[3].tolist() == [1, 1, 2, 2, 3, 3]
    h3.reset()  # a new episode pads with ITS first observation
    assert h3.push(o[3]).tolist() == [3, 3, 3, 3, 3, 3]


@pytest.mark.parametrize("k", [0, -1, 17, 1.5, True, "3", None])
def test_bad_k_is_refused(k):
    with pytest.raises(ValueError, match=f"history = {k!r}: expected an integer in 1..16"):
        check_history(k)
    with pytest.raises(ValueError, match="history = "):
        distill_oracle(None, {"iterations": 1, "episodes": 1, "history": k}, ORACLE, RES, ENV, KW,
                       {"net_arch": [8, 8]}, [50000], 0, None)


def test_history_without_a_residual_is_refused(tmp_path):
    with pytest.raises(ValueError, match="a history needs a residual student"):
        build_policy({"kind": "agent", "path": "x.zip", "history": 3}, None)


def test_labelled_inputs_k1_are_todays_and_k3_stack_the_same_episode():
    """beta 1 (the oracle acts; no student): one trajectory whatever K, so the inputs can be compared row by row."""
    today = {k: v for k, v in oracle_jobs(ENV, KW, ORACLE, RES, None, [7], 1.0, 0)[0].items() if k != "history"}
    e0 = oracle_episode_job(today)  # a job without the key: today's behaviour
    e1 = oracle_episode_job(oracle_jobs(ENV, KW, ORACLE, RES, None, [7], 1.0, 0, history=1)[0])
    e3 = oracle_episode_job(oracle_jobs(ENV, KW, ORACLE, RES, None, [7], 1.0, 0, history=3)[0])
    np.testing.assert_array_equal(e0["x"], e1["x"])
    np.testing.assert_array_equal(e0["label"], e3["label"])
    obs, b = e1["x"][:, :-2], e1["x"][:, -2:]
    n, t = obs.shape
    assert n >= 3 and e3["x"].shape == (n, 3 * t + 2)
    for i in range(n):
        want = augment(np.concatenate([obs[max(i - 2, 0)], obs[max(i - 1, 0)], obs[i]]), b[i])
        np.testing.assert_array_equal(e3["x"][i], want)


def test_evaluation_feeds_a_k3_student_its_training_inputs(tmp_path):
    """The distilled student acting alone in a labelled episode (beta 0) and the benchmark's policy built from its
    spec, on the same episode, must see exactly the same inputs (same stack, same padding)."""
    with Runner(1) as runner:
        spec = distill_oracle(runner, {"iterations": 2, "episodes": 1, "history": 3}, ORACLE, RES, ENV, KW,
                              {"net_arch": [8, 8]}, [50000, 50001], 0, tmp_path / "student.zip")
    assert spec["history"] == 3
    x = oracle_episode_job(oracle_jobs(ENV, KW, ORACLE, RES, spec, [50001], 0.0, 0, history=3)[0])["x"]
    env = make_env(ENV, **KW)
    pol = build_policy({"kind": "agent", "path": spec["path"], "obs_norm": spec["obs_norm"], "residual": RES,
                        "history": 3}, env)
    seen, inner = [], pol.model.predict

    def spy(o, **kw):
        seen.append(np.asarray(o, np.float32).copy())
        return inner(o, **kw)

    pol.model.predict = spy
    obs, _ = env.reset(seed=50001)
    pol.reset(env)
    done = False
    while not done:
        obs, _, term, trunc, _ = env.step(pol.predict(obs)[0])
        done = term or trunc
    assert x.shape[1] == 3 * len(obs) + 2
    np.testing.assert_allclose(np.array(seen), x, rtol=0, atol=1e-6)


def test_k1_spec_keeps_todays_keys(tmp_path):
    with Runner(1) as runner:
        spec = distill_oracle(runner, {"iterations": 1, "episodes": 1}, ORACLE, RES, ENV, KW, {"net_arch": [8, 8]},
                              [50000], 0, tmp_path / "student.zip")
    assert "history" not in spec


def _pilot():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scripts" / "history_pilot.py"
    spec = importlib.util.spec_from_file_location("history_pilot", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("k", [1, 3])
def test_pilot_plays_a_student_with_the_history_it_was_trained_with(tmp_path, k):
    import json

    (tmp_path / "distill.json").write_text(json.dumps({"history": k}))
    spec = _pilot().student_spec(tmp_path, {"pump_off": PO})
    assert spec["residual"] == {"base": "pump_off", "scale": 0.5, "params": PO}
    assert spec.get("history", 1) == k and ("history" in spec) == (k != 1)  # K = 1: today's spec


def test_pilot_refuses_bad_k_with_one_line(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "scripts/history_pilot.py", "--distill", str(tmp_path / "d"), "--history",
                        "0"], check=False, capture_output=True, text=True, cwd=repo, timeout=120,
                       env={"PYTHONPATH": str(repo), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    want = "history_pilot: history = 0: expected an integer in 1..16 (field observations stacked)"
    assert r.stderr.strip().splitlines() == [want]
    assert not (tmp_path / "d").exists()
