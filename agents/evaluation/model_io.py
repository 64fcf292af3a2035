"""Model files read as data: SB3 zips without unpickling, normalisation statistics as JSON.

An SB3 zip holds ``data`` (JSON in which every non-JSON object - spaces, schedules, the policy class, the
policy kwargs - is a base64 *cloudpickle* under a ``:serialized:`` key) and ``policy.pth`` (a torch state
dict). ``stable_baselines3``'s ``load`` unpickles the ``:serialized:`` entries, and unpickling runs
whatever code the file names: a model file from elsewhere is a program. So by default a model is read
here as data only:

* ``data`` is parsed as JSON and no ``:serialized:`` payload is ever decoded; what is needed (algorithm,
  policy class name, policy kwargs, space shapes) is taken from the plain-text fields SB3 writes beside
  each payload, and accepted only when it is plain data (``ast.literal_eval``, never ``eval``) or a
  ``torch.nn`` activation named by its class path;
* the network is rebuilt from the env's spaces and those kwargs, and its weights are loaded with
  ``torch.load(weights_only=True)``, which refuses anything but tensors and plain containers;
* VecNormalize statistics come from ``<model>_vecnormalize.json`` (mean, var, count, clip, epsilon,
  gamma); a ``*_vecnormalize.pkl`` is a pickle and is only read with ``--trust-model``.

Anything else (a custom policy class, a features extractor, a checkpoint with only pickled statistics)
needs ``--trust-model``, which loads through SB3 and pickle as before: use it only for files you made.
"""

from __future__ import annotations

import ast
import io
import json
import math
import re
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from srenv.input_files import parse_json, read_json

from .normalizer import ObsNormalizer

STATS_SUFFIX = "_vecnormalize.json"
MAX_STATS_BYTES = 10_000_000  # a statistics JSON: mean and var of the observation, a few kB
MAX_MODEL_BYTES = 200_000_000  # a zip member larger than this is refused before it is read

# policy_kwargs keys that are plain data in the policies this package trains (MlpPolicy of PPO, A2C, SAC,
# TD3); any other key (features extractors, optimizer classes, ...) is code and needs --trust-model
_PLAIN_KWARGS = {"net_arch", "log_std_init", "ortho_init", "use_sde", "full_std", "use_expln",
                 "squash_output", "share_features_extractor", "n_critics", "clip_mean", "normalize_images"}
_ACTIVATION_RE = re.compile(r"^<class 'torch\.nn\.modules\.activation\.([A-Za-z0-9_]+)'>$")
_INIT_RE = re.compile(r"^<function ([A-Za-z0-9_]+)\.__init__ at 0x[0-9a-f]+>$")


class ModelFileError(ValueError):
    """A model file that cannot be read as data; the message says why and what to do."""


def _trust_hint(path: str | Path, what: str) -> ModelFileError:
    return ModelFileError(f"{path}: {what}; reading it would mean unpickling, which can run arbitrary code - "
                          "pass --trust-model only if you made this file yourself")


def _open_zip(path: str | Path) -> zipfile.ZipFile:
    p = Path(path)
    if not p.is_file():
        raise ModelFileError(f"--policy {path}: no such model file (or use rocking / fillage)")
    try:
        zf = zipfile.ZipFile(p)
        for info in zf.infolist():  # sizes first: testzip decompresses
            if info.file_size > MAX_MODEL_BYTES:
                raise ModelFileError(f"{path}: member {info.filename!r} of {info.file_size} bytes exceeds "
                                     f"{MAX_MODEL_BYTES}")
        bad = zf.testzip()  # CRC of every member: a truncated or corrupted file is refused here
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise ModelFileError(f"{path}: not a readable SB3 model zip ({exc})") from None
    if bad is not None:
        raise ModelFileError(f"{path}: corrupted zip member {bad!r}")
    return zf


def read_data(path: str | Path) -> dict[str, Any]:
    """The ``data`` JSON of an SB3 zip (no ``:serialized:`` payload is decoded)."""
    with _open_zip(path) as zf:
        try:
            raw = zf.read("data")
        except KeyError:
            raise ModelFileError(f"{path}: not an SB3 model zip (no 'data' member)") from None
    data = parse_json(raw, str(path), "data", "SB3 model member")
    if not isinstance(data, dict):
        raise ModelFileError(f"{path}: its 'data' member is not a JSON mapping")
    return data


def _plain(text: Any, path: str | Path, key: str) -> Any:
    """A plain-data value from SB3's text beside a payload ('[64, 64]', '-1.0', 'True')."""
    if not isinstance(text, str):
        return text
    try:
        return ast.literal_eval(text)  # literals only: numbers, strings, lists, dicts, booleans, None
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        raise _trust_hint(path, f"policy_kwargs.{key} = {text[:60]!r} is not plain data") from None


def policy_kwargs(data: dict[str, Any], path: str | Path) -> dict[str, Any]:
    """Policy kwargs from the readable fields of ``data['policy_kwargs']``; code-valued keys are refused."""
    from torch import nn

    raw = data.get("policy_kwargs") or {}
    if not isinstance(raw, dict):
        raise _trust_hint(path, "policy_kwargs is not a mapping")
    out: dict[str, Any] = {}
    for key, value in raw.items():
        if key in (":type:", ":serialized:"):
            continue
        if key == "activation_fn":
            m = _ACTIVATION_RE.match(str(value))
            cls = getattr(nn, m.group(1), None) if m else None
            if not (isinstance(cls, type) and issubclass(cls, nn.Module)):
                raise _trust_hint(path, f"policy_kwargs.activation_fn = {str(value)[:60]!r} is not a torch.nn "
                                  "activation")
            out[key] = cls
        elif key == "net_arch":
            from ..inputs import net_arch  # widths bounded before the network is built

            out[key] = net_arch(_plain(value, path, key), f"{path}: policy_kwargs.net_arch")
        elif key in _PLAIN_KWARGS:
            out[key] = _plain(value, path, key)
        else:
            raise _trust_hint(path, f"policy_kwargs.{key} is not plain data this loader rebuilds")
    return out


def space_shape(data: dict[str, Any], key: str, path: str | Path) -> tuple[int, ...]:
    """Shape of a Box space from its readable '_shape' field."""
    entry = data.get(key)
    shape = _plain(entry.get("_shape"), path, key) if isinstance(entry, dict) else None
    if not (isinstance(shape, (list, tuple)) and all(isinstance(n, int) for n in shape)):
        raise _trust_hint(path, f"{key} is not a Box space with a readable shape")
    from ..inputs import shape as bounded_shape  # each dimension bounded before any Box is allocated

    return bounded_shape(list(shape), "model", f"{key}._shape[]", f"{path}: {key}._shape")


def policy_class_name(data: dict[str, Any]) -> str | None:
    entry = data.get("policy_class")
    if isinstance(entry, dict):
        m = _INIT_RE.match(str(entry.get("__init__", "")))
        return m.group(1) if m else None
    return None


def load_policy(path: str | Path, algo_cls: type, observation_space: Any, action_space: Any) -> Any:
    """The SB3 policy network of a zip, rebuilt for the given spaces with weights-only loading."""
    import torch

    data = read_data(path)
    policy_cls = algo_cls.policy_aliases["MlpPolicy"]
    name = policy_class_name(data)
    if name != policy_cls.__name__:
        raise _trust_hint(path, f"its policy class {name or 'unknown'} is not the {policy_cls.__name__} "
                          "this loader rebuilds")
    kwargs = policy_kwargs(data, path)
    if "use_sde" in data and "use_sde" not in kwargs and algo_cls.__name__ in ("PPO", "A2C"):
        kwargs["use_sde"] = bool(data["use_sde"])
    policy = policy_cls(observation_space, action_space, lambda _progress: 0.0, **kwargs)
    with _open_zip(path) as zf:
        try:
            raw = zf.read("policy.pth")
        except KeyError:
            raise ModelFileError(f"{path}: not an SB3 model zip (no 'policy.pth' member)") from None
    try:
        state = torch.load(io.BytesIO(raw), map_location="cpu", weights_only=True)
        policy.load_state_dict(state)
    except Exception as exc:  # noqa: BLE001 - torch raises several types for a bad or foreign state dict
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ModelFileError(f"{path}: policy weights do not load ({first[:200]})") from None
    policy.set_training_mode(False)
    return policy


# ---------------------------------------------------------------------------------- normalisation stats
def stats_record(vecnormalize: Any) -> dict[str, Any]:
    """JSON-safe statistics of a VecNormalize (what evaluation and a later re-creation need)."""
    rec: dict[str, Any] = {"format": "srenv-vecnormalize-1", "norm_obs": bool(vecnormalize.norm_obs),
                           "norm_reward": bool(vecnormalize.norm_reward),
                           "clip_obs": float(vecnormalize.clip_obs), "clip_reward": float(vecnormalize.clip_reward),
                           "epsilon": float(vecnormalize.epsilon), "gamma": float(vecnormalize.gamma)}
    for name in ("obs_rms", "ret_rms"):
        rms = getattr(vecnormalize, name, None)
        if rms is not None and not isinstance(rms, dict):
            rec[name] = {"mean": np.asarray(rms.mean, dtype=float).tolist(),
                         "var": np.asarray(rms.var, dtype=float).tolist(), "count": float(rms.count)}
    return rec


def write_stats(vecnormalize: Any, path: str | Path) -> None:
    """Write the statistics JSON atomically (temporary file in the target directory, then rename)."""
    from srenv.outputs import atomic_write

    text = json.dumps(stats_record(vecnormalize), allow_nan=False)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def read_stats(path: str | Path, obs_shape: tuple[int, ...]) -> ObsNormalizer | None:
    """The observation normaliser of a statistics JSON (None when it does not normalise observations)."""
    try:
        rec = read_json(path, "statistics", "statistics file", MAX_STATS_BYTES)
        if not rec.get("norm_obs", True):
            return None
        mean = np.asarray(rec["obs_rms"]["mean"], dtype=np.float64)
        var = np.asarray(rec["obs_rms"]["var"], dtype=np.float64)
        clip, eps = float(rec["clip_obs"]), float(rec["epsilon"])
    except ModelFileError:
        raise
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:  # AttributeError: not a mapping
        raise ModelFileError(f"{path}: not a readable statistics JSON ({type(exc).__name__}: {exc})") from None
    if mean.shape != tuple(obs_shape) or var.shape != mean.shape:
        raise ModelFileError(f"{path}: normalisation statistics of shape {mean.shape} do not fit the env's "
                             f"observation shape {tuple(obs_shape)}")
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(var)) and np.all(var >= 0)
            and math.isfinite(clip) and clip > 0 and math.isfinite(eps) and eps > 0):
        raise ModelFileError(f"{path}: statistics are not finite / positive")
    return ObsNormalizer.from_variance(mean, var, clip, eps)


def stats_path(model_path: str | Path) -> Path:
    p = Path(model_path)
    return p.with_name(p.name.removesuffix(".zip") + STATS_SUFFIX)


# ---------------------------------------------------------------------------------- which model is it
VECNORM_SUFFIX = "_vecnormalize.pkl"


def algorithms() -> dict[str, type]:
    """Supported SB3 algorithms by YAML name (imported lazily: torch is slow to import)."""
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import A2C, PPO, SAC, TD3

    return {"ppo": PPO, "sac": SAC, "a2c": A2C, "td3": TD3, "recurrent_ppo": RecurrentPPO}


def detect_algo(model_path: str | Path) -> str:
    """The algorithm a saved zip was trained with, from its JSON hyperparameters (nothing unpickled)."""
    data = read_data(model_path)
    if "recurrent" in str(data.get("policy_class", "")).lower():  # sb3-contrib's LSTM policies (v2 designs)
        return "recurrent_ppo"
    # keys that only one supported algorithm stores
    for key, algo in (("clip_range", "ppo"), ("target_entropy", "sac"), ("policy_delay", "td3"),
                      ("normalize_advantage", "a2c")):
        if key in data:
            return algo
    raise ValueError(f"{model_path}: cannot tell which algorithm saved this model (supported: "
                     + ", ".join(algorithms()) + ")")


def check_spaces(model_obs: Any, model_act: Any, env_obs: Any, env_act: Any, path: str | Path) -> None:
    """One clear error when a model cannot drive this env (the same test SB3 applies when loading)."""
    problems = []
    if model_obs != env_obs:
        problems.append(f"observation space: model {model_obs} vs env {env_obs}")
    if model_act != env_act:
        problems.append(f"action space: model {model_act} vs env {env_act}")
    if problems:
        raise ValueError(f"{path} does not fit this env: " + "; ".join(problems)
                         + " (trained on a different env config or version?)")


def vecnormalize_path(model_path: str | Path) -> Path | None:
    """The VecNormalize statistics that belong to a saved model, if any.

    Conventions, in order: ``X.zip`` -> ``X_vecnormalize.pkl`` (this package), SB3 checkpoints
    ``rl_model_N_steps.zip`` -> ``rl_model_vecnormalize_N_steps.pkl``, rl-zoo's ``vecnormalize.pkl``.
    """
    p = Path(model_path)
    stem = p.name.removesuffix(".zip")
    m = re.match(r"^(.*)_(\d+)_steps$", stem)
    candidates = [p.with_name(stem + VECNORM_SUFFIX), p.with_name("vecnormalize.pkl")]
    if m:
        candidates.insert(1, p.with_name(f"{m.group(1)}_vecnormalize_{m.group(2)}_steps.pkl"))
    return next((c for c in candidates if c.is_file()), None)
