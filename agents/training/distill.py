"""Teacher-student distillation: a residual PPO that sees the hidden well teaches one that sees the field.

A *teacher* is a residual PPO run trained on the ``privileged`` observation (the field observation plus the
true annulus level, intake pressure, true fillage, current inflow and the hidden well parameters; it is not
deployable: no controller measures these). A *student* acts on the field observation only, with the same
base controller and scale. Distillation is DAgger (Ross, Gordon & Bagnell 2011):

1. roll out on training-split episodes; on every interval both see the same state (the student its field
   part, which is the first ``len(FIELD_OBS_NAMES)`` entries of the privileged observation), and the label
   is the teacher's correction: the mean of the teacher models' deterministic outputs, clipped to [-1, 1];
2. in iteration 0 each interval's acting correction is the teacher's with probability 1/2, else the
   student's; from iteration 1 on the student acts alone, so the labels cover the states the student
   itself reaches;
3. after each iteration the student's actor (its policy MLP and action head) is fitted to every label so
   far by mean squared error on its Gaussian mean (Adam), from the student's current weights.

The student starts from a trained field residual model (``students_from``, the same seed) and keeps that
model's observation statistics, so iteration 0 rolls out a sensible controller. Its zip is the starting
zip with only ``policy.pth`` (the network weights) replaced, so every loader that reads the starting model
reads the student (:func:`agents.evaluation.model_io.load_policy`). Every random draw is seeded: the same job gives the
same student.
"""

from __future__ import annotations

import io
import os
import shutil
import zipfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..evaluation.normalizer import obs_norm_path
from ..policies.residual import _Base, augment, compose
from .tuning import refuse_test_split

BETA0 = 0.5        # the teacher's share of the acting corrections in iteration 0
BATCH = 256
EPOCHS = 30        # passes over the aggregated labels after each iteration
LR = 1e-3
DISTILL_KEYS = {"students_from", "iterations", "episodes", "seed_start", "idle_scale"}
SEED_STRIDE = 1000  # student k rolls out seeds seed_start + SEED_STRIDE * k + 0, 1, ...


def rollout_labels(env: Any, teacher: Any, student: Any, residual: dict[str, Any], seeds: Sequence[int],
                   beta: float, rng: np.random.Generator, n_field: int) -> tuple[np.ndarray, np.ndarray, float]:
    """One DAgger iteration: (student inputs, teacher labels, mean episode return) over ``seeds``."""
    xs, ys, returns = [], [], []
    for seed in seeds:
        obs, _ = env.reset(seed=int(seed))
        base = _Base(residual["base"], residual["params"], env)
        base.reset(env)
        done, total = False, 0.0
        while not done:
            b = base.act(obs)
            label = np.clip(np.asarray(teacher.predict(augment(obs, b))[0], np.float32).reshape(2), -1.0, 1.0)
            x = augment(obs[:n_field], b)
            x = student.norm(x) if student.norm is not None else x
            own = np.asarray(student.model.predict(x, deterministic=True)[0], np.float32).reshape(2)
            xs.append(x)
            ys.append(label)
            r = label if rng.random() < beta else own
            obs, reward, terminated, truncated, _ = env.step(compose(b, r, residual["scale"]))
            total += float(reward)
            done = terminated or truncated
        returns.append(total)
    return np.asarray(xs, np.float32), np.asarray(ys, np.float32), float(np.mean(returns))


def fit_actor(policy: Any, x: np.ndarray, y: np.ndarray, seed: int, epochs: int = EPOCHS, weight_decay: float = 0.0,
              on_epoch: Callable[[int], None] | None = None) -> float:
    """Fit ``policy``'s Gaussian mean to ``y`` (MSE, Adam with ``weight_decay``, 0 = plain Adam); the final epoch's
    mean loss. ``on_epoch(e)`` is called after epoch ``e`` (1-based): a fit of N epochs seen at its epoch e is the
    fit of e epochs (the same seeded draws), so one fit scores several epoch counts."""
    import torch

    torch.manual_seed(seed)
    xt, yt = torch.as_tensor(x), torch.as_tensor(y)
    params = list(policy.mlp_extractor.policy_net.parameters()) + list(policy.action_net.parameters())
    opt = torch.optim.Adam(params, lr=LR, weight_decay=float(weight_decay))
    n, loss_sum = len(xt), 0.0
    for epoch in range(1, epochs + 1):
        perm, loss_sum = torch.randperm(n), 0.0
        for i in range(0, n, BATCH):
            idx = perm[i:i + BATCH]
            loss = ((policy.get_distribution(xt[idx]).distribution.mean - yt[idx]) ** 2).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
            loss_sum += float(loss.detach()) * len(idx)
        if on_epoch is not None:
            on_epoch(epoch)
    return loss_sum / max(n, 1)


def write_student(init_zip: str | Path, policy: Any, dest_zip: Path) -> None:
    """``init_zip`` with its ``policy.pth`` replaced by ``policy``'s weights, written atomically."""
    import torch

    buf = io.BytesIO()
    torch.save(policy.state_dict(), buf)
    dest_zip.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest_zip.with_name(dest_zip.name + ".tmp")
    with zipfile.ZipFile(init_zip) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as out:
        for item in src.infolist():
            out.writestr(item, buf.getvalue() if item.filename == "policy.pth" else src.read(item.filename))
    os.replace(tmp, dest_zip)


def distill(teachers: Sequence[dict[str, Any]], student_init: dict[str, Any], residual: dict[str, Any],
            env_id: str, env_kwargs: dict[str, Any], seeds: Sequence[int], iterations: int, seed: int,
            dest_zip: Path, log: Any = None) -> dict[str, Any]:
    """DAgger from the teacher models' mean correction into a copy of ``student_init``; the student's spec."""
    import torch

    from ..envs import make_env
    from ..evaluation.agent import AgentPolicy, build_policy

    refuse_test_split(env_kwargs.get("scenario", "train"), "train")
    torch.set_num_threads(1)
    # the teachers' mean correction: the same ensemble policy the benchmark evaluates (agents/policies/ensemble.py)
    teacher = build_policy({"kind": "ensemble", "members": list(teachers)}, None)
    student = AgentPolicy(student_init["path"], student_init.get("obs_norm"))
    student.model.set_training_mode(True)
    env = make_env(env_id, **{**env_kwargs, "observation": "privileged"})
    # the student's inputs: the field observation (a prefix of the privileged one) and the base action
    n_field = student.observation_space.shape[0] - 2
    if env.observation_space.shape[0] <= n_field:
        env.close()
        raise ValueError(f"distill: the privileged observation has {env.observation_space.shape[0]} entries; "
                         f"expected more than the student's {n_field} field entries")
    rng = np.random.default_rng(seed)
    per_iter = max(1, len(seeds) // iterations)
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    history = []
    try:
        for it in range(iterations):
            chunk = seeds[it * per_iter:(it + 1) * per_iter]
            x, y, mean_return = rollout_labels(env, teacher, student, residual, chunk, BETA0 if it == 0 else 0.0,
                                               rng, n_field)
            xs.append(x)
            ys.append(y)
            loss = fit_actor(student.model, np.concatenate(xs), np.concatenate(ys), seed + it)
            history.append({"iteration": it, "episodes": len(chunk), "labels": int(sum(len(a) for a in xs)),
                            "rollout_mean_return": mean_return, "mse": loss})
            if log:
                log(f"distill seed {seed}: iteration {it}: {history[-1]}")
    finally:
        env.close()
    student.model.set_training_mode(False)
    write_student(student_init["path"], student.model, dest_zip)
    norm = None
    if student_init.get("obs_norm"):
        norm = obs_norm_path(dest_zip)
        shutil.copyfile(student_init["obs_norm"], norm)
    return {"kind": "agent", "path": str(dest_zip), "obs_norm": str(norm) if norm else None, "distill": history}


def distill_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry (:class:`agents.evaluation.rollout.Runner`): one student."""
    import sys
    import time

    t0 = time.perf_counter()
    spec = distill(job["teachers"], job["student_init"], job["residual"], job["env_id"], job["env_kwargs"],
                   job["seeds"], job["iterations"], job["seed"], Path(job["dest"]),
                   log=lambda m: print(m, file=sys.stderr, flush=True))
    spec["wall_time_s"] = time.perf_counter() - t0
    return spec
