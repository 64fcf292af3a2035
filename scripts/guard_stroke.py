"""Issue 24, helper b43: the SHIPPED oracle-distilled students under a guard whose fallback changes what the tuned
alarm_pump_off pumps on a tagging (or pound) card, chosen on training wells; one gate; the looks only if it passes.

a43's guard handed a tagging well to alarm_pump_off, which pumped on at the same stroke and tagged as much. Here the
fallback is that baseline with its ``a_stroke`` / ``a_spm`` changed (a variant's ``fallback``). The inner is the
shipped ensemble exactly as its test and fresh looks played it: docs/v2/benchmark.json's record rebuilt by
replay's ``policy_specs`` (models/oracle_distilled_v2_seed{0,1,2}.zip, residual on the tuned pump_off, scale 0.5,
uncapped), the models' sha256 checked. Everything is pre-registered in
configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml (its ``history``); the stages are
scripts/guard_described.py's, handed this design's :data:`PLAN`:

    PYTHONPATH=. nice -n 5 python scripts/guard_stroke.py --stage mechanism --out runs/b43
    PYTHONPATH=. nice -n 5 python scripts/guard_stroke.py --stage select --out runs/b43 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/guard_stroke.py --stage gate --out runs/b43 --workers 2

``--stage read`` (after the selection, judging nothing): per variant, the episodes its guard changed and how many of
them had a tagging event -> OUT/read.json.
``--stage mechanism`` (before the family was registered; judging nothing): on a training well with a tagging event
(:data:`MECHANISM_SEED`), the tuned alarm_pump_off with each of :data:`MECHANISM` parameter changes from the start:
the tagging intervals' cost, damage, SPM, stroke, duty and the classifier's tagging probability -> OUT/mechanism.json.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import arguments
from guard_described import BASE, REFERENCE, Plan, registered, run_stage
from guard_pilot import INTERVALS, shipped
from oracle_distill_more import ROOT, write_json

from agents.benchmark.assemble import guarded_record
from agents.inputs import baseline_params
from agents.policies.guarded import check_guard, guarded_spec

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml"
SELECT_SEEDS = list(range(59450, 59500))  # THE SELECTION's: training wells 50..99 once each (seed mod 200)
GATE_SEEDS = list(range(21750, 21800))  # THE GATE's: v2's validation wells 0..49 once each (seed mod 50)
FRESH_SEED = 20261206  # THE FRESH LOOK's (registered; never played before)
STAGES = ("mechanism", "select", "gate", "test", "read")
LOOK_NAME = "oracle_distilled_guarded"  # the design's name in the looks' reports (the config's evaluate_only.agents)
MODELS_SHA256 = {  # the shipped students, as registered in the config's history
    "oracle_distilled_v2_seed0.zip": "45bded836663b230551420939e09b19d798ce16d789ae54d09ccd9777eed597c",
    "oracle_distilled_v2_seed1.zip": "0f3aed9edf15786fa641fbbc48adb7b8a611c27697c8bcc95d30f521e059374a",
    "oracle_distilled_v2_seed2.zip": "8bee1e1eec695d10560bb941dfcd07b8b20dd63f1a0072c15c66b3345ccc6e42"}

# THE MECHANISM CHECK (not a selection): a training well with a tagging event, a43's selection seed 59404
# (train-004, tagging_down from 3.1 h), and the fallback's parameter changes it compares
MECHANISM_SEED = 59404
MECHANISM: dict[str, dict[str, float]] = {
    "tuned": {}, "stroke-0.5": {"a_stroke": -0.5}, "stroke-1": {"a_stroke": -1.0},
    "stroke-1_spm0.0": {"a_stroke": -1.0, "a_spm": 0.0}, "stroke-1_spm-0.6": {"a_stroke": -1.0, "a_spm": -0.6},
    "idle": {"a_spm": -1.0}}


# THE GUARD FAMILY (the config's history), declared once, chosen after the mechanism check (idling is the only
# fallback that stops the tagging cost; the shorter, slower stroke is kept for the pound signal): tagging x pound x
# fallback x hold, follow_shut_in always
TAG = (0.5, 0.8)  # prob_tagging_up and prob_tagging_down above T (the classifier's tagging labels)
POUND: dict[str, dict[str, float]] = {"none": {}, "pound": {"fillage_est": 0.85}}
FALLBACK: dict[str, dict[str, float]] = {"idle": {"a_spm": -1.0}, "short_slow": {"a_stroke": -1.0, "a_spm": -0.6},
                                         "short": {"a_stroke": -1.0}}
HOLD = (3, 6)


def family() -> dict[str, dict[str, Any] | None]:
    """{name: {"guard", "fallback"}} - variant 0 (the reference: None), then the grid in its declared order."""
    out: dict[str, dict[str, Any] | None] = {REFERENCE: None}
    for t, (p, below), (f, change), h in itertools.product(TAG, POUND.items(), FALLBACK.items(), HOLD):
        out[f"tag{t}_{p}_{f}_hold{h}"] = {
            "guard": {"above": {"prob_tagging_up": t, "prob_tagging_down": t}, "below": dict(below),
                      "hold_intervals": h, "follow_shut_in": True}, "fallback": dict(change)}
    return out


VARIANTS = family()
for _v in VARIANTS.values():  # every guard bounded where the guarded policy bounds it
    if _v is not None:
        check_guard(_v["guard"])


def inner() -> dict[str, Any]:
    """The shipped ensemble's spec, as docs/v2/benchmark.json records it, its models' sha256 checked."""
    ens, _ = shipped()
    for m in ens["members"]:
        registered(Path(m["path"]), MODELS_SHA256, "shipped student's")
    return ens


def fallback_params(tuned: dict[str, Any], change: dict[str, float]) -> dict[str, Any]:
    """The tuned alarm_pump_off's parameters with a variant's changes, bounded where every baseline's are."""
    return baseline_params(BASE, {**tuned, **change}, f"fallback.{BASE}")


def specs(out: Path, d: dict[str, Any], variants: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """alarm_pump_off (the tuned parameters) and every variant's spec: the shipped ensemble under its guard, the
    fallback the tuned alarm_pump_off with the variant's changes."""
    ens = inner()
    tuned = d["tuned"][BASE]["params"]
    return {BASE: {"kind": "baseline", "name": BASE, "params": tuned},
            **{n: ens if v is None else guarded_spec(ens, BASE, fallback_params(tuned, v["fallback"]), v["guard"])
               for n, v in variants.items()}}


def look_design(out: Path, name: str, tuned: dict[str, Any], to: Path) -> tuple[str, dict, dict]:
    """(report name, spec, record) of the chosen variant on the re-tuned baselines (the shipped models in models/)."""
    from oracle_distill_pooled import NAME, design

    d = {**design(CONFIG), "tuned": tuned}
    spec = specs(out, d, {name: VARIANTS[name]})[name]
    return LOOK_NAME, spec, guarded_record({**spec, "of": NAME}, d["cfg"]["agents"]["runs"], [])


def mechanism(out: Path) -> dict[str, Any]:
    """THE MECHANISM CHECK (module docstring) -> OUT/mechanism.json."""
    import gymnasium as gym
    import numpy as np
    from oracle_distill_pooled import design

    from agents.evaluation.agent import build_policy

    tuned = design(CONFIG)["tuned"][BASE]["params"]
    env = gym.make("srenv/SuckerRod-v2", observation="field", scenario="train")
    i_tag = list(env.unwrapped.obs_names).index("prob_tagging_down")
    rec: dict[str, Any] = {"stage": "mechanism", "seed": MECHANISM_SEED, "rows": {}}
    for k, change in MECHANISM.items():
        pol = build_policy({"kind": "baseline", "name": BASE, "params": fallback_params(tuned, change)}, env)
        obs, _ = env.reset(seed=MECHANISM_SEED)
        if hasattr(pol, "reset"):
            pol.reset(env)
        rows, ret, state, done = [], 0.0, None, False
        while not done:
            act, state = pol.predict(obs, state)
            obs, r, term, trunc, info = env.step(act)
            ret += r
            if str(info["condition"]).startswith("tagging"):
                rows.append([info["cost_tagging"], info["reward_tagging"], info["avg_spm"], info["stroke_length_m"],
                             info["duty"], info["strokes"], obs[i_tag]])
            done = term or trunc
        a = np.array(rows, float)
        rec["well_id"] = info["well_id"]
        rec["rows"][k] = {"change": change, "usd_h": ret / INTERVALS, "tagging_intervals": len(a),
                          "cost_tagging": float(a[:, 0].sum()), "reward_tagging_usd_h": float(a[:, 1].mean()),
                          "avg_spm": float(a[:, 2].mean()), "stroke_length_m": float(a[:, 3].mean()),
                          "duty": float(a[:, 4].mean()), "strokes": float(a[:, 5].sum()),
                          "prob_tagging_down": float(a[:, 6].mean())}
    write_json(out / "mechanism.json", rec)
    return rec


PLAN = Plan(CONFIG, SELECT_SEEDS, GATE_SEEDS, VARIANTS, specs, look_design, precheck=False)


def read(eps: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    """Read after the selection, judging nothing: per variant, on how many episodes it acted otherwise than the
    unguarded inner (the guard fired), how many of those had a tagging event (the inner's tagging cost > 0), and the
    mean d vs the inner (USD/h over all episodes) carried by the tagging episodes and by the others."""
    ref = eps[REFERENCE]
    tagged = {i for i, e in enumerate(ref) if e["cost_tagging"] > 0}
    out: dict[str, Any] = {"tagging_episodes": [ref[i]["well_id"] for i in sorted(tagged)]}
    for n, v in eps.items():
        if n in (BASE, REFERENCE):
            continue
        d = [(e["reward"] - r["reward"]) / INTERVALS for e, r in zip(v, ref)]
        fired = {i for i, x in enumerate(d) if x != 0.0}
        out[n] = {"fired": len(fired), "fired_tagging": len(fired & tagged),
                  "d_tagging": sum(d[i] for i in tagged) / len(d),
                  "d_other": sum(d[i] for i in fired - tagged) / len(d),
                  "tagging_cost": [round(v[i]["cost_tagging"], 2) for i in sorted(tagged)]}
    return out


TRACED = "tag0.8_none_idle_hold3"  # --stage read traces this variant (tagging limits only, the idle fallback)


def why(seed: int, name: str = TRACED) -> dict[str, Any]:
    """One selection episode of a variant, interval by interval: how often the tagging limits fired, how often the
    fallback's shut-in alarm held the well, and the first card they fired on (its interval and true condition; the
    cards after it are an idle well's stale ones)."""
    import gymnasium as gym
    from oracle_distill_pooled import design

    from agents.evaluation.agent import build_policy

    env = gym.make("srenv/SuckerRod-v2", observation="field", scenario="train")
    pol = build_policy(specs(None, design(CONFIG), {name: VARIANTS[name]})[name], env)
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    limits, shut, first, k, done, info = 0, 0, None, 0, False, {}
    while not done:
        if pol.fires(obs):
            limits += 1
            first = first or {"interval": k, "condition": str(info.get("condition", "(the well as found)"))}
        before = pol.fired
        act, _ = pol.predict(obs)
        st = pol.fallback.state
        shut += int(pol.fired > before and st is not None and float(st.reshape(-1, 4)[0, 2]) > 0.5)
        obs, _, term, trunc, info = env.step(act)
        done, k = term or trunc, k + 1
    return {"well_id": info["well_id"], "limits_fired": limits, "shut_in": shut, "first_fired_on": first}


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "mechanism":
        for k, r in mechanism(a.out)["rows"].items():
            print(k, {n: round(v, 3) if isinstance(v, float) else v for n, v in r.items()})
        return
    if a.stage == "read":
        path = a.out / "select" / "episodes.json"
        if not path.is_file() or path.is_symlink():
            print(f"guard_stroke: {path}: no such file: expected --stage select's episodes", file=sys.stderr)
            sys.exit(2)
        eps = json.loads(path.read_text())
        rec = read(eps)
        ref, v = eps[REFERENCE], eps[TRACED]
        rec["traced"] = {TRACED: [why(r["seed"]) for r, e in zip(ref, v) if e["reward"] != r["reward"]]}
        write_json(a.out / "read.json", rec)
        print(json.dumps(rec, indent=1))
        return
    run_stage(a.stage, a.out, a.workers, PLAN)


if __name__ == "__main__":
    main()
