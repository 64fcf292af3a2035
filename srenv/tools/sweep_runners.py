"""How a sweep's cases run: in this process, in a local pool of processes (pipes only, no listener), or as Ray
tasks on a cluster named by ``--address``; every backend gives the same rows (see :mod:`srenv.tools.sweep`)."""

from __future__ import annotations

import math
import os
import time
import warnings
from typing import Any

import numpy as np

from ..errors import ConfigError
from .sweep_cases import Case


def run_case(raw: dict, duration_s: float, settle_fraction: float) -> dict[str, float]:
    """Simulate one case and measure it (module docstring); runs in a Ray worker or in this process."""
    from ..analysis import metrics
    from ..config import config_from_dict
    from ..simulation.simulator import Simulator, concat_traces

    cfg = config_from_dict(raw)
    with warnings.catch_warnings():
        # the driver already warned once per set when it validated the cases
        warnings.simplefilter("ignore", UserWarning)
        sim = Simulator(cfg)
    if cfg.surface.motion == "pullout":
        results = [sim.run_duration(duration_s)]
        strokes_late = 0.0
        trace = results[0].trace
        t = trace["t_s"]
        late = t >= t[0] + settle_fraction * (t[-1] - t[0])
    else:
        n_strokes = max(1, round(duration_s * cfg.surface.spm / 60.0))
        results = sim.run_strokes(n_strokes)
        trace = concat_traces(results)
        first = math.ceil(settle_fraction * n_strokes - 1e-9)  # a window starting at a stroke boundary
        strokes_late = float(n_strokes - first)
        late = np.zeros(len(trace["t_s"]), dtype=bool)
        late[sum(r.n_steps for r in results[:first]):] = True
    t, load, vb = trace["t_s"][late], trace["polished_rod_load_n"][late], trace["pump_velocity_m_s"][late]
    du = (trace["polished_rod_position_m"] - trace["pump_position_m"])[late]  # u_B - u_A, positive down
    window_s = 1.0 / sim.f1_hz
    n_steps = sum(r.n_steps for r in results)
    return {
        "duration_s": float(sum(r.duration_s for r in results)),
        "plunger_stick_episodes": len(metrics.rest_episodes(vb)),
        "plunger_extra_stick_episodes": metrics.plunger_extra_stick_episodes(vb, strokes_late),
        "slip_amplitude_m": metrics.slip_amplitude_m(t, du, window_s),
        "peak_polished_rod_load_n": float(load.max()),
        "min_polished_rod_load_n": float(load.min()),
        "polished_rod_load_oscillation_pp_n": metrics.load_oscillation_pp_n(t, load, window_s),
        "dc_iterations_per_step": sum(r.dc_iterations for r in results) / n_steps,
        "qp_steps": sum(r.qp_steps for r in results),
    }


def _run_case_portable(raw: dict, duration_s: float, settle_fraction: float) -> dict[str, Any]:
    """run_case for another process: srenv's own errors come back as data, because their constructors
    take several arguments and so do not survive Ray's exception pickling."""
    from ..errors import SolverFailure

    try:
        return run_case(raw, duration_s, settle_fraction)
    except ConfigError as exc:
        return {"error": "ConfigError", "args": [exc.field, exc.value, exc.expected]}
    except SolverFailure as exc:
        return {"error": "SolverFailure", "args": [exc.step, exc.time_s, exc.detail]}


def _unwrap(result: dict[str, Any]) -> dict[str, Any]:
    """Re-raise an error returned by :func:`_run_case_portable` as itself (the CLI reports it as for a
    serial run); pass a metrics row through."""
    from ..errors import SolverFailure

    if "error" in result:
        raise {"ConfigError": ConfigError, "SolverFailure": SolverFailure}[result["error"]](*result["args"])
    return result


# ----------------------------------------------------------------------------------------------- backends
def run_serial(cases: list[Case], duration_s: float, settle_fraction: float,
               progress: bool = True) -> list[dict[str, float]]:
    from tqdm import tqdm

    return [run_case(c.raw, duration_s, settle_fraction)
            for c in tqdm(cases, desc="sweep", unit="case", disable=not progress)]


def _run_indexed(job: tuple[int, dict, float, float]) -> tuple[int, dict[str, Any]]:
    index, raw, duration_s, settle_fraction = job
    return index, _run_case_portable(raw, duration_s, settle_fraction)


def run_local(cases: list[Case], duration_s: float, settle_fraction: float, workers: int | None = None,
              progress: bool = True) -> list[dict[str, float]]:
    """Cases in a local process pool (spawned, so no state of this process is shared); results come back
    in case order. The pool is terminated on any exit, an error, Ctrl-C or SIGTERM included."""
    import multiprocessing

    from tqdm import tqdm

    n = min(workers or os.cpu_count() or 1, len(cases))
    from ..interrupts import workers_ignore_sigint

    with workers_ignore_sigint():  # Ctrl-C is reported by this driver alone, in one line
        pool = multiprocessing.get_context("spawn").Pool(n)
    try:
        out: list[dict[str, float] | None] = [None] * len(cases)
        jobs = [(c.index, c.raw, duration_s, settle_fraction) for c in cases]
        with tqdm(total=len(cases), desc="sweep", unit="case", disable=not progress) as bar:
            for i, result in pool.imap_unordered(_run_indexed, jobs):
                out[i] = _unwrap(result)
                bar.update()
        pool.close()
        return [r for r in out if r is not None]
    finally:
        pool.terminate()
        pool.join()


def run_ray(cases: list[Case], duration_s: float, settle_fraction: float, workers: int | None = None,
            address: str | None = None, progress: bool = True,
            timings: dict[str, float] | None = None) -> list[dict[str, float]]:
    """One Ray task per case on the running cluster at ``address``; results are returned in case order
    whatever order they finish in. ``timings`` (if given) receives ``ray_init_s``, the time spent
    connecting. No local Ray is ever started here (module docstring: it would listen on every interface)."""
    import logging

    from tqdm import tqdm

    try:
        import ray
    except ModuleNotFoundError:  # the core install has no Ray: one line, exit 2
        raise ConfigError("--address", address, "an installed Ray (pip install 'srenv[rllib]')") from None
    if not address:
        raise ConfigError("--address", address, "the address of a running Ray cluster (local runs use "
                          "run_local, which opens no network port)")
    started = False
    t0 = time.perf_counter()
    _check_reachable(address)
    if not ray.is_initialized():
        quiet = {"include_dashboard": False, "log_to_driver": False, "logging_level": logging.ERROR}
        try:
            ray.init(address=address, **quiet)
        except (ConnectionError, ValueError) as exc:  # ValueError: not an address at all ("garbage")
            raise ConfigError("--address", address, f"the address of a running Ray cluster ({exc})") from None
        started = True
    if timings is not None:
        timings["ray_init_s"] = round(time.perf_counter() - t0, 3)
    try:
        task = ray.remote(num_cpus=1)(_run_case_portable)
        refs = [task.remote(c.raw, duration_s, settle_fraction) for c in cases]
        order = {ref: i for i, ref in enumerate(refs)}
        out: list[dict[str, float] | None] = [None] * len(refs)
        pending = list(refs)
        with tqdm(total=len(refs), desc="sweep", unit="case", disable=not progress) as bar:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    out[order[ref]] = _unwrap(ray.get(ref))
                    bar.update()
        return [r for r in out if r is not None]
    finally:
        if started:
            ray.shutdown()


def _check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """Fail fast on a HOST:PORT nobody listens on: ray.init would retry for minutes before giving up.
    'auto', 'local' and other forms without a port are left to Ray."""
    import socket

    hostport = address.split("://", 1)[-1]
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as exc:
        raise ConfigError("--address", address, f"the HOST:PORT of a running Ray cluster ({exc})") from None


# ----------------------------------------------------------------------------------------------- results
