"""scripts/v3_mechanism.py, v3_baselines.py, v3_tune.py and v3_validation.py (issue 24; docs/task.md, "v3";
docs/v3/benchmark.md): no arguments (one line, exit 2); the mechanism figures show v3's mechanisms against v2's;
the slow-down rule slows alarm_pump_off by its gas_slowdown on a tagging or leak alarm and leaves it alone
otherwise; an episode books every interval under its true condition; the validation figures' booking by condition
group, their best tuned baseline (by the training score) and paired differences over the wells."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"


def _script(name: str):
    sys.path.insert(0, str(SCRIPTS))  # as when it runs
    return importlib.import_module(name)


@pytest.fixture(scope="module")
def mech():
    return _script("v3_mechanism")


@pytest.fixture(scope="module")
def base():
    return _script("v3_baselines")


@pytest.mark.parametrize("name", ["v3_mechanism", "v3_baselines", "v3_tune", "v3_validation"])
def test_an_argument_is_refused_in_one_line(name, capsys) -> None:
    with pytest.raises(SystemExit) as ex:
        _script(name).main(["--out", "x"])
    err = capsys.readouterr().err.strip().splitlines()
    assert ex.value.code == 2 and len(err) == 1 and "--out" in err[0] and "expected" in err[0]


def test_the_figures_show_the_mechanisms(mech, capsys) -> None:
    mech.main([])
    d = json.loads(capsys.readouterr().out)
    v2, v3 = (d["tagging"][k] for k in mech.VERSIONS)
    by = {(r["spm"], r["stroke_m"], r["severity"]): r["reward_tagging_usd_h"] for r in v3}
    assert by[(3.0, "installed", 0.6)] > by[(8.0, "installed", 0.6)] and by[(8.0, "installed", 0.0)] == 0.0
    assert by[(6.0, 1.6, 0.6)] > by[(6.0, "installed", 0.6)]
    assert len({r["reward_tagging_usd_h"] for r in v2 if r["spm"] == 6.0}) == 1  # v2: the stroke moves nothing
    leak3 = d["leaks"][mech.VERSIONS[1]]
    assert all(s["3.0"] > s["5.0"] > s["8.0"] for s in leak3.values())
    ref = d["tag_reference"]
    assert ref["shipped_reference_m_s"] == pytest.approx(ref["reference_m_s"], rel=0.01)


def test_the_rule_slows_on_a_tagging_or_leak_alarm_only(base) -> None:
    from agents.policies.alarms import AlarmPumpOffPolicy
    from srenv.envs.sucker_rod_v3 import FIELD_OBS_NAMES

    params = {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0, "load_drop": 0.5,
              "alarm_prob": 0.6, "gas_slowdown": 0.6}
    obs = np.zeros(len(FIELD_OBS_NAMES), np.float32)
    obs[FIELD_OBS_NAMES.index("pprl")], obs[FIELD_OBS_NAMES.index("fillage_est")] = 1.0, 1.0
    for label, slowed in (("tagging_down", True), ("travelling_valve_leak", True), ("full", False)):
        o = obs.copy()
        o[FIELD_OBS_NAMES.index(f"prob_{label}")] = 0.9
        ref = AlarmPumpOffPolicy(FIELD_OBS_NAMES, **params).predict(o, None, np.array([True]))[0]
        rule = base.SlowOnAlarm(FIELD_OBS_NAMES, **params).predict(o, None, np.array([True]))[0]
        assert rule[1] == ref[1] and ref[0] > -0.4  # the baseline pumps here
        assert rule[0] == (pytest.approx(max(ref[0] - 0.6, -1.0)) if slowed else ref[0]), label


def test_an_episode_is_booked_by_condition(base, monkeypatch) -> None:
    from agents.envs import make_env

    monkeypatch.setattr(base, "SEEDS", range(59600, 59601))
    env = make_env("srenv/SuckerRod-v3", scenario="train", observation="field", episode_hours=1.0)
    got = base.episodes(env, base.policies(env)["installed"])
    rows = got["per_condition"].values()
    assert sum(r["intervals"] for r in rows) == 12
    assert sum(r["reward"] for r in rows) / 12 == pytest.approx(got["mean_reward_rate_usd_h"], rel=1e-12)


def test_validation_figures_book_by_condition_and_pair_by_well() -> None:
    val = _script("v3_validation")
    tr = {"condition": ["None", "tagging_down", "tagging_down", "gas_interference", "mystery"],
          "reward": [10.0, 4.0, 2.0, 6.0, 1.0], "cost": [0.0, 1.0, 0.5, float("nan"), 0.0]}
    pc = val.per_condition(tr)
    assert pc["normal"] == {"intervals": 1, "reward": 10.0, "cost": 0.0}
    assert pc["tagging"] == {"intervals": 2, "reward": 6.0, "cost": 1.5} and pc["gas"]["cost"] == 0.0
    assert pc["other:mystery"]["intervals"] == 1  # an unknown label is shown, never dropped
    table = val.condition_table([{"per_condition": pc}, {"per_condition": {"tagging": pc["tagging"]}}])
    assert table["tagging"] == {"intervals": 4, "episodes": 2, "reward_usd_h": 3.0, "cost_per_interval": 0.75}
    tuned = {"installed": {"params": {}}, "pump_off": {"params": {}, "score": 5.0},
             "alarm_pump_off": {"params": {}, "score": 6.0}, "oracle": {"params": {}}}
    assert val.best_tuned(tuned) == "alarm_pump_off"
    eps = [{"well_id": f"w{k}", "seed": k, "reward": 100.0 + k, "cost": 0.0, "reward_rate_usd_h": (100.0 + k) / 4,
            "per_condition": {}} for k in range(3)]
    rep = {"policies": {"a": {"kind": "baseline", "episodes": eps},
                        "b": {"kind": "agent", "episodes": [{**e, "reward": e["reward"] + 8.0} for e in eps]}},
           "summary": {"a": {"normalised_score": 0.0, "failures": 0}, "b": {"normalised_score": 1.0, "failures": 0}}}
    fig = val.figures(rep, "a", 4)
    assert fig["b"]["vs_best_tuned_usd_h"]["mean"] == pytest.approx(2.0)  # 8 return units over 4 intervals
    assert fig["b"]["vs_best_tuned_usd_h"]["n_wells"] == 3 and fig["a"]["vs_best_tuned_usd_h"]["mean"] == 0.0
