"""Issue 24, helper a43: a deployment-time guard on d42's FROZEN described students, chosen on training wells.

d42's design (described students, f24's cap, residual on the tuned pump_off at scale 0.5) failed gate 2 on its CI
and its cost: one validation well where it pumps all day and tags, one where alarm_pump_off loses to stick-slip.
Does a guard (agents/policies/guarded.py, fallback the tuned alarm_pump_off) remove the tagging / cost tail without
losing the median gain? Everything below is pre-registered in
configs/benchmark/v2_oracle_distilled_described_guarded.yaml (its ``history``):

    mkdir -p runs/a43 && cp -r /work/keep/d42/d42/design /work/keep/d42/d42/precheck.json runs/a43/
    PYTHONPATH=. nice -n 5 python scripts/guard_described.py --stage select --out runs/a43 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/guard_described.py --stage gate --out runs/a43 --workers 2

``--stage select`` (training wells only): alarm_pump_off and every variant (:data:`VARIANTS`: the unguarded inner
and the declared guard grid) on :data:`SELECT_SEEDS`, THE SELECTION RULE (:func:`choose`) -> OUT/select.json.
``--stage gate`` (only with a chosen variant): that variant once on v2's validation split (:data:`GATE_SEEDS`)
against alarm_pump_off by play_design_gate -> OUT/gate/gate.json.
``--stage tails`` (after the looks, judging nothing): the chosen variant on gate 2's two tail episodes.
``--stage test`` (only after a passed gate): THE TEST LOOK, scripts/v2_test_look.py's ``test_look`` with this design
(the baselines re-tuned by the benchmark's code and checked equal to the ones the design was gated with; d42's fits
copied to OUT/test/models, sha256 checked, where the report's ``models/`` names resolve) -> OUT/test/benchmark.json.
The fresh look then rebuilds the design from that report (``described`` and ``guarded`` records):

    PYTHONPATH=. nice -n 5 python scripts/guard_described.py --stage test --out runs/a43 --workers 2
    python -m agents benchmark configs/benchmark/v2_oracle_distilled_described_guarded.yaml --evaluate-only \
        --fresh-seed 20261205 --episodes 40 --report runs/a43/test/benchmark.json --out-dir runs/a43/fresh
"""

from __future__ import annotations

import argparse
import copy
import itertools
import json
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import arguments
from guard_pilot import play_validation, summarise
from oracle_distill_described import GATE2_SEEDS, design_spec
from oracle_distill_more import ROOT, episode_tables, play_design_gate, write_json
from oracle_distill_pooled import NAME, design, require_precheck

from agents.benchmark.assemble import guarded_record
from agents.benchmark.runs import residual_spec
from agents.evaluation.manifest import sha256
from agents.policies.guarded import guarded_spec

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_described_guarded.yaml"
SELECT_SEEDS = list(range(59400, 59450))  # THE SELECTION's: training wells 0..49 once each (seed mod 200)
GATE_SEEDS = list(range(21700, 21750))  # THE GATE's: v2's validation wells 0..49 once each (seed mod 50)
BASE = "alarm_pump_off"  # the fallback and the baseline every variant is judged against
REFERENCE = "unguarded"  # variant 0: the inner as it is (reported, not a candidate)
STAGES = ("select", "gate", "test", "tails")
TAILS = (3, 20)  # gate 2's two tail wells (validation-003: tagging; validation-020: stick-slip), its seeds' indices
LOOK_NAME = "oracle_distilled_guarded"  # the design's name in the looks' reports (the config's evaluate_only.agents)
FITS_SHA256 = {  # d42's frozen fits, as registered in the config's history
    "oracle_distilled_v2_seed0.zip": "359b418671b20164fa823b09f38cc8594eef06b5a4fede689480546106f25463",
    "oracle_distilled_v2_seed1.zip": "32d4036bc512231ba8aceeda9b0ed0480856f243be2cb0c2adf03ceaede3d623",
    "oracle_distilled_v2_seed2.zip": "8a445f9731bcffd75a98ae8c8dcb73bc8ffbabd3ab0f7892c617688fe760f0ea"}

# THE GUARD FAMILY (the config's history), declared once: tagging x pound x load x hold, follow_shut_in always
TAG = (0.3, 0.5)  # prob_tagging_up and prob_tagging_down above T (the classifier's tagging labels)
POUND: dict[str, dict[str, float]] = {"none": {}, "pound": {"fillage_est": 0.85},
                                      "pound_minspm": {"fillage_est": 0.85, "spm": 0.45}}
LOAD: dict[str, dict[str, float]] = {"noload": {}, "load95": {"pprl": 0.95}}
HOLD = (3, 6)


def family() -> dict[str, dict[str, Any] | None]:
    """{name: guard} - variant 0 (``unguarded``: None), then the grid in its declared order."""
    out: dict[str, dict[str, Any] | None] = {REFERENCE: None}
    for t, (p, below), (ld, above), h in itertools.product(TAG, POUND.items(), LOAD.items(), HOLD):
        out[f"tag{t}_{p}_{ld}_hold{h}"] = {"above": {"prob_tagging_up": t, "prob_tagging_down": t, **above},
                                           "below": dict(below), "hold_intervals": h, "follow_shut_in": True}
    return out


VARIANTS = family()


@dataclass(frozen=True)
class Plan:
    """One guard design's registered pieces (its config's history): the stages below play any of them.
    ``variants`` {name: guard | {"guard", "fallback"} | None (the reference)}; ``specs`` (OUT, design(config),
    variants) -> {name: policy spec} with alarm_pump_off first; ``look`` (OUT, name, re-tuned baselines, TO) ->
    (report name, spec, record) for the test look; ``precheck``: the stages need d42's OUT/precheck.json."""
    config: Path
    select_seeds: list[int]
    gate_seeds: list[int]
    variants: dict[str, Any]
    specs: Callable[..., dict[str, dict[str, Any]]]
    look: Callable[..., tuple[str, dict, dict]]
    precheck: bool = True


def registered(path: Path, digests: dict[str, str], what: str) -> None:
    """Stop unless ``path`` is the file its design's history registered (``digests`` by file name)."""
    if sha256(path) != digests.get(path.name):
        raise SystemExit(f"{path}: sha256 differs from the registered {what}")


def guard_of(variant: Any) -> dict[str, Any] | None:
    """A variant's guard (a variant is its guard, or {"guard", "fallback"} with the fallback's parameter changes)."""
    return variant.get("guard") if isinstance(variant, dict) and "fallback" in variant else variant


def conditions(guard: dict[str, Any] | None) -> int:
    """The number of limits a guard watches (above + below): the selection's tie-break."""
    return 0 if guard is None else len(guard.get("above") or {}) + len(guard.get("below") or {})


def choose(summ: dict[str, Any], variants: dict[str, Any] = VARIANTS) -> str | None:
    """THE SELECTION RULE: among the guarded variants (not the reference) whose mean constraint cost is at most
    alarm_pump_off's, the highest lower bound of the paired 95 % CI vs alarm_pump_off; ties -> fewer guard conditions,
    then the declared order. None if none qualifies or the best lower bound is <= 0 (a negative result, no gate)."""
    order = [n for n in variants if n != REFERENCE and n in summ and summ[n]["cost"] <= summ[BASE]["cost"]]
    if not order:
        return None
    best = min(order, key=lambda n: (-summ[n][f"vs_{BASE}"]["ci95"][0], conditions(guard_of(variants[n])),
                                     order.index(n)))
    return best if summ[best][f"vs_{BASE}"]["ci95"][0] > 0 else None


def specs(out: Path, d: dict[str, Any], variants: dict[str, Any] = VARIANTS) -> dict[str, dict[str, Any]]:
    """alarm_pump_off (the tuned parameters) and every variant's policy spec: d42's frozen design (OUT/design) under
    its guard, fallback the tuned alarm_pump_off."""
    inner = design_spec(out, d)
    fb = d["tuned"][BASE]["params"]
    return {BASE: {"kind": "baseline", "name": BASE, "params": fb},
            **{n: inner if g is None else guarded_spec(inner, BASE, fb, g) for n, g in variants.items()}}


def select(out: Path, workers: int, plan: Plan | None = None) -> dict[str, Any]:
    """THE SELECTION on the training wells (the plan's select_seeds) -> OUT/select.json."""
    p = plan or A43
    if p.precheck:
        require_precheck(out)
    d = design(p.config)
    sp = p.specs(out, d, p.variants)
    gcfg = {**copy.deepcopy(d["cfg"]), "validation": {"seeds": p.select_seeds, "scenario": "train"}}
    eps = play_validation(gcfg, sp, out / "select", workers)
    summ = summarise(eps, (BASE,))
    rec = {"stage": "select", "config": str(p.config.relative_to(ROOT)), "seeds": p.select_seeds, "scenario": "train",
           "specs": sp, "summary": summ, "conditions": {n: conditions(guard_of(v)) for n, v in p.variants.items()},
           "chosen": choose(summ, p.variants), **episode_tables(eps)}
    write_json(out / "select.json", rec)
    return rec


def chosen(out: Path, plan: Plan | None = None) -> str:
    """The variant OUT/select.json chose (the rule re-applied to its summary); exit 2 in one line without one."""
    p = plan or A43
    path = out / "select.json"
    rec = json.loads(path.read_text()) if path.is_file() and not path.is_symlink() else {}
    name = rec.get("chosen")
    if name is None or name not in p.variants or choose(rec.get("summary") or {}, p.variants) != name:
        print(f"{Path(sys.argv[0]).stem}: {path}: chosen = {name!r}: expected a variant chosen by --stage select "
              "(none chosen: a negative result, no gate)", file=sys.stderr)
        sys.exit(2)
    return name


def gate(out: Path, workers: int, plan: Plan | None = None) -> dict[str, Any]:
    """THE GATE: the chosen variant once on v2's validation split (the plan's gate_seeds) -> OUT/gate/gate.json."""
    p = plan or A43
    name = chosen(out, p)
    d = design(p.config)
    (out / "gate").mkdir(exist_ok=True)
    return play_design_gate(d["cfg"], p.config, p.gate_seeds, {name: p.specs(out, d, {name: p.variants[name]})[name]},
                            d["tuned"], d["res"], out / "gate", workers, scenario="validation", shipped=False)


def passed_gate(out: Path, plan: Plan | None = None) -> str:
    """The chosen variant, if OUT/gate/gate.json records its passed gate; exit 2 in one line otherwise."""
    name, path = chosen(out, plan), out / "gate" / "gate.json"
    rec = json.loads(path.read_text()) if path.is_file() and not path.is_symlink() else {}
    if rec.get("gate") is not True or name not in rec.get("specs", {}):
        print(f"{Path(sys.argv[0]).stem}: {path}: gate = {rec.get('gate')!r}: expected a passed gate of {name} "
              "(no look without it)", file=sys.stderr)
        sys.exit(2)
    return name


def look_design(out: Path, name: str, tuned: dict[str, Any], to: Path) -> tuple[str, dict, dict]:
    """(report name, policy spec, report record) of the chosen variant on the re-tuned baselines ``tuned``; d42's
    fits copied to TO/models (their registered sha256 checked) so the report's ``models/`` names resolve there."""
    d = design(CONFIG)
    (to / "models").mkdir(parents=True, exist_ok=True)
    for f in sorted((out / "design").glob(f"{NAME}_v2_seed*")):
        if f.suffix == ".zip":
            registered(f, FITS_SHA256, "fit's: not d42's frozen design")
        shutil.copyfile(f, to / "models" / f.name)
    d = {**d, "tuned": tuned, "res": residual_spec(d["run"], tuned)}
    spec = specs(out, d, {name: VARIANTS[name]})[name]
    return LOOK_NAME, spec, guarded_record({**spec, "of": NAME}, d["cfg"]["agents"]["runs"], [])


A43 = Plan(CONFIG, SELECT_SEEDS, GATE_SEEDS, VARIANTS, specs, look_design)


def play_test_look(out: Path, workers: int, plan: Plan | None = None) -> dict[str, Any]:
    """THE TEST LOOK (only after a passed gate) -> OUT/test/benchmark.json (and .md)."""
    from v2_test_look import test_look

    p = plan or A43
    name = passed_gate(out, p)
    d = design(p.config)
    return test_look(str(p.config.relative_to(ROOT)) if Path.cwd().resolve() == ROOT else str(p.config), out, None,
                     workers, out / "test",
                     built=lambda tuned: p.look(out, name, tuned, out / "test"),
                     expected={k: v["params"] for k, v in d["tuned"].items()})


def tails(out: Path, workers: int) -> dict[str, Any]:
    """Read after the looks, judging nothing: alarm_pump_off, the unguarded inner and the chosen variant on gate 2's
    two tail episodes (its seeds for validation-003 and -020) -> OUT/tails/tails.json. Did the guard remove them?"""
    name = chosen(out)
    d = design(CONFIG)
    seeds = [GATE2_SEEDS[k] for k in TAILS]
    gcfg = {**copy.deepcopy(d["cfg"]), "validation": {"seeds": seeds, "scenario": "validation"}}
    sp = specs(out, d, {REFERENCE: None, name: VARIANTS[name]})
    eps = play_validation(gcfg, sp, out / "tails", workers)
    rec = {"stage": "tails", "seeds": seeds, "summary": summarise(eps, (BASE,)), **episode_tables(eps),
           "trace": {str(s): trace(sp[name], d["cfg"], s) for s in seeds}}
    write_json(out / "tails" / "tails.json", rec)
    return rec


def trace(spec: dict[str, Any], cfg: dict[str, Any], seed: int) -> dict[str, Any]:
    """One validation episode of a guarded spec, interval by interval: how often the fallback acted, and the tagging
    cost and mean SPM while it acted and while the inner did (the rollout's records do not say)."""
    import gymnasium as gym

    from agents.evaluation.agent import build_policy

    env = gym.make(cfg["env_id"], **{**cfg["env_kwargs"], "scenario": "validation"})
    pol = build_policy(spec, env)
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    rows: dict[bool, list[tuple[float, float]]] = {True: [], False: []}
    done = False
    while not done:
        before = pol.fired
        act, _ = pol.predict(obs)
        obs, _, term, trunc, info = env.step(act)
        rows[pol.fired > before].append((float(info.get("cost_tagging", 0.0)), float(info["spm"])))
        done = term or trunc
    return {who: {"intervals": len(r), "tagging_cost": round(sum(t for t, _ in r), 4),
                  "mean_spm": round(sum(v for _, v in r) / len(r), 3) if r else None}
            for who, r in (("fallback", rows[True]), ("inner", rows[False]))}


def rows(rec: dict[str, Any]) -> list[str]:
    """A stage's table: USD/h, cost and its terms, d vs alarm_pump_off [95 % CI] and wins."""
    out = ["| policy | USD/h | cost (pound, overload, tagging) | vs alarm_pump_off [95 % CI] wins |", "|---|---|---|---|"]
    for k, r in rec["summary"].items():
        t = r["cost_terms"]
        v = r.get(f"vs_{BASE}")
        cell = f"{v['mean']:+.2f} [{v['ci95'][0]:+.2f}, {v['ci95'][1]:+.2f}] {v['wins']}/{v['n']}" if v else "-"
        out.append(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} ({t.get('cost_pound', 0):.2f}, "
                   f"{t.get('cost_overload', 0):.2f}, {t.get('cost_tagging', 0):.2f}) | {cell} |")
    return out


def run_stage(stage: str, out: Path, workers: int, plan: Plan | None = None) -> None:
    """--stage select | gate | test of a plan, its table printed."""
    if stage == "test":
        from agents.benchmark.report import markdown_tables, verdict

        rep = play_test_look(out, workers, plan)
        print(markdown_tables(rep))
        print(verdict(rep))
        return
    rec = select(out, workers, plan) if stage == "select" else gate(out, workers, plan)
    print("\n".join(rows(rec)))
    if stage == "select":
        print("CHOSEN:", rec["chosen"] or "none (a negative result, no gate)")
    else:
        print("GATE:", "passed" if rec["gate"] else "failed")


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "tails":
        rec = tails(a.out, a.workers)
        print(json.dumps({k: rec[k] for k in ("well_id", "per_episode_usd_h", "per_episode_cost", "trace")}))
        return
    run_stage(a.stage, a.out, a.workers)


if __name__ == "__main__":
    main()
