"""How much a reward term's per-stroke figure varies from stroke to stroke inside an interval when every stroke is
simulated, and how many exact strokes K an interval's mean would need to be within a bound (docs/speed.md §2g).

One episode of a test well is played with every stroke exact (as srenv.tools.stepping_error's reference); each
exact stroke's figures are kept with the interval it belongs to. Per term and interval:
- ``cv``: the standard deviation over the interval's full strokes over their mean; ``cv_detrended`` the same about
  a straight line through them (the drift with the annulus level removed);
- ``k_se``: the K for which the mean of K strokes drawn at random from the interval is within ``bound`` with 95 %
  confidence by the standard error (finite-population corrected; independent strokes assumed);
- ``k_direct``: the smallest K for which the mean of the interval's first K strokes (what a runner simulating K
  exact strokes and repeating their mean would see) and every larger K' stay within ``bound`` of the interval's
  own mean (for the peak load: the largest PPRL of the first K against the interval's largest).
A term whose episode total is under 0.1 % of the summed |terms| is not reported (as relative_errors does).
"""

from __future__ import annotations

import functools
import math

import numpy as np

# the reward term each per-stroke figure drives (srenv/task/economics.py); the peak load reads the largest PPRL
FIGURES = {"stick_slip": ("reward_stick_slip", lambda f: f.stick_slip_j),
           "pound": ("reward_pound", lambda f: f.impact_m_s ** 2),
           "peak_load": ("reward_peak_load", lambda f: f.summary["pprl_n"]),
           "fatigue": ("reward_fatigue", lambda f: f.damage),
           "energy": ("reward_energy", lambda f: f.work_j),
           "production": ("reward_revenue", lambda f: f.lifted_m3)}
Z95 = 1.96
KS = (1, 2, 4, 8, 16)
UNPRICED = ("energy", "production")  # figures the first stroke after a change counts itself


def every_stroke_intervals(policy: str, seed: int, hours: float, version: str = "v2", scenario: str = "test",
                           interval_s: float = 300.0) -> tuple[list[dict], dict]:
    """The episode played with every stroke exact: per interval the full strokes' figures (a fractional last
    stroke is left out), and the episode's summed reward terms."""
    from ..task.interval import IntervalRunner
    from .stepping_error import actions, env_class, reward_terms

    env = env_class(version)(scenario=scenario, episode_hours=hours, interval_s=interval_s, fast_stepping=False)
    steps = max(1, math.ceil(hours * 3600.0 / interval_s - 1e-9))
    env.reset(seed=seed)
    runner, strokes, priced = env.runner, [], []
    figures, add_costs_or_not = runner._figures, runner._add

    def keep(r, defer=False):
        strokes.append(figures(r, defer))
        return strokes[-1]

    def add(res, f, w, lifted_m3, displaced_m3, costs=True):  # the first stroke after a change prices no costs
        priced.append(costs)
        return add_costs_or_not(res, f, w, lifted_m3, displaced_m3, costs)

    runner._figures, runner._add = keep, add
    runner.run = functools.partial(IntervalRunner.run, runner, fast_forward=False)
    terms = {k: 0.0 for k in reward_terms(version)}
    out = []
    for a in actions(policy, steps, seed):
        strokes.clear()
        priced.clear()
        _, _, term, trunc, info = env.step(a)
        res = env.unwrapped._result
        n = math.floor(res.strokes + 1e-9)
        out.append({name: np.array([get(f) for f, c in zip(strokes[:n], priced[:n]) if c or name in UNPRICED],
                                   float) for name, (_, get) in FIGURES.items()})
        for k in terms:
            terms[k] += info[k]
        if term or trunc:
            break
    return out, terms


def k_se(x: np.ndarray, bound: float) -> float:
    """K strokes drawn at random (without replacement) from the interval's n for the mean's 95 % half-width to be
    within ``bound`` of the mean; n when even all of them are needed."""
    n, mean = len(x), abs(float(np.mean(x)))
    if n < 2 or mean == 0.0:
        return float(n)
    k0 = (Z95 * float(np.std(x, ddof=1)) / (bound * mean)) ** 2
    return float(min(n, math.ceil(n * k0 / (n + k0 - 1.0)))) if k0 > 0 else 1.0


def k_direct(x: np.ndarray, bound: float, peak: bool = False) -> int:
    """The smallest K for which the first K strokes' mean (``peak``: largest value) and every larger K' stay within
    ``bound`` of the interval's."""
    ref = float(np.max(x)) if peak else float(np.mean(x))
    run = np.maximum.accumulate(x) if peak else np.cumsum(x) / np.arange(1, len(x) + 1)
    bad = np.nonzero(np.abs(run - ref) > bound * max(abs(ref), 1e-300))[0]
    return int(bad[-1] + 2) if len(bad) else 1


def variability(intervals: list[dict], terms: dict, bound: float = 0.005) -> dict:
    """Per figure: the median and largest CV and K over the episode's intervals (None for a negligible term);
    ``strokes`` the median number of full strokes an interval holds."""
    scale = 1e-3 * sum(abs(v) for v in terms.values())
    out = {"strokes": float(np.median([len(iv["energy"]) for iv in intervals]))}
    for name, (term, _) in FIGURES.items():
        xs = [iv[name] for iv in intervals if len(iv[name]) >= 2 and np.any(iv[name] != 0)]
        if abs(terms.get(term, 0.0)) < scale and name != "peak_load" or not xs:
            out[name] = None
            continue
        cv = [float(np.std(x, ddof=1) / abs(np.mean(x))) for x in xs]
        cv_d = [detrended_cv(x) for x in xs]
        kse = [k_se(x, bound) for x in xs]
        kd = [k_direct(x, bound, peak=name == "peak_load") for x in xs]
        out[name] = {"cv_median": float(np.median(cv)), "cv_max": max(cv), "cv_detrended_median":
                     float(np.median(cv_d)), "cv_detrended_max": max(cv_d), "k_se_median": float(np.median(kse)),
                     "k_se_max": max(kse), "k_direct_median": float(np.median(kd)), "k_direct_max": max(kd),
                     "episode_error_first_k": {k: episode_error(xs, k, name == "peak_load") for k in KS}}
    return out


def detrended_cv(x: np.ndarray) -> float:
    """The CV left about a straight line through the interval's strokes (the drift with the annulus level
    removed): the stroke-to-stroke scatter a runner following the drift would still have to average."""
    i = np.arange(len(x), dtype=float)
    resid = x - np.polyval(np.polyfit(i, x, 1), i) if len(x) >= 3 else x - np.mean(x)
    return float(np.std(resid, ddof=min(2, len(x) - 1)) / abs(np.mean(x)))


def episode_error(xs: list[np.ndarray], k: int, peak: bool = False) -> float:
    """The episode total's relative error when each interval's strokes are its first k strokes' mean repeated
    (``peak``: the episode's largest value from the first k strokes of each interval)."""
    if peak:
        ref, got = max(float(np.max(x)) for x in xs), max(float(np.max(x[:k])) for x in xs)
    else:
        ref, got = sum(float(np.sum(x)) for x in xs), sum(len(x) * float(np.mean(x[:k])) for x in xs)
    return abs(got - ref) / max(abs(ref), 1e-300)
