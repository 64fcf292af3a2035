"""The benchmark's figure: mean return with its 95 % CI per policy, and on one test episode the best agent
beside the best tuned baseline (average SPM, duty, fillage estimate over time, the spans of the well's true
condition where v2 names one; three surface cards)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .report import _fmt

# one colour per condition, the same in every panel (matplotlib's tab10 without the lines' blue/orange/green)
_CONDITION_COLOURS = ("tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray")


def _condition_spans(ax: Any, hours: np.ndarray, conditions: list[str], dt_h: float) -> None:
    """Shade each run of intervals whose true condition is not a full pump (what the agent met), labelled once."""
    names = sorted({c for c in conditions if c not in ("", "full")})
    colour = {c: _CONDITION_COLOURS[k % len(_CONDITION_COLOURS)] for k, c in enumerate(names)}
    start = 0
    for i in range(1, len(conditions) + 1):
        if i == len(conditions) or conditions[i] != conditions[start]:
            c = conditions[start]
            if c in colour:
                ax.axvspan(hours[start] - dt_h, hours[i - 1], color=colour[c], alpha=0.12,
                           label=c.replace("_", " ") if c in names else None)
                names = [n for n in names if n != c]  # label each condition once
            start = i


def surface_card(ax: Any, card: Any, stroke_length_m: float, **plot: Any) -> None:
    """One surface card of the observation (its first 64 values: 32 loads up, 32 down, / PPRL rating) over the
    polished-rod position, the stroke length ``stroke_length_m`` long."""
    c = np.asarray(card, dtype=float)
    x = np.linspace(0, 1, len(c) // 2) * stroke_length_m
    ax.plot(np.r_[x, x[::-1]], np.r_[c[: len(c) // 2], c[len(c) // 2:][::-1]], **{"lw": 1, **plot})


def figure(report: dict[str, Any], traces: dict[str, dict[str, Any]], path: Path) -> None:
    """Top: mean return with its 95 % CI per policy. Below: on one test episode, the best agent beside
    the best tuned baseline - average SPM and duty over time, fluid level, and three surface cards."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    s = report["summary"]
    names = sorted(s, key=lambda n: s[n]["mean_reward"])
    shown = list(traces)
    fig = Figure(figsize=(12, 4 + 3.2 * 2), dpi=100)
    gs = fig.add_gridspec(3, max(2, len(shown)), height_ratios=[1.1, 1, 1])
    ax = fig.add_subplot(gs[0, :])
    y = np.arange(len(names))
    means = np.array([s[n]["mean_reward"] for n in names])
    lo = np.array([s[n]["ci95_reward"][0] for n in names])
    hi = np.array([s[n]["ci95_reward"][1] for n in names])
    colors = ["tab:orange" if s[n]["kind"] == "agent" else "tab:gray" for n in names]
    ax.barh(y, means, xerr=np.nan_to_num(np.vstack([means - lo, hi - means])), color=colors, capsize=3)
    ax.set_yticks(y, [f"{n}  (score {_fmt(s[n]['normalised_score'], 2)})" for n in names])
    ax.set_xlabel("mean episode return on the test episodes (sum of interval rates, USD/h), 95 % CI")
    ax.grid(alpha=0.3, axis="x")
    for col, (label, tr) in enumerate(traces.items()):
        t = tr["trace"]
        hours = np.arange(1, len(t["avg_spm"]) + 1) * tr["interval_s"] / 3600
        a1 = fig.add_subplot(gs[1, col])
        a1.step(hours, t["avg_spm"], where="pre", color="tab:blue", label="average SPM")
        _condition_spans(a1, hours, t.get("condition", []), tr["interval_s"] / 3600)
        # two lines: a long policy name must not run into the neighbouring panel's title
        a1.set(title=f"{label}\non {tr['well_id']} (seed {tr['seed']}): return {tr['reward']:.0f}",
               xlabel="time (h)", ylabel="average SPM")
        tw = a1.twinx()
        tw.step(hours, t["duty"], where="pre", color="tab:orange", label="duty (-)", alpha=0.8)
        tw.plot(hours, np.asarray(t["fillage_est"]), color="tab:green", lw=0.8, label="fillage_est (-)")
        tw.set(ylim=(-0.05, 1.1), ylabel="duty, fillage estimate (-)")
        h1, l1 = a1.get_legend_handles_labels()
        h2, l2 = tw.get_legend_handles_labels()
        a1.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower left")
        a1.grid(alpha=0.3)
        a2 = fig.add_subplot(gs[2, col])
        cards = np.asarray(t["card"])
        duty = np.asarray(t["duty"])
        pumped = np.flatnonzero(duty > 0)
        picks = sorted({int(pumped[0]), int(pumped[len(pumped) // 2]), int(pumped[-1])}) if len(pumped) else []
        for i in picks:
            surface_card(a2, cards[i], t["stroke_length_m"][i], label=f"t = {hours[i]:.1f} h")
        a2.set(xlabel="polished-rod position (m)", ylabel="load / PPRL rating (-)", title="surface cards")
        a2.legend(fontsize=7)
        a2.grid(alpha=0.3)
    fig.tight_layout()
    from srenv.outputs import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda tmp: fig.savefig(tmp, format="png"))
