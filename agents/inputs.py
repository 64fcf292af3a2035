"""One declaration per numeric flag of ``python -m agents`` and per field of the files the agents read
(benchmark and training YAML, a benchmark report, ``*_obs_norm.npz``, a model zip's metadata, an RLlib
``srenv_policy.json``, baseline parameters), with the readers that check them before any allocation or work.

The declarations are :class:`srenv.declarations.Number` (type, unit, range, where a bound comes from), so a
refusal is the same one line as srenv's: the flag or field, the value, what is expected
(``ConfigError``: exit 2). ``tests/test_declared_inputs.py`` (flags) and ``tests/test_declared_files.py``
(fields) generate their cases from these tables.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from srenv.declarations import Number
from srenv.errors import ConfigError, short_repr
from srenv.input_files import open_regular
from srenv.outputs import check_output_dir  # noqa: F401 - agents' callers import it from here

# --------------------------------------------------------------------------- resource-derived bounds
MAX_SEED = 2**32 - 1           # numpy's seed range
MAX_SEEDS = 10_000             # seeds in one list: each is at least one episode (seconds to minutes each)
MAX_EPISODES = 10_000          # evaluate / replay --episodes: the same
MAX_TIMESTEPS = 1_000_000_000  # n_timesteps: ~6 days of one core at 2 000 env steps/s, more than any run here
MAX_ENVS = 256                 # n_envs / num_env_runners: processes
MAX_WORKERS = 64               # benchmark workers: processes
MAX_OBS_DIM = 4096             # a model's observation vector (the v1 envs have < 100; Box allocations)
MAX_NET_WIDTH = 4096           # one hidden layer: width^2 float32 = 64 MiB at most
MAX_NET_LAYERS = 16
MAX_NPZ_BYTES = 10_000_000

FLAGS: dict[str, dict[str, Number]] = {
    "train": {"--total-timesteps": Number("--total-timesteps", int, hi=MAX_TIMESTEPS, why="wall time"),
              "--n-envs": Number("--n-envs", int, hi=MAX_ENVS, why="processes")},
    "evaluate": {"--episodes": Number("--episodes", int, hi=MAX_EPISODES, why="wall time"),
                 "--seed": Number("--seed", int, lo=0, hi=MAX_SEED, lo_open=False)},
    "quickstart": {"--total-timesteps": Number("--total-timesteps", int, hi=MAX_TIMESTEPS, why="wall time"),
                   "--episodes": Number("--episodes", int, hi=MAX_EPISODES, why="wall time"),
                   "--seed": Number("--seed", int, lo=0, hi=MAX_SEED, lo_open=False),
                   "--workers": Number("--workers", int, hi=MAX_WORKERS, why="processes")},
    "benchmark": {"--fresh-seed": Number("--fresh-seed", int, lo=0, hi=MAX_SEED, lo_open=False),
                  "--episodes": Number("--episodes", int, hi=MAX_EPISODES, why="wall time"),
                  "--workers": Number("--workers", int, hi=MAX_WORKERS, why="processes")},
    "replay": {"--episodes": Number("--episodes", int, hi=MAX_EPISODES, why="wall time"),
               "--tol": Number("--tol", float, lo=0.0, hi=1.0, lo_open=False, why="a relative difference")},
}

FIELDS: dict[str, dict[str, Number]] = {
    "benchmark": {
        "workers": Number("workers", int, hi=MAX_WORKERS, why="processes"),
        "seeds.start": Number("seeds.start", int, lo=0, hi=MAX_SEED, lo_open=False),
        "seeds.count": Number("seeds.count", int, hi=MAX_SEEDS, why="episodes (wall time, memory)"),
        "seeds[]": Number("seeds[]", int, lo=0, hi=MAX_SEED, lo_open=False),
    },
    "train": {
        "n_timesteps": Number("n_timesteps", int, hi=MAX_TIMESTEPS, why="wall time"),
        "n_envs": Number("n_envs", int, lo=0, hi=MAX_ENVS, lo_open=False, why="processes (0 = all cores)"),
        "num_env_runners": Number("num_env_runners", int, lo=0, hi=MAX_ENVS, lo_open=False, why="processes"),
        "vec_processes": Number("vec_processes", int, lo=0, hi=MAX_ENVS, lo_open=False,
                                why="processes (0 = all cores, 1 = threads)"),
    },
    "report": {
        "episodes[].seed": Number("episodes[].seed", int, lo=0, hi=MAX_SEED, lo_open=False),
        "episodes[].reward": Number("episodes[].reward", float, "", lo=-1e300, hi=1e300, lo_open=False),
    },
    "model": {
        "observation_space._shape[]": Number("observation_space._shape[]", int, hi=MAX_OBS_DIM, why="memory"),
        "action_space._shape[]": Number("action_space._shape[]", int, hi=16),
        "policy_kwargs.net_arch[]": Number("policy_kwargs.net_arch[]", int, hi=MAX_NET_WIDTH,
                                           why="memory (width^2 weights per layer)"),
    },
    "checkpoint": {
        "num_timesteps": Number("num_timesteps", int, lo=0, hi=MAX_TIMESTEPS, lo_open=False),
        "iterations": Number("iterations", int, lo=0, hi=MAX_TIMESTEPS, lo_open=False),
    },
    "obs_norm": {
        "clip_obs": Number("clip_obs", float, hi=1e6),
        "epsilon": Number("epsilon", float, hi=1.0),
    },
}
# gymnasium.make's own keywords (the env's are checked by the env): a wrong one is one line, not an assertion
MAKE_NUMBERS = {"max_episode_steps": Number("max_episode_steps", int, hi=MAX_TIMESTEPS, why="wall time")}
MAKE_FLAGS = ("autoreset", "disable_env_checker", "apply_api_compatibility")


def make_kwargs(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """``gymnasium.make`` keywords checked: its numbers declared, its switches booleans, ``render_mode`` a name."""
    out = dict(kwargs)
    for key, value in kwargs.items():
        if key in MAKE_NUMBERS and value is not None:
            out[key] = MAKE_NUMBERS[key].check(value)
        elif key in MAKE_FLAGS and not isinstance(value, bool):
            raise ConfigError(key, value, "true or false")
        elif key == "render_mode" and not (value is None or isinstance(value, str)):
            raise ConfigError(key, value, "a render mode name (rgb_array or human) or null")
    return out


UNIT_INTERVAL = Number("action", float, "", lo=-1.0, hi=1.0, lo_open=False)
FRACTION = Number("fillage", float, "", lo=0.0, hi=1.0, lo_open=False)
GAIN = Number("gain", float, "", lo=0.0, hi=100.0, lo_open=False)
BASELINE_PARAMS: dict[str, dict[str, Number]] = {
    "best_constant": {"a_spm": UNIT_INTERVAL, "a_stroke": UNIT_INTERVAL},
    "pump_off": {"threshold": FRACTION, "idle_time_s": Number("idle_time_s", float, "s", lo=0.0, hi=8.76e6,
                                                              lo_open=False),
                 "a_spm": UNIT_INTERVAL, "a_stroke": UNIT_INTERVAL, "interval_s": Number("interval_s", float, "s",
                                                                                       lo=10.0, hi=86400.0)},
    "fillage_pi": {"setpoint": FRACTION, "kp": GAIN, "ki": GAIN, "a_stroke": UNIT_INTERVAL, "u0": UNIT_INTERVAL,
                   "u_min": UNIT_INTERVAL},
}

BASELINE_PARAMS["alarm_pump_off"] = {  # pump-off's set point and the alarms' (agents/policies/alarms.py)
    **BASELINE_PARAMS["pump_off"],
    "load_drop": Number("load_drop", float, "", lo=0.0, hi=0.999, why="a fraction of the load range below 1"),
    "alarm_prob": Number("alarm_prob", float, "", lo=1.0 / 12.0, hi=1.0, why="above the classifier's uniform 1/12"),
    "gas_slowdown": Number("gas_slowdown", float, "", lo=0.0, hi=2.0, lo_open=False),
}


def field(kind: str, name: str, value: Any, where: str = "") -> Any:
    """Check one declared field of a file of ``kind``; ``where`` prefixes the field name in the message."""
    decl = FIELDS[kind][name]
    return decl.check(value, f"{where}{name}" if where else None)


def seeds(value: Any, key: str) -> list[int]:
    """A seed list: ``[1, 2, 3]`` or ``{start: S, count: N}``, bounded before the list is built."""
    if isinstance(value, Mapping) and set(value) == {"start", "count"}:
        s = FIELDS["benchmark"]["seeds.start"].check(value["start"], f"{key}.start")
        n = FIELDS["benchmark"]["seeds.count"].check(value["count"], f"{key}.count")
        return list(range(s, s + n))
    if isinstance(value, list) and value:
        if len(value) > MAX_SEEDS:
            raise ConfigError(key, value, f"at most {MAX_SEEDS} seeds")
        out = [FIELDS["benchmark"]["seeds[]"].check(v, f"{key}[{i}]") for i, v in enumerate(value)]
        if len(set(out)) == len(out):
            return out
    raise ConfigError(key, value, "a list of distinct non-negative integers or {start: S, count: N}")


def baseline_params(name: str, params: Any, where: str) -> dict[str, Any]:
    """A baseline's (tuned) parameters: a mapping of its declared numeric fields (others are the
    oracle's and the installed rule's, checked by those policies)."""
    if not isinstance(params, Mapping):
        raise ConfigError(where, params, "a mapping of the baseline's parameters")
    decls = BASELINE_PARAMS.get(name)
    if decls is None:
        return dict(params)
    unknown = sorted(str(k) for k in params if k not in decls)
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]}", params[unknown[0]], f"one of the parameters {', '.join(decls)}")
    return {k: decls[k].check(v, f"{where}.{k}") for k, v in params.items()}


def report_episodes(policy: Mapping, name: str) -> dict[int, float]:
    """{seed: reward} of a report's stored episodes: a list of mappings with a seed and a finite reward."""
    eps = policy.get("episodes", [])
    where = f"policies.{name}.episodes"
    if not isinstance(eps, list):
        raise ConfigError(where, eps, "a list of {seed, reward} mappings")
    out = {}
    for i, e in enumerate(eps):
        if not isinstance(e, Mapping) or "seed" not in e or "reward" not in e:
            raise ConfigError(f"{where}[{i}]", e, "a mapping with a seed and a reward")
        seed = FIELDS["report"]["episodes[].seed"].check(e["seed"], f"{where}[{i}].seed")
        out[seed] = FIELDS["report"]["episodes[].reward"].check(e["reward"], f"{where}[{i}].reward")
    return out


def report_env_kwargs(value: Any) -> dict[str, Any]:
    """A report's env kwargs: a mapping with string keys (the env checks the values, its horizon included)."""
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise ConfigError("env_kwargs", value, "a mapping of env keyword arguments with string keys")
    return dict(value)


def shape(value: Any, kind: str, key: str, where: str) -> tuple[int, ...]:
    """A space shape from a model file, each dimension bounded before any Box or tensor is allocated."""
    if not isinstance(value, (list, tuple)) or not 1 <= len(value) <= 4:
        raise ConfigError(where, value, "a shape of 1 to 4 dimensions")
    dims = tuple(FIELDS[kind][key].check(n, f"{where}[{i}]") for i, n in enumerate(value))
    if int(np.prod(dims)) > MAX_OBS_DIM:
        raise ConfigError(where, value, f"at most {MAX_OBS_DIM} values in all")
    return dims


def net_arch(value: Any, where: str) -> Any:
    """SB3's net_arch: a list of widths, or a mapping pi/vf/qf -> list of widths; each bounded."""
    def widths(v: Any, w: str) -> list[int]:
        if not isinstance(v, list) or len(v) > MAX_NET_LAYERS:
            raise ConfigError(w, v, f"a list of at most {MAX_NET_LAYERS} layer widths")
        return [FIELDS["model"]["policy_kwargs.net_arch[]"].check(n, f"{w}[{i}]") for i, n in enumerate(v)]
    if isinstance(value, Mapping):
        return {k: widths(v, f"{where}.{k}") for k, v in value.items()}
    return widths(value, where)


def obs_norm_npz(path: str | Path) -> dict[str, Any]:
    """``mean``, ``var``, ``clip_obs``, ``epsilon`` of an ``*_obs_norm.npz`` (no pickles), checked: present,
    finite, var >= 0, shapes matching and bounded. Any defect: one line naming the file and the key."""
    p = Path(path)
    try:
        if p.stat().st_size > MAX_NPZ_BYTES:
            raise ConfigError("obs_norm", str(p), f"an .npz of at most {MAX_NPZ_BYTES} bytes")
        with open_regular(p, "obs_norm", ".npz file") as fh, np.load(fh, allow_pickle=False) as z:
            missing = [k for k in ("mean", "var", "clip_obs", "epsilon") if k not in z.files]
            if missing:
                raise ConfigError("obs_norm", str(p), f"an .npz with mean, var, clip_obs, epsilon (missing "
                                  f"{', '.join(missing)})")
            arrays = {k: z[k] for k in ("mean", "var", "clip_obs", "epsilon")}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError("obs_norm", str(p), f"a readable .npz ({type(exc).__name__}: {short_repr(str(exc), 80)})") \
            from None
    mean, var = (np.asarray(arrays[k], dtype=np.float64) for k in ("mean", "var"))
    if mean.ndim != 1 or mean.shape != var.shape or not 1 <= mean.size <= MAX_OBS_DIM:
        raise ConfigError("obs_norm", str(p), f"mean and var of one shape with 1 to {MAX_OBS_DIM} values "
                          f"(found {mean.shape} and {var.shape})")
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(var)) and np.all(var >= 0)):
        raise ConfigError("obs_norm", str(p), "finite mean and finite var >= 0")
    out: dict[str, Any] = {"mean": mean, "var": var}
    for k in ("clip_obs", "epsilon"):
        a = arrays[k]
        if np.ndim(a) != 0:
            raise ConfigError(f"obs_norm {p}: {k}", a.shape, "a scalar")
        out[k] = field("obs_norm", k, a.item(), f"obs_norm {p}: ")
    return out


def checkpoint_progress(record: Any, path: str | Path) -> tuple[int, int]:
    """(num_timesteps, iterations) of a checkpoint's progress JSON, each declared and bounded."""
    if not isinstance(record, Mapping) or not {"num_timesteps", "iterations"} <= set(record):
        raise ConfigError(f"{path}", short_repr(record, 80), "a JSON mapping with num_timesteps and iterations")
    return (field("checkpoint", "num_timesteps", record["num_timesteps"], f"{path}: "),
            field("checkpoint", "iterations", record["iterations"], f"{path}: "))


def policy_json(meta: Any, path: str | Path) -> dict[str, Any]:
    """An RLlib ``srenv_policy.json``: a mapping with the keys the loader uses, shapes bounded."""
    where = f"{path}"
    if not isinstance(meta, Mapping):
        raise ConfigError(where, type(meta).__name__, "a JSON mapping (algo, model_config, shapes, action bounds)")
    need = ("algo", "model_config", "observation_shape", "action_shape", "action_low", "action_high")
    missing = [k for k in need if k not in meta]
    if missing:
        raise ConfigError(where, sorted(meta)[:8], f"the keys {', '.join(need)} (missing {', '.join(missing)})")
    shape(meta["observation_shape"], "model", "observation_space._shape[]", f"{where}: observation_shape")
    shape(meta["action_shape"], "model", "action_space._shape[]", f"{where}: action_shape")
    if not isinstance(meta["model_config"], Mapping):
        raise ConfigError(f"{where}: model_config", meta["model_config"], "a mapping")
    for k, v in meta["model_config"].items():  # RLlib's layer widths (fcnet_hiddens, head_fcnet_hiddens)
        if str(k).endswith("hiddens"):
            net_arch(v, f"{where}: model_config.{k}")
    for k in ("action_low", "action_high"):
        v = meta[k]
        if not (isinstance(v, list) and len(v) <= 16 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                              for x in v)):
            raise ConfigError(f"{where}: {k}", v, "a list of numbers")
    return dict(meta)
