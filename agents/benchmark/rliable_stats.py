"""The v2 benchmark's statistics as RL readers expect them: ``rliable`` (Agarwal et al., 2021).

Scores. Each test episode (a well and its schedule) is a *task*; a policy's *runs* are its training seeds'
models (an agent) or its one tuned parameter set (a baseline). The normalised score of an episode is
``(R - R_installed) / (R_ref - R_installed)`` on that episode, with ``R_ref`` the **causal oracle**'s return
(the true model without the future: :mod:`agents.policies.causal_oracle`; the clairvoyant oracle when the report has no
causal one, and then the section says so). A denominator below ``floor`` x its median over the episodes is
raised to that (an episode on which the installed point is already near the top cannot blow a score up).

Figures, each from :mod:`rliable.library` / :mod:`rliable.metrics`:

- ``iqm``: the interquartile mean of the normalised scores with a 95 % stratified-bootstrap interval
  (``task_bootstrap=True``: episodes resampled too, since they are a sample of the family's wells);
- ``probability_of_improvement``: P(agent > baseline) on a random episode, with its interval, for every agent
  against every baseline;
- ``performance_profile``: the fraction of (run, episode) scores above each tau in ``taus``, with its band.
"""

from __future__ import annotations

from typing import Any

import numpy as np

TAUS = tuple(np.round(np.linspace(-0.5, 1.5, 21), 3))


class _seeded_bootstrap:
    """rliable 1.2 hands ``random_state=`` to arch's bootstrap, which arch >= 8 (the first to import with
    pandas 3) refuses (it is ``seed=`` there): within this context rliable's class passes it on as ``seed``.
    rliable draws its resampling indices from NumPy's global generator, so the context also seeds that (and
    restores it after): every figure is reproducible from ``seed``."""

    def __init__(self, seed: int) -> None:
        self.seed = seed

    def __enter__(self) -> None:
        from arch.bootstrap import IIDBootstrap
        from rliable import library as rly

        self.orig, self.state = rly.StratifiedBootstrap, np.random.get_state()
        np.random.seed(self.seed)

        class Seeded(rly.StratifiedBootstrap):
            def __init__(self, *args: np.ndarray, random_state: Any = None, task_bootstrap: bool = False,
                         **kwargs: np.ndarray) -> None:
                IIDBootstrap.__init__(self, *args, seed=random_state, **kwargs)
                self._args_shape = args[0].shape
                self._num_tasks = self._args_shape[1]
                self._parameters = [self._num_tasks, task_bootstrap]
                self._task_bootstrap = task_bootstrap
                self._strata_indices = self._get_strata_indices()

        rly.StratifiedBootstrap = Seeded

    def __exit__(self, *exc: object) -> None:
        from rliable import library as rly

        rly.StratifiedBootstrap = self.orig
        np.random.set_state(self.state)


def _returns(report: dict[str, Any], name: str, keys: list[tuple[str, int]]) -> np.ndarray:
    """(runs, episodes) returns of a policy: per training seed for an agent averaged over seeds, else one row."""
    runs = (report.get("training") or {}).get("runs", {}).get(name, {}).get("per_seed")
    rows = [s["episodes"] for s in runs] if runs else [report["policies"][name]["episodes"]]
    out = []
    for eps in rows:
        by = {(str(e["well_id"]), int(e["seed"])): float(e["reward"]) for e in eps}
        out.append([by[k] for k in keys])
    return np.asarray(out, np.float64)


def normalised_scores(report: dict[str, Any], floor: float = 0.1) -> tuple[dict[str, np.ndarray], str]:
    """Per policy, the (runs, episodes) matrix of normalised scores, and the reference's name."""
    pol = report["policies"]
    ref = "causal_oracle" if "causal_oracle" in pol else "oracle" if "oracle" in pol else None
    if ref is None or "installed" not in pol:
        raise ValueError("rliable: the report needs an installed and a (causal) oracle policy to normalise")
    keys = [(str(e["well_id"]), int(e["seed"])) for e in pol["installed"]["episodes"]]
    lo = _returns(report, "installed", keys)[0]
    span = _returns(report, ref, keys)[0] - lo
    med = float(np.median(np.abs(span)))
    span = np.where(np.abs(span) < floor * med, floor * med, span)
    return {n: (_returns(report, n, keys) - lo) / span for n in pol}, ref


def rliable_section(report: dict[str, Any], reps: int = 2000, seed: int = 0) -> dict[str, Any]:
    """The report's ``rliable`` block (schema in the module docstring)."""
    from rliable import library as rly
    from rliable import metrics

    scores, ref = normalised_scores(report)
    kinds = {n: p["kind"] for n, p in report["policies"].items()}
    with _seeded_bootstrap(seed):
        return _section(scores, ref, kinds, reps, seed, rly, metrics)


def _section(scores: dict[str, np.ndarray], ref: str, kinds: dict[str, str], reps: int, seed: int, rly: Any,
             metrics: Any) -> dict[str, Any]:
    point, ci = rly.get_interval_estimates(scores, lambda x: np.array([metrics.aggregate_iqm(x)]), reps=reps,
                                           task_bootstrap=True)
    agents = [n for n in scores if kinds[n] == "agent"]
    bases = [n for n in scores if kinds[n] != "agent" and n not in (ref, "oracle")]
    poi: dict[str, dict[str, Any]] = {}
    rng = np.random.default_rng(seed)
    for a in agents:
        for b in bases:
            poi.setdefault(a, {})[b] = _poi(scores[a], scores[b], reps, rng, metrics)
    taus = np.asarray(TAUS)
    prof, prof_ci = rly.create_performance_profile(scores, taus, reps=reps)
    return {
        "reference": ref,
        "score": f"(R - R_installed) / (R_{ref} - R_installed) per test episode",
        "reps": reps, "seed": seed,
        "iqm": {n: {"iqm": float(np.ravel(point[n])[0]), "ci95": [float(v) for v in np.ravel(ci[n])],
                    "runs": int(scores[n].shape[0]), "episodes": int(scores[n].shape[1])} for n in scores},
        "probability_of_improvement": poi,
        "performance_profile": {"taus": [float(t) for t in taus],
                                "fraction_above": {n: [float(v) for v in prof[n]] for n in scores},
                                "band95": {n: np.asarray(prof_ci[n]).tolist() for n in scores}},
    }


def _poi_stat(x: np.ndarray, y: np.ndarray) -> float:
    """rliable's probability of improvement, vectorised: per episode P(X > Y) + P(X = Y) / 2 over the pairs of
    runs (the Mann-Whitney U over n x m), averaged over episodes."""
    gt = (x[:, None, :] > y[None, :, :]).mean(axis=(0, 1))
    eq = (x[:, None, :] == y[None, :, :]).mean(axis=(0, 1))
    return float((gt + 0.5 * eq).mean())


def _poi(x: np.ndarray, y: np.ndarray, reps: int, rng: np.random.Generator, metrics: Any) -> dict[str, Any]:
    """Probability of improvement P(x > y) (rliable's point estimate) with a stratified bootstrap over episodes
    and, within each, runs (rliable's own interval class cannot be seeded with arch >= 8)."""
    p = float(metrics.probability_of_improvement(x, y))
    n_ep = x.shape[1]
    draws = np.empty(reps)
    for k in range(reps):
        ep = rng.integers(n_ep, size=n_ep)
        xr = x[rng.integers(x.shape[0], size=x.shape[0])][:, ep]
        yr = y[rng.integers(y.shape[0], size=y.shape[0])][:, ep]
        draws[k] = _poi_stat(xr, yr)
    return {"p": p, "ci95": [float(v) for v in np.percentile(draws, [2.5, 97.5])]}


def markdown(section: dict[str, Any]) -> str:
    """The block as markdown tables."""
    head = (f"Normalised score: {section['score']} (rliable; 95 % stratified-bootstrap intervals, "
            f"{section['reps']} resamples, episodes resampled too).")
    lines = [head, "",
             "| policy | IQM normalised score (95 % CI) | runs x episodes |", "|---|---|---|"]
    iq = section["iqm"]
    for n in sorted(iq, key=lambda n: -iq[n]["iqm"]):
        r = iq[n]
        lines.append(f"| {n} | {r['iqm']:.3f} [{r['ci95'][0]:.3f}, {r['ci95'][1]:.3f}] | {r['runs']} x {r['episodes']} |")
    poi = section["probability_of_improvement"]
    if poi:
        bases = list(next(iter(poi.values())))
        lines += ["", "Probability of improvement P(agent > baseline) on a random test episode (95 % CI):", "",
                  "| agent | " + " | ".join(bases) + " |", "|---" * (1 + len(bases)) + "|"]
        for a, row in poi.items():
            lines.append(f"| {a} | " + " | ".join(
                f"{row[b]['p']:.2f} [{row[b]['ci95'][0]:.2f}, {row[b]['ci95'][1]:.2f}]" for b in bases) + " |")
    return "\n".join(lines)
