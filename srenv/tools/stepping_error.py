"""The error of a stepping option against simulating every stroke at the configured time step.

Two envs of the same task, seeded alike, take the same actions: the reference simulates every stroke of every
interval exactly (``IntervalRunner.run(..., fast_forward=False)``), the other steps as configured (v1's default,
or ``fast_stepping=True``). Per episode: production (the sum of the intervals' liquid), the largest PPRL, the
return and every reward term summed over the episode, each as a relative error against the reference
(docs/speed.md). ``scripts/stepping_error.py`` prints the table; tests/test_speed.py checks a sample.
"""

from __future__ import annotations

import functools
import math

import numpy as np

POLICIES = ("full_speed", "vsd_minimum", "hold_and_change")


def actions(policy: str, steps: int, seed: int) -> np.ndarray:
    """The action sequence of a test policy: constant at full speed, constant at the VSD minimum (a0 = -0.6,
    as the acceptance's rate check), or a setpoint held for 6 intervals at a time (a controller's pattern)."""
    if policy == "full_speed":
        return np.tile(np.float32([1.0, 1.0]), (steps, 1))
    if policy == "vsd_minimum":
        return np.tile(np.float32([-0.6, 1.0]), (steps, 1))
    if policy == "hold_and_change":
        rng = np.random.default_rng(seed)
        held = rng.uniform(-0.7, 1.0, ((steps + 5) // 6, 2)).astype(np.float32)
        return np.repeat(held, 6, axis=0)[:steps]
    raise ValueError(f"policy = {policy!r}: expected one of {', '.join(POLICIES)}")


def reward_terms(version: str = "v1") -> tuple[str, ...]:
    """The reward terms a task version reports in its info (v2 adds the conditions' terms)."""
    from ..envs.sucker_rod_v2 import V2_REWARD_TERMS
    from ..task.economics import REWARD_TERMS

    return REWARD_TERMS + (V2_REWARD_TERMS if version == "v2" else ())


def env_class(version: str):
    from ..envs.sucker_rod_v1 import SuckerRodV1Env
    from ..envs.sucker_rod_v2 import SuckerRodV2Env

    classes = {"v1": SuckerRodV1Env, "v2": SuckerRodV2Env}
    if version not in classes:
        raise ValueError(f"version = {version!r}: expected one of {', '.join(classes)}")
    return classes[version]


def episode(env, seed: int, acts: np.ndarray) -> dict:
    """Sums over one episode of the figures compared (stops early if the episode ends)."""
    env.reset(seed=seed)
    out = {"production_m3": 0.0, "pprl_max_n": 0.0, "return": 0.0, "exact_strokes": 0, "steps": 0}
    terms = reward_terms("v2" if isinstance(env.unwrapped, env_class("v2")) else "v1")
    out.update({k: 0.0 for k in terms})
    for a in acts:
        _, rew, term, trunc, info = env.step(a)
        out["production_m3"] += info["production_m3_day"] * env.unwrapped._result.duration_s / 86400.0
        out["pprl_max_n"] = max(out["pprl_max_n"], info["pprl_n"])
        out["return"] += rew
        out["exact_strokes"] += info["exact_strokes"]
        out["steps"] += 1
        for k in terms:
            out[k] += info[k]
        if term or trunc:
            break
    return out


def relative_errors(ref: dict, got: dict) -> dict:
    """|got - ref| / |ref| per figure; a reward term smaller than 0.1 % of the episode's summed |terms| is
    compared against that sum instead (a term near zero has no meaningful relative error)."""
    terms = [k for k in reward_terms("v2") if k in ref]
    scale = 1e-3 * sum(abs(ref[k]) for k in terms)
    keys = ("production_m3", "pprl_max_n", "return", *terms)
    return {k: abs(got[k] - ref[k]) / max(abs(ref[k]), scale, 1e-12) for k in keys}


def compare(policy: str, seed: int, hours: float, scenario: str = "test", interval_s: float = 300.0,
            options: dict | None = None, version: str = "v1") -> dict:
    """One episode of `hours` on well `seed` of `scenario` of task ``version`` ("v1" or "v2"; v2 draws the same
    conditions for every run of a seed): each of ``options`` (a label -> env kwargs; default v1 as it is and v1
    with fast_stepping=True) against every stroke simulated exactly. An option's ``"runner"`` entry (a dict of
    ``exact_min`` / ``follow_drift``, srenv/task/stepping.py; ``boundary_strokes``, srenv/task/boundary.py;
    ``draw_follows_pump``, srenv/task/pump_draw.py) is set on the env's interval runner at its reset."""
    from ..task.interval import IntervalRunner

    cls = env_class(version)
    options = {"v1": {}, "fast_stepping": {"fast_stepping": True}} if options is None else options
    steps = max(1, math.ceil(hours * 3600.0 / interval_s - 1e-9))
    acts = actions(policy, steps, seed)
    ref_env = cls(scenario=scenario, episode_hours=hours, interval_s=interval_s, fast_stepping=False)
    ref = _episode_every_stroke(ref_env, seed, acts, functools.partial(IntervalRunner.run, fast_forward=False))
    out = {"policy": policy, "seed": seed, "hours": hours, "reference": ref}
    for label, kw in options.items():
        kw = dict(kw)
        runner_kw = kw.pop("runner", None)
        env = cls(scenario=scenario, episode_hours=hours, interval_s=interval_s, **kw)
        got = episode(env, seed, acts) if not runner_kw else _episode_with_runner_options(env, seed, acts, runner_kw)
        out[label] = {"figures": got, "relative_error": relative_errors(ref, got)}
    return out


def _episode_after_reset(env, seed: int, acts: np.ndarray, prepare) -> dict:
    """episode() with `prepare(runner)` applied to the env's fresh interval runner after every reset (the runner keeps
    no state before its first interval, so this is the runner built that way); the env's reset is restored after."""
    reset = env.reset

    def reset_then_prepare(**kw):
        obs, info = reset(**kw)
        prepare(env.runner)
        return obs, info

    env.reset = reset_then_prepare
    try:
        return episode(env, seed, acts)
    finally:
        env.reset = reset


def _episode_every_stroke(env, seed: int, acts: np.ndarray, run) -> dict:
    """episode() with the env's interval runner simulating every stroke."""
    def every_stroke(r):
        r.run = functools.partial(run, r)

    return _episode_after_reset(env, seed, acts, every_stroke)


def _episode_with_runner_options(env, seed: int, acts: np.ndarray, runner_kw: dict) -> dict:
    """episode() with the opt-in stepping options set on the env's fresh interval runner."""
    from ..task import boundary, pump_draw, stepping

    def with_options(r):
        r.exact_min, r.follow_drift = stepping.check(runner_kw.get("exact_min", 0), runner_kw.get("follow_drift",
                                                     False), r.carry)
        r.boundary_strokes = boundary.check(runner_kw.get("boundary_strokes", 0))
        r.draw_follows_pump = pump_draw.check(runner_kw.get("draw_follows_pump", False))

    return _episode_after_reset(env, seed, acts, with_options)


def worst_term(err: dict) -> tuple[str, float]:
    """The largest relative error of an episode over production, the PPRL and the reward terms (the issue's list;
    the return is left out)."""
    k = max((k for k in err if k != "return"), key=err.get)
    return k, err[k]


def summary(rows: list[dict], labels: list[str], against: tuple[str, ...] = ("v2", "v2_drift"),
            bound: float = 0.005) -> dict:
    """Per policy and option over ``compare``'s rows: episodes within ``bound`` on every term, the median and largest
    worst term, the geometric-mean ratio of the worst term against each of ``against`` (with the episodes smaller /
    larger), and exact strokes per env step."""
    out: dict = {}
    for policy in dict.fromkeys(r["policy"] for r in rows):
        got = [r for r in rows if r["policy"] == policy]
        for label in labels:
            worst = np.array([worst_term(r[label]["relative_error"])[1] for r in got])
            line = {"episodes": len(got), "within": int(np.sum(worst <= bound)), "median": float(np.median(worst)),
                    "largest": float(worst.max()), "exact_per_step": float(
                        sum(r[label]["figures"]["exact_strokes"] for r in got)
                        / sum(r[label]["figures"]["steps"] for r in got))}
            for base in against:
                if base in got[0] and base != label:
                    b = np.array([worst_term(r[base]["relative_error"])[1] for r in got])
                    ratio = np.maximum(worst, 1e-9) / np.maximum(b, 1e-9)
                    line[f"vs_{base}"] = {"geomean": float(np.exp(np.mean(np.log(ratio)))),
                                          "smaller": int(np.sum(worst < b)), "larger": int(np.sum(worst > b))}
            out[(policy, label)] = line
    return out
