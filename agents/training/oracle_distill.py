"""The causal oracle as a DAgger teacher: model-predictive control on the true well distilled into a field student.

The causal oracle (:class:`agents.policies.causal_oracle.CausalOraclePolicy`) plans on a frozen deep copy of
the env it drives - the true well, its state now, no future - so it needs no training, only CPU (~14 s per
144-interval v2 episode at horizon 6, replan_every 3). It is not deployable (no field controller has the
true model); this module teaches its decisions to a *student* that sees the field observation only:

1. roll out training-split episodes; on every interval the oracle, driven alongside on the **student's**
   env (it deep-copies the true state it is in, and its tuned baselines run on the same observations),
   decides its action ``a_o`` - it replans every ``replan_every`` intervals from the state the student has
   reached and plays its decision between - and the label is the residual correction
   ``clip((a_o - b) / scale, -1, 1)`` on the run's base action ``b`` (:func:`label_of`);
2. in iteration 0 each interval's acting correction is the oracle's with probability ``beta0`` (default
   1/2), else the student's; from iteration 1 on the student acts alone (DAgger, Ross et al. 2011);
3. after each iteration the student's actor is fitted to every label so far (the same MSE fit as the PPO
   teachers', :func:`agents.training.distill.fit_actor`).

With no trained model to start from, the student is a fresh SB3 PPO actor (seeded; the run's training
YAML gives its network) whose correction is 0 - the base controller itself - until its first fit, and whose
observation statistics are those of iteration 0's inputs. With ``teacher.init: {path, obs_norm}`` (``{seed}`` in
either = the run seed) the DAgger continues that student instead (warm start, :func:`init_files`): it acts from
iteration 0 on (with ``beta0`` 0), its observation statistics are kept as they are, and its fits are on the
labels of this run only. Episodes run in the benchmark's worker
processes (one job per episode); every random draw is seeded by (run seed, episode seed), so the same job
gives the same student whatever the number of workers.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..evaluation.normalizer import obs_norm_path
from ..policies.history import History, check_history
from ..policies.residual import _Base, augment, compose
from .tuning import refuse_test_split

ORACLE_KIND = "causal_oracle"
ORACLE_TEACHER_KEYS = {"kind", "params", "iterations", "episodes", "seed_start", "beta0", "init", "pool"}
INIT_FILES = (("path", ".zip"), ("obs_norm", ".npz"))  # teacher.init: the student to continue, its statistics
MAX_PATH = 4096
ORACLE_PARAM_KEYS = {"horizon", "replan_every", "steps"}
ORACLE_POLICIES = ("pump_off", "fillage_pi")  # the tuned baselines the oracle also weighs (the lead's pilot)
CLIP_OBS = 10.0    # the student's observation clip, as SB3's VecNormalize
EPSILON = 1e-8


def label_of(a_oracle: np.ndarray, base: np.ndarray, scale: float, idle_scale: float | None = None) -> np.ndarray:
    """The residual correction that moves ``base`` to ``a_oracle`` (inverse of
    :func:`agents.policies.residual.compose`), clipped to [-1, 1]: exact when the oracle is within reach."""
    b = np.asarray(base, np.float32)
    s = np.full(b.shape, float(scale), np.float32)
    if idle_scale is not None:
        s[..., 0] = np.where(b[..., 0] <= -1.0, np.float32(idle_scale), s[..., 0])
    return np.clip((np.asarray(a_oracle, np.float32) - b) / s, -1.0, 1.0).astype(np.float32)


def _student(job: dict[str, Any]) -> Any:
    """The acting student: one model ``{path, obs_norm}``, an ensemble ``{members: [...]}`` (the mean of its
    members' corrections, as :mod:`agents.policies.ensemble`), or None (a fresh student: the base)."""
    if not job.get("student"):
        return None
    from ..evaluation.agent import AgentPolicy
    from ..policies.ensemble import EnsemblePolicy

    spec = job["student"]
    if "members" in spec:
        return EnsemblePolicy([AgentPolicy(m["path"], m.get("obs_norm")) for m in spec["members"]])
    return AgentPolicy(spec["path"], spec.get("obs_norm"))


def oracle_episode_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry: one labelled episode ``{env_id, env_kwargs, oracle, residual, student, seed, run_seed,
    beta[, history]}`` -> the student's raw inputs (the last ``history`` field observations stacked, and the
    base action), the oracle's actions, the base's, the labels and the return."""
    import torch

    from ..evaluation.rollout import _cached_env
    from ..policies.causal_oracle import CausalOraclePolicy

    torch.set_num_threads(1)
    t0 = time.process_time()
    refuse_test_split(job["env_kwargs"].get("scenario", "train"), "train")
    env = _cached_env(job["env_id"], job["env_kwargs"])
    res, student = job["residual"], _student(job)
    rng = np.random.default_rng([int(job["run_seed"]), int(job["seed"])])
    oracle = CausalOraclePolicy(**job["oracle"])
    obs, _ = env.reset(seed=int(job["seed"]))
    base = _Base(res["base"], res["params"], env)
    base.reset(env)
    oracle.reset(env)
    hist = History(job.get("history", 1))  # the same stack the evaluation's residual policy builds
    rows: dict[str, list[np.ndarray]] = {"x": [], "a_oracle": [], "a_base": [], "label": []}
    done, total = False, 0.0
    while not done:
        b = base.act(obs)
        a_o = np.asarray(oracle.predict(obs)[0], np.float32).reshape(2)  # plans on a deep copy of this true state
        label = label_of(a_o, b, res["scale"], res.get("idle_scale"))
        x = augment(hist.push(obs), b)
        own = np.zeros(2, np.float32)  # a fresh student is the base until its first fit
        if student is not None:
            own = np.asarray(student.predict(x, deterministic=True)[0], np.float32).reshape(2)
        for k, v in zip(rows, (x, a_o, b, label)):
            rows[k].append(v)
        r = label if rng.random() < job["beta"] else own
        obs, reward, terminated, truncated, _ = env.step(compose(b, r, res["scale"], res.get("idle_scale")))
        total += float(reward)
        done = terminated or truncated
    out = {k: np.asarray(v, np.float32) for k, v in rows.items()}
    out.update(seed=int(job["seed"]), reward=total, steps=len(rows["x"]), model_steps=int(oracle.sim_steps),
               cpu_s=time.process_time() - t0)
    return out


def fresh_student(obs_dim: int, policy_kwargs: dict[str, Any], seed: int, path: Path) -> None:
    """A seeded, untrained SB3 PPO on the residual observation (field + base action) saved to ``path``."""
    import gymnasium as gym
    from stable_baselines3 import PPO

    from .sb3.builders import build_policy_kwargs

    class _Spaces(gym.Env):  # the spaces only: the student is fitted, never trained by PPO
        observation_space = gym.spaces.Box(-np.inf, np.inf, (obs_dim,), np.float32)
        action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)

        def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
            return np.zeros(obs_dim, np.float32), {}

        def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
            return np.zeros(obs_dim, np.float32), 0.0, True, False, {}

    model = PPO("MlpPolicy", _Spaces(), policy_kwargs=build_policy_kwargs(policy_kwargs), seed=int(seed),
                device="cpu", verbose=0)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(str(path))


def save_obs_norm(x: np.ndarray, path: Path) -> None:
    """The student's observation statistics: mean and variance of iteration 0's inputs."""
    from ..evaluation.normalizer import ObsNormalizer

    x64 = np.asarray(x, np.float64)
    ObsNormalizer.from_variance(x64.mean(0), x64.var(0), CLIP_OBS, EPSILON).save(path)


def init_files(init: Any, seed: int) -> tuple[Path, Path]:
    """The student a warm-started run continues (``teacher.init: {path, obs_norm}``, ``{seed}`` = the run seed):
    its zip and its observation statistics, each an existing regular file (read later as data); a ValueError
    naming the field, its value and what is expected otherwise."""
    if not (isinstance(init, dict) and set(init) == {k for k, _ in INIT_FILES}
            and all(isinstance(v, str) and 0 < len(v) <= MAX_PATH for v in init.values())):
        raise ValueError(f"teacher.init = {str(init)[:120]!r}: expected {{path: STUDENT.zip, obs_norm: STATS.npz}} "
                         "(paths, {seed} = the run seed)")
    out = []
    for key, ext in INIT_FILES:
        try:
            p = Path(init[key].format(seed=int(seed)))
        except (KeyError, IndexError, ValueError):
            raise ValueError(f"teacher.init.{key} = {init[key][:120]!r}: expected a path whose only placeholder "
                             "is {seed}") from None
        if p.suffix != ext or p.is_symlink() or not p.is_file():
            raise ValueError(f"teacher.init.{key} = {str(p)[:120]!r}: expected an existing {ext} file (not a "
                             "symlink)")
        out.append(p)
    return out[0], out[1]


def _warm_student(teacher: dict[str, Any], seed: int, norm: Path) -> tuple[Any, Path | None]:
    """(the student to continue, its zip) from ``teacher.init`` - its statistics written to ``norm`` unchanged -
    or (None, None) for a fresh student."""
    from ..evaluation.agent import AgentPolicy

    if teacher.get("init") is None:
        return None, None
    src, src_norm = init_files(teacher["init"], seed)
    student = AgentPolicy(str(src), str(src_norm))
    if norm.resolve() != src_norm.resolve():
        norm.parent.mkdir(parents=True, exist_ok=True)
        student.norm.save(norm)  # the statistics as they are, beside the run's student
    return student, src


def oracle_jobs(env_id: str, env_kwargs: dict[str, Any], oracle: dict[str, Any], residual: dict[str, Any],
                student: dict[str, Any] | None, seeds: Sequence[int], beta: float, run_seed: int,
                history: int = 1) -> list[dict]:
    return [{"env_id": env_id, "env_kwargs": env_kwargs, "oracle": oracle, "residual": residual,
             "student": student, "seed": int(s), "beta": float(beta), "run_seed": int(run_seed),
             "history": int(history)} for s in seeds]


def distill_oracle(runner: Any, teacher: dict[str, Any], oracle: dict[str, Any], residual: dict[str, Any],
                   env_id: str, env_kwargs: dict[str, Any], policy_kwargs: dict[str, Any], seeds: Sequence[int],
                   seed: int, dest_zip: Path, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """DAgger from the causal oracle into a fresh field student, or the one ``teacher.init`` names (warm start)
    (``teacher``: the run's checked teacher block;
    ``oracle``: the CausalOraclePolicy kwargs with the tuned baselines; its ``history`` K, default 1, is how many
    field observations the student sees, stacked); the student's policy spec."""
    from ..evaluation.agent import AgentPolicy
    from .distill import fit_actor, write_student

    refuse_test_split(env_kwargs.get("scenario", "train"), "train")
    if teacher.get("pool") is not None:
        raise ValueError("teacher.pool: a pooled student is fitted by scripts/oracle_distill_pooled.py, not by the "
                         "benchmark's per-seed DAgger")
    k_hist = check_history(teacher.get("history", 1))
    hist_key = {"history": k_hist} if k_hist != 1 else {}  # K = 1: today's spec, key for key
    t0 = time.perf_counter()
    init = dest_zip.with_name(dest_zip.stem + "_init.zip")
    norm = obs_norm_path(dest_zip)
    n_it = int(teacher["iterations"])
    per = len(seeds) // n_it
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    acts: list[np.ndarray] = []  # the oracle's and the base's actions: a student of another scale can be refitted
    history: list[dict[str, Any]] = []
    student, template = _warm_student(teacher, seed, norm)
    spec = None if student is None else {"path": str(template), "obs_norm": str(norm), **hist_key}
    for it in range(n_it):
        jobs = oracle_jobs(env_id, env_kwargs, oracle, residual, spec, seeds[it * per:(it + 1) * per],
                           float(teacher.get("beta0", 0.5)) if it == 0 else 0.0, seed, k_hist)
        eps = runner.map(jobs, fn=oracle_episode_job)
        xs += [e["x"] for e in eps]
        ys += [e["label"] for e in eps]
        acts += [np.concatenate([e["a_oracle"], e["a_base"]], 1) for e in eps]
        if student is None:  # the fresh actor and its statistics from iteration 0's inputs
            fresh_student(xs[0].shape[1], policy_kwargs, seed, init)
            save_obs_norm(np.concatenate(xs), norm)
            student, template = AgentPolicy(str(init), str(norm)), init
        x = np.concatenate(xs)
        loss = fit_actor(student.model, student.norm(x), np.concatenate(ys), seed + it)
        write_student(template, student.model, dest_zip)
        spec = {"path": str(dest_zip), "obs_norm": str(norm), **hist_key}
        a_o, a_b = np.concatenate([e["a_oracle"] for e in eps]), np.concatenate([e["a_base"] for e in eps])
        history.append({"iteration": it, "episodes": len(eps), "labels": len(x), "mse": loss,
                        "rollout_mean_return": float(np.mean([e["reward"] for e in eps])),
                        "rollout_cpu_s": float(sum(e["cpu_s"] for e in eps)),
                        "model_steps": int(sum(e["model_steps"] for e in eps)),
                        # how often the oracle is out of the residual's reach (the label is clipped)
                        "clipped_share": float(np.mean(np.any(np.abs(a_o - a_b) > residual["scale"] + 1e-6, 1)))})
        if log:
            log(f"oracle distill seed {seed}: iteration {it}: {history[-1]}")
    init.unlink(missing_ok=True)
    a = np.concatenate(acts)
    np.savez(dest_zip.with_name(dest_zip.stem + "_labels.npz"), x=np.concatenate(xs), label=np.concatenate(ys),
             a_oracle=a[:, :2], a_base=a[:, 2:])
    return {"kind": "agent", "path": str(dest_zip), "obs_norm": str(norm), **hist_key, "distill": history,
            "wall_time_s": time.perf_counter() - t0}
