"""The native vector env's process backend: N envs split into P contiguous blocks, the first stepped by the driver
process itself and each other by a worker process (``driver_block``; P = 1 is one worker).

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


def _serve(envs: list, cmd: str, args, first: int) -> tuple[str, object]:
    """One command on a block of envs: ``("ok", results)`` or ``("error", one line naming the block)``."""
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
        return "ok", out
    except Exception as exc:  # noqa: BLE001 - reported to the parent as one line
        return "error", (f"{cmd} in the worker of envs {first}..{first + len(envs) - 1}: "
                         f"{type(exc).__name__}: {exc}")


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
        conn.send(_serve(envs, cmd, args, first))


class _DriverBlock:
    """The first block, stepped in the driver process itself behind a pipe's send/recv: the command is kept at
    ``send`` and run at ``recv``, which :meth:`ProcessShards._gather` calls after every worker has its command, so
    the blocks still run at the same time. Why: with P workers and a driver that only waits, P + 1 processes are
    runnable on P cores during a step's hand-offs, and a pipe write that wakes a worker gives it the driver's core
    (docs/speed.md §3); with P - 1 workers no more processes run than there are cores."""

    def __init__(self, env_cls: type, env_kwargs: dict, count: int, env_wrapper=None) -> None:
        self.envs: list = []
        try:
            self.envs = [slot_env(env_cls, env_kwargs, env_wrapper) for _ in range(count)]
            self._pending: tuple = ("ok", (self.envs[0].observation_space, self.envs[0].action_space))
        except Exception as exc:  # noqa: BLE001 - raised by _gather as a worker's would be
            self._pending = ("error", f"building env 0: {type(exc).__name__}: {exc}")

    def send(self, msg: tuple) -> None:
        if msg[0] == "close":
            for env in self.envs:
                env.close()
            self._pending = ("ok", None)
        else:
            self._pending = ("run", msg)

    def recv(self) -> tuple:
        status, payload = self._pending
        if status == "run":
            cmd, args = payload
            return _serve(self.envs, cmd, args, 0)
        return status, payload

    def close(self) -> None:
        pass


class ProcessShards:
    """P blocks of the N envs, contiguous: with P > 1 the driver steps the first (``driver_block``, default) and P - 1
    worker processes the others; P = 1 is one worker process."""

    def __init__(self, env_cls: type, num_envs: int, processes: int, env_kwargs: dict, env_wrapper=None,
                 driver_block: bool = True) -> None:
        ctx = mp.get_context("forkserver")
        self.blocks = [b.tolist() for b in np.array_split(np.arange(num_envs), processes)]
        self.conns, self.procs = [], []
        local = processes > 1 and driver_block  # the driver steps the first block itself
        for block in self.blocks[1:] if local else self.blocks:
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(child, env_cls, dict(env_kwargs), len(block), block[0],
                                                         env_wrapper), daemon=True)
            p.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(p)
        if local:  # built while the workers build theirs; first in the list, as its block is first
            self.conns.insert(0, _DriverBlock(env_cls, dict(env_kwargs), len(self.blocks[0]), env_wrapper))
        self.spaces = self._gather()[0]

    def _gather(self) -> list:
        out = []
        errors = []
        for c, block in zip(self.conns, self.blocks):  # every worker answers before an error is raised
            try:
                status, payload = c.recv()
            except EOFError:  # it died before answering: most often a script without a main guard
                status, payload = "error", (f"the worker of envs {block[0]}..{block[-1]} exited before it built "
                                            f"its envs (a script that makes processes= envs keeps its top level "
                                            f"under `if __name__ == \"__main__\":`, as forkserver imports it "
                                            f"again in the worker)")
            (out if status == "ok" else errors).append(payload)
        if errors:
            raise RuntimeError(errors[0])
        return out

    def run(self, cmd: str, per_env: list) -> list:
        """Send each worker its block's arguments, then collect: the blocks run at the same time."""
        return [r for part in self.run_parts(cmd, per_env) for r in part]

    def run_parts(self, cmd: str, per_env: list):
        """:meth:`run` block by block, in env order: the caller can merge the driver's block (first) while the
        workers still run theirs. Every block is collected before an error is raised (the pipes stay in step)."""
        for c, block in zip(self.conns, self.blocks):
            c.send((cmd, [per_env[i] for i in block]))
        error = None
        for c in self.conns:
            status, payload = c.recv()
            if status != "ok":
                error = error or payload
            elif error is None:
                yield payload
        if error is not None:
            raise RuntimeError(error)

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
