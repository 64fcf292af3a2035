"""The native vector env's process backend: N envs split into P worker processes, a contiguous block each.

Why processes: a step's Python (the env's bookkeeping, card features, the classifier) holds the GIL and is about
half of its CPU time, so threads cannot keep two cores busy (docs/speed.md §3); a worker process runs its block's
whole steps. Each worker builds its envs from the class and kwargs (nothing but those two and the commands cross
the pipe; observations come back pickled), and steps them with the same functions as the thread backend
(:mod:`srenv.envs.vector_steps`), so the results are those of the
single envs. Workers start by ``forkserver`` (no fork of a process whose threads may hold locks, numba's
included). A worker's exception comes back as one line naming the env and is raised in the parent.
"""

from __future__ import annotations

import multiprocessing as mp

import numpy as np

from .vector_steps import env_op, next_step, same_step, slot_env


def _worker(conn, env_cls: type, env_kwargs: dict, count: int, first: int, env_wrapper=None) -> None:
    try:
        envs = [slot_env(env_cls, env_kwargs, env_wrapper) for _ in range(count)]
        conn.send(("ok", (envs[0].observation_space, envs[0].action_space)))
    except Exception as exc:  # noqa: BLE001 - reported to the parent as one line
        conn.send(("error", f"building env {first}: {type(exc).__name__}: {exc}"))
        return
    while True:
        cmd, args = conn.recv()
        if cmd == "close":
            for env in envs:
                env.close()
            conn.send(("ok", None))
            return
        try:
            if cmd == "reset":
                out = [env.reset(seed=s, options=o) for env, (s, o) in zip(envs, args)]
            elif cmd == "next":
                out = [next_step(env, done, a) for env, (done, a) in zip(envs, args)]
            elif cmd == "same":
                out = [same_step(env, a) for env, a in zip(envs, args)]
            else:  # ("op", (what, name, local indices, args, kwargs))
                what, name, idx, a, k = args
                out = [env_op(envs[i], what, name, a, k) for i in idx]
            conn.send(("ok", out))
        except Exception as exc:  # noqa: BLE001 - reported to the parent as one line
            conn.send(("error", (f"{cmd} in the worker of envs {first}..{first + count - 1}: "
                                f"{type(exc).__name__}: {exc}")))


class ProcessShards:
    """P worker processes holding a contiguous block of the N envs each."""

    def __init__(self, env_cls: type, num_envs: int, processes: int, env_kwargs: dict, env_wrapper=None) -> None:
        ctx = mp.get_context("forkserver")
        self.blocks = [b.tolist() for b in np.array_split(np.arange(num_envs), processes)]
        self.conns, self.procs = [], []
        for block in self.blocks:
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(child, env_cls, dict(env_kwargs), len(block), block[0],
                                                         env_wrapper), daemon=True)
            p.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(p)
        self.spaces = self._gather()[0]

    def _gather(self) -> list:
        out = []
        errors = []
        for c in self.conns:  # every worker answers before an error is raised: the pipes stay in step
            status, payload = c.recv()
            (out if status == "ok" else errors).append(payload)
        if errors:
            raise RuntimeError(errors[0])
        return out

    def run(self, cmd: str, per_env: list) -> list:
        """Send each worker its block's arguments, then collect: the blocks run at the same time."""
        for c, block in zip(self.conns, self.blocks):
            c.send((cmd, [per_env[i] for i in block]))
        return [r for part in self._gather() for r in part]

    def call(self, what: str, name: str, indices: list, args: tuple, kwargs: dict) -> list:
        want = {int(i) for i in indices}
        for c, block in zip(self.conns, self.blocks):
            local = [j for j, i in enumerate(block) if i in want]
            c.send(("op", (what, name, local, args, kwargs)))
        res = {}
        for block, part in zip(self.blocks, self._gather()):
            res.update(zip([i for i in block if i in want], part))
        return [res[int(i)] for i in indices]

    def close(self) -> None:
        for c in self.conns:
            try:
                c.send(("close", None))
                c.recv()
            except (OSError, EOFError):
                pass
        for p in self.procs:
            p.join(timeout=10)
            if p.is_alive():
                p.terminate()
        for c in self.conns:
            c.close()
