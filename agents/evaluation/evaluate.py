"""Evaluate policies (the two baselines or saved SB3 models) on held-out seeds.

Every policy runs the same episodes: ``env.reset(seed=S + k)`` for k = 0..N-1, deterministic actions.
Per episode the metrics are read from the env's ``info`` (one entry per control interval):

=================================  ============================================================
``reward``                         sum of rewards over the episode
``production_m3_day``              time-weighted mean: volume pumped / pumping time, m3/day
``pprl_n`` / ``pprl_max_n``        mean / maximum peak polished-rod load, N
``goodman_max_pct``                maximum Goodman loading over the episode, %
``stick_slip_index``               mean per-stroke stick-slip index
``production_per_peak_load``       mean production / maximum PPRL, (m3/day) per kN
``fillage``, ``spm``,              means over the episode
``stroke_length_m``
``failures``                       1 if the episode ended in a rod or solver failure
=================================  ============================================================

and each is summarised over episodes as mean and standard deviation (``mean_<metric>``,
``std_<metric>``).
"""

from __future__ import annotations

import math
import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from srenv.errors import ConfigError

from ..envs import ENV_ID_V0, make_env
from ..policies.protocol import Policy
from ..policies.v0 import FillagePolicy, RockingMachinePolicy
from .agent import SB3Policy
from .model_io import (
    ModelFileError,
    algorithms,
    check_spaces,
    detect_algo,
    load_policy,
    read_data,
    read_stats,
    space_shape,
    stats_path,
    vecnormalize_path,
)
from .rollout import play

BASELINES = ("rocking", "fillage")
# info keys averaged per episode (all in the env's SI units)
_STEP_KEYS = ("production_m3_day", "pprl_n", "goodman_max_pct", "stick_slip_index", "fillage", "spm",
              "stroke_length_m")
# printed in the comparison table: (metric key, column header, format)
_TABLE = (("reward", "reward", "{:.2f}"), ("production_m3_day", "production (m3/day)", "{:.2f}"),
          ("pprl_max_n", "peak PPRL (kN)", "{:.2f}"), ("goodman_max_pct", "Goodman max (%)", "{:.1f}"),
          ("stick_slip_index", "stick-slip index", "{:.2f}"),
          ("production_per_peak_load", "m3/day per kN PPRL", "{:.3f}"),
          ("spm", "SPM", "{:.2f}"), ("stroke_length_m", "stroke (m)", "{:.2f}"))


# --------------------------------------------------------------------------------------------- loading
def load_model(path: str | Path, env: Any, trust: bool = False) -> SB3Policy:
    """Load an SB3 zip (PPO, SAC, A2C, TD3) and its VecNormalize statistics, checked against ``env``.

    By default as data only (:mod:`agents.evaluation.model_io`): nothing in the file is unpickled, so a model file
    cannot run code. ``trust=True`` (``--trust-model``) loads through SB3 and pickle instead - which runs
    whatever the file's pickles name: only for files you made yourself.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"--policy {path}: no such model file (or use rocking / fillage)")
    algo_cls = algorithms()[detect_algo(path)]
    if not trust:
        data = read_data(path)
        obs_shape = space_shape(data, "observation_space", path)
        act_shape = space_shape(data, "action_space", path)
        check_spaces(obs_shape, act_shape, env.observation_space.shape, env.action_space.shape, path)
        policy = load_policy(path, algo_cls, env.observation_space, env.action_space)
        normalizer = None
        json_stats = stats_path(path)
        if json_stats.is_file():
            normalizer = read_stats(json_stats, env.observation_space.shape)
        elif vecnormalize_path(path) is not None:
            raise ModelFileError(f"{vecnormalize_path(path)}: normalisation statistics only as a pickle, "
                                 "which can run arbitrary code when loaded; convert it to "
                                 f"{json_stats.name} (python -m agents convert-stats) or pass --trust-model "
                                 "if you made it yourself")
        return SB3Policy(policy, normalizer, str(path))
    model = algo_cls.load(str(path), device="cpu")
    check_spaces(model.observation_space, model.action_space, env.observation_space, env.action_space, path)
    normalizer = None
    stats = vecnormalize_path(path)
    if stats is not None:
        with open(stats, "rb") as fh:
            normalizer = pickle.load(fh)  # trusted only: a VecNormalize without its venv (needs obs_rms)
        if normalizer.norm_obs and normalizer.obs_rms.mean.shape != env.observation_space.shape:
            raise ValueError(f"{stats}: normalisation statistics of shape {normalizer.obs_rms.mean.shape} "
                             f"do not fit the env's observation space {env.observation_space}")
        if not normalizer.norm_obs:
            normalizer = None
    return SB3Policy(model, normalizer, str(path))


def well_config(env: Any) -> Any:
    """The WellConfig the env was built from, overrides included, before the per-episode randomisation
    (the installed unit's SPM and stroke, the control range)."""
    return env.unwrapped.base_cfg


def fillage_index(env: Any) -> int:
    """Index of the last stroke's pump fillage in the env's flat observation (its documented layout)."""
    from srenv.envs import obs_index

    return obs_index("fillage", env.unwrapped.card_points)


def make_policy(spec: str, env: Any, trust: bool = False) -> Policy:
    if spec == "rocking":
        return RockingMachinePolicy(well_config(env))
    if spec == "fillage":
        return FillagePolicy(well_config(env), fillage_index=fillage_index(env))
    from .rllib_model import is_rllib_checkpoint, load_rllib_policy

    if is_rllib_checkpoint(spec):  # a directory from backend: rllib (its checkpoint/ or step_<N>/)
        return load_rllib_policy(spec, env, trust=trust)
    return load_model(spec, env, trust=trust)


def policy_label(spec: str) -> str:
    if spec in BASELINES:
        return spec
    path = Path(spec)
    if path.name == "checkpoint" and path.parent.name:  # an RLlib run's final checkpoint directory
        return f"{path.parent.name}/checkpoint"
    stem = path.name.removesuffix(".zip")
    # train() names its outputs model / best_model: the run directory tells runs apart
    return f"{path.parent.name}/{stem}" if stem in ("model", "best_model") and path.parent.name else stem


# -------------------------------------------------------------------------------------------- episodes
@dataclass
class Episode:
    seed: int
    rewards: list[float] = field(default_factory=list)
    steps: dict[str, list[float]] = field(default_factory=lambda: {k: [] for k in _STEP_KEYS})
    cards: list[dict] = field(default_factory=list)
    failure: str | None = None

    def metrics(self) -> dict[str, float]:
        m = {k: float(np.mean(v)) if v else math.nan for k, v in self.steps.items()}
        if self.steps["production_m3_day"] and self.steps["spm"]:
            # a stroke lasts 60/SPM s: a per-stroke mean would overweight the fast strokes' rates
            m["production_m3_day"] = float(np.average(self.steps["production_m3_day"],
                                                      weights=1.0 / np.asarray(self.steps["spm"])))
        m["reward"] = float(np.sum(self.rewards))
        m["pprl_max_n"] = float(np.max(self.steps["pprl_n"])) if self.steps["pprl_n"] else math.nan
        m["goodman_max_pct"] = float(np.max(self.steps["goodman_max_pct"])) if self.steps["goodman_max_pct"] \
            else math.nan
        m["production_per_peak_load"] = m["production_m3_day"] / (m["pprl_max_n"] / 1e3)
        m["steps"] = float(len(self.rewards))
        m["failures"] = float(self.failure is not None)
        return m


def evaluate_episode(env: Any, policy: Policy, seed: int, record_cards: bool = False) -> Episode:
    """One deterministic episode (:func:`agents.evaluation.rollout.play`) as the per-step metrics of this module."""
    ep = Episode(seed)
    for obs, reward, terminated, _, info in play(env, policy, seed)[1]:
        ep.rewards.append(float(reward))
        for k in _STEP_KEYS:
            if k in info:
                ep.steps[k].append(float(info[k]))
        if record_cards:
            ep.cards.append(card_from_observation(env, obs, info["stroke_length_m"]))
        ep.failure = info.get("failure") if terminated else None
    return ep


def card_from_observation(env: Any, obs: np.ndarray, stroke_length_m: float) -> dict:
    """Surface card of the stroke just run, from the observation's documented layout: the up and down
    branches' load / ``reward.pprl_rating_n`` on a uniform grid of the stroke (``card_points`` each)."""
    n = env.unwrapped.card_points
    grid_m = np.linspace(0.0, 1.0, n) * stroke_length_m
    load_n = np.asarray(obs[: 2 * n], dtype=np.float64) * well_config(env).reward.pprl_rating_n
    # up branch bottom -> top, then the down branch top -> bottom: one closed loop
    return {"position_m": np.r_[grid_m, grid_m[::-1], grid_m[:1]],
            "load_n": np.r_[load_n[:n], load_n[n:][::-1], load_n[:1]]}


def summarize(episodes: list[Episode]) -> dict[str, float]:
    per = [e.metrics() for e in episodes]
    out: dict[str, float] = {}
    for k in per[0]:
        vals = np.array([p[k] for p in per])
        out[f"mean_{k}"] = float(np.mean(vals))
        out[f"std_{k}"] = float(np.std(vals))
    return out


def evaluate(specs: list[str], episodes: int, seed: int, config: str = "default",
             env_kwargs: dict | None = None, plot: str | Path | None = None,
             env_id: str = ENV_ID_V0, trust_model: bool = False) -> dict[str, Any]:
    """Evaluate each policy on seeds seed..seed+episodes-1; returns {label: summary} and writes the plot."""
    from srenv.outputs import atomic_write, check_output_path

    check_output_path("--plot", None if plot is None else str(plot), (".png",))  # before any work; no symlink
    if "config" in (env_kwargs or {}):
        raise ConfigError("--env-kwarg config", env_kwargs["config"], "the well given by --config instead")
    env = make_env(env_id, config=config, **(env_kwargs or {}))
    control = well_config(env).control
    results: dict[str, dict] = {}
    samples: dict[str, Episode] = {}
    try:
        for spec in specs:
            policy = make_policy(spec, env, trust=trust_model)
            eps = [evaluate_episode(env, policy, seed + k, record_cards=plot is not None and k == 0)
                   for k in range(episodes)]
            label = policy_label(spec)
            if label in results:  # e.g. two runs' best_model from directories of the same name
                label = f"{label} ({len(results) + 1})"
            results[label] = {"policy": spec, **summarize(eps)}
            samples[label] = eps[0]
    finally:
        env.close()
    if plot is not None:
        stroke_range = (control.stroke_min_m * 0.95, control.stroke_max_m * 1.05)
        fig = episode_figure(samples, stroke_range, title=f"config {config}, seed {seed}")
        atomic_write(plot, lambda tmp: fig.savefig(tmp, format="png"))
    return results


def markdown_table(results: dict[str, dict]) -> str:
    head = "| policy | " + " | ".join(h for _, h, _ in _TABLE) + " |"
    rule = "|---" * (len(_TABLE) + 1) + "|"
    rows = [head, rule]
    for label, r in results.items():
        cells = []
        for key, _, fmt in _TABLE:
            scale = 1e-3 if key.endswith("_n") else 1.0  # loads shown in kN
            cells.append(f"{fmt.format(r[f'mean_{key}'] * scale)} ± {fmt.format(r[f'std_{key}'] * scale)}")
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def episode_figure(samples: dict[str, Episode], stroke_range_m: tuple[float, float], title: str = "") -> Any:
    """One column per policy: surface cards of the sample episode (first, middle, last stroke), the
    commanded SPM and stroke length, and the production and fillage, per control interval."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    n = len(samples)
    fig = Figure(figsize=(4.2 * n, 9.0), dpi=100)
    axes = np.array(fig.subplots(3, n, squeeze=False, sharey="row"))
    for col, (label, ep) in enumerate(samples.items()):
        ax_card, ax_ctl, ax_prod = axes[:, col]
        picks = sorted({0, len(ep.cards) // 2, len(ep.cards) - 1}) if ep.cards else []
        for i in picks:
            c = ep.cards[i]
            ax_card.plot(c["position_m"] - np.min(c["position_m"]), c["load_n"] / 1e3, lw=1.0,
                         label=f"stroke {i + 1}")
        ax_card.set(title=f"{label}: reward {np.sum(ep.rewards):.1f}", xlabel="polished-rod position (m)",
                    ylabel="polished-rod load (kN)" if col == 0 else None)
        if picks:
            ax_card.legend(fontsize=8)
        steps = np.arange(1, len(ep.rewards) + 1)
        _twin_plot(ax_ctl, steps, ep.steps["spm"], "SPM", ep.steps["stroke_length_m"], "stroke length (m)",
                   label_y=col == 0, right_lim=stroke_range_m)
        _twin_plot(ax_prod, steps, ep.steps["production_m3_day"], "production (m3/day)", ep.steps["fillage"],
                   "pump fillage (-)", label_y=col == 0, right_lim=(0.0, 1.05))
        for ax in (ax_card, ax_ctl, ax_prod):
            ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def _twin_plot(ax: Any, x: np.ndarray, left: list[float], left_label: str, right: list[float],
               right_label: str, label_y: bool, right_lim: tuple[float, float]) -> None:
    """Two series of different units on one panel (left and right axes), legend naming both."""
    l1 = ax.plot(x, left, color="tab:blue", label=left_label)
    twin = ax.twinx()
    l2 = twin.plot(x, right, color="tab:orange", label=right_label)
    ax.set(xlabel="control interval (strokes)", ylabel=left_label if label_y else None)
    twin.set(ylabel=right_label, ylim=right_lim)  # fixed: a constant series must not fill the panel
    ax.legend(l1 + l2, [line.get_label() for line in l1 + l2], fontsize=8, loc="lower right")
