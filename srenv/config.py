"""Typed, validated well configs.

Every section is a frozen dataclass; every numeric field carries its unit in its name and a check in its
metadata. ``load_config`` reads YAML with ``yaml.safe_load`` only, applies ``key.path=value`` overrides,
and raises one :class:`~srenv.errors.ConfigError` naming the field, the value and the expected unit.
Nothing in a config is ever evaluated as code. ``docs/config.md`` is generated from these classes
(``srenv config-doc``), so the table of fields, units and defaults cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import types
import typing
from pathlib import Path
from typing import Any

import yaml

from .config_checks import (  # noqa: F401  (re-exported: the resource bounds are part of the config API)
    MAX_DENSE_NODES,
    MAX_NODES,
    MAX_RUN_SAMPLES,
    MAX_STEPS_PER_STROKE,
    _check_consistency,
    _check_resources,
    check_dense_size,
    check_run_samples,
    check_stroke_steps,
    node_count,
    steps_per_stroke,
)
from .config_scalar import _parse_scalar
from .config_sections import (  # noqa: F401  (re-exported: the sections are the config API)
    _CHECKS,
    MATERIAL_DEFAULTS,
    ControlConfig,
    DampingConfig,
    EconomicsConfig,
    FluidConfig,
    FrictionConfig,
    InflowConfig,
    PumpConfig,
    RewardConfig,
    RodConfig,
    SimulationConfig,
    SurfaceConfig,
    SurveyConfig,
    SurveyStation,
    TaperConfig,
    TaskConfig,
    TubingConfig,
    WellConfig,
    choice,
    num,
    opt,
)
from .config_units import si_mapping
from .errors import ConfigError
from .safe_yaml import (  # noqa: F401
    _AMBIGUOUS_NUMBER,
    AMBIGUOUS_WHY,
    MAX_YAML_BYTES,
    MAX_YAML_DEPTH,
    MAX_YAML_NODES,
    _yaml_load,
    _yaml_problem,
    load_yaml_file,
)
from .shipped import shipped_dir


# ----------------------------------------------------------------------------------------------- parsing
def _is_dataclass_type(tp: Any) -> bool:
    return isinstance(tp, type) and dataclasses.is_dataclass(tp)


@functools.cache
def _type_hints(cls: type) -> dict:
    """typing.get_type_hints of a config section, resolved once (it dominated an env reset's time)."""
    return typing.get_type_hints(cls)


@functools.cache
def _plan(cls: type) -> tuple[dict, tuple]:
    """A section's fields as ``_parse`` walks them, resolved once per class (the reset of a well not seen parses
    two configs: docs/speed.md §2e): (the fields by name, (name, type, origin, a section, required, metadata) in
    order)."""
    hints = _type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    rows = tuple((name, hints[name], typing.get_origin(hints[name]), _is_dataclass_type(hints[name]),
                  f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING, dict(f.metadata))
                 for name, f in fields.items())
    return fields, rows


def _parse(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise ConfigError(path or "<root>", data, f"a mapping of {cls.__name__} fields")
    fields, rows = _plan(cls)
    unknown = [k for k in data if k not in fields]
    if unknown:
        key = unknown[0]
        where = f"{path}.{key}" if path else str(key)
        raise ConfigError(where, data[key], "no such field; known fields: " + ", ".join(fields))
    kwargs = {}
    for name, tp, origin, section, required, meta in rows:
        where = f"{path}.{name}" if path else name
        if name not in data:
            if required:
                raise ConfigError(where, None, "a value (this field is required)"
                                  + (f" in {meta['unit']}" if "unit" in meta else ""))
            continue
        value = data[name]
        if origin is tuple:
            (item_tp, _ellipsis) = typing.get_args(tp)
            if not isinstance(value, list):
                raise ConfigError(where, value, f"a list of {item_tp.__name__} entries")
            kwargs[name] = tuple(_parse(item_tp, v, f"{where}[{i}]") for i, v in enumerate(value))
        elif section:
            kwargs[name] = _parse(tp, value, where)
        elif origin in (typing.Union, types.UnionType):
            # an optional field (``float | None``) or section (``Section | None``): null is "not given"
            inner = _optional(tp, where)
            if value is None:
                kwargs[name] = None
            elif _is_dataclass_type(inner):
                kwargs[name] = _parse(inner, value, where)
            else:
                kwargs[name] = _parse_scalar(inner, value, where, meta)
        else:
            kwargs[name] = _parse_scalar(tp, value, where, meta)
    return cls(**kwargs)


def _optional(tp: Any, where: str) -> type:
    """The type of an optional field ``T | None``; no other union is a config type."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if len(args) != 1 or len(typing.get_args(tp)) != 2:
        raise TypeError(f"unsupported union at {where}")  # programming error, not user input
    return args[0]


# ----------------------------------------------------------------------------------------------- loading
CONFIG_DIR = shipped_dir("wells")  # configs/wells of the checkout, or the wheel's package data


def shipped_configs() -> list[str]:
    return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


def _resolve(path_or_name: str | Path) -> Path:
    """A path is a path, a name is a name: anything with a path separator or a .yaml/.yml suffix (or a
    ``Path``) must be an existing, regular, readable file; a bare name must be a shipped config. (A path
    that does not exist never falls back to the shipped config of the same name.)"""
    text = str(path_or_name)
    if isinstance(path_or_name, Path) or "/" in text or os.sep in text or text.endswith((".yaml", ".yml")):
        p = Path(text)
        if not p.exists():
            raise ConfigError("config", text, "an existing YAML file (no such file); or a shipped name: "
                              + ", ".join(shipped_configs()))
        if not p.is_file():
            raise ConfigError("config", text, "a regular YAML file (this is a directory or a special file)")
        if not os.access(p, os.R_OK):
            raise ConfigError("config", text, "a readable YAML file (permission denied)")
        return p
    if text in shipped_configs():
        return CONFIG_DIR / f"{text}.yaml"
    raise ConfigError("config", text, "a YAML path or a shipped name: " + ", ".join(shipped_configs()))


def _parse_override_value(text: str) -> Any:
    # YAML scalar syntax (numbers, true/false, strings) - parsed, never evaluated.
    try:
        return _yaml_load(text)
    except yaml.YAMLError:
        return text


def apply_overrides(data: dict, overrides: dict[str, Any] | list[str] | None, owned: bool = False) -> dict:
    """Apply ``{"a.b.c": value}`` or ``["a.b.c=value", ...]`` to a raw config mapping (a copy unless ``owned``)."""
    import copy

    if not owned:
        data = copy.deepcopy(data)
    if overrides is None or (isinstance(overrides, (dict, list)) and not overrides):
        return data
    if not isinstance(overrides, (dict, list)):
        raise ConfigError("overrides", overrides, "a mapping {'section.field': value} (or a list of "
                          "'section.field=value' strings)")
    for key in overrides:
        if not isinstance(key, str):
            raise ConfigError("overrides", key, "'section.field' strings as keys" if isinstance(overrides, dict)
                              else "'section.field=value' strings")
    items = overrides.items() if isinstance(overrides, dict) else []
    if isinstance(overrides, list):
        pairs = []
        for s in overrides:
            if "=" not in s:
                raise ConfigError("--set", s, "key.path=value")
            k, v = s.split("=", 1)
            if _AMBIGUOUS_NUMBER.match(v.strip()):  # YAML 1.1 would read 010 as 8 and 1:30 as 90
                raise ConfigError(k.strip(), v.strip(), "a number without a leading zero, 0b, colon or underscore "
                                  f"(ambiguous: {AMBIGUOUS_WHY})")
            pairs.append((k.strip(), _parse_override_value(v.strip())))
        items = pairs
    for key, value in items:
        if key.split(".")[0] == "units":  # the file's numbers are SI by now (read_raw): its units are settled
            raise ConfigError(key, value, "a config field (a file's units: block is not overridden)")
        node: Any = data
        parts = key.split(".")
        for part in parts[:-1]:
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ConfigError(key, value, f"a valid list index at '{part}'")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
                if not isinstance(node, (dict, list)):
                    raise ConfigError(key, value, f"a path through mappings ('{part}' is a value)")
        last = parts[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise ConfigError(key, value, f"a valid list index at '{last}'")
            node[int(last)] = value
        else:
            node[last] = value
    return data


def read_raw(path_or_name: str | Path) -> dict:
    path = _resolve(path_or_name)
    data = load_yaml_file(path, "config")
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError("config", str(path), "a YAML mapping at the top level")
    return si_mapping(data)  # a `units:` block (field units) read into SI here: overrides applied after are SI


def _material_defaults(data: dict) -> dict:
    """Fill a fiberglass / sinker-bar taper's unset E, density and strength from MATERIAL_DEFAULTS, in a copy; a
    mapping with no such taper is returned as it is (the parse does not change it: no copy needed)."""
    tapers = (data.get("rod") or {}).get("tapers") if isinstance(data.get("rod"), dict) else None
    if not isinstance(tapers, list) or not any(isinstance(t, dict) and t.get("material") in MATERIAL_DEFAULTS
                                               for t in tapers):
        return data
    import copy

    data = copy.deepcopy(data)
    for t in data["rod"]["tapers"]:
        if isinstance(t, dict) and t.get("material") in MATERIAL_DEFAULTS:
            for key, value in MATERIAL_DEFAULTS[t["material"]].items():
                t.setdefault(key, value)
    return data


def _check_exclusive(data: dict) -> None:
    """Fields a set field excludes (a section's EXCLUDES: the intake pressure follows from a fluid level, so
    both cannot be given): refused on the raw mapping, where "given" can still be seen."""
    for section, cls in _type_hints(WellConfig).items():
        raw = data.get(section)
        if not isinstance(raw, dict):
            continue
        for key, excluded in getattr(cls, "EXCLUDES", {}).items():
            if raw.get(key) is not None and excluded in raw:
                raise ConfigError(f"{section}.{excluded}", raw[excluded], f"absent when {section}.{key} is given "
                                  f"(it follows from {section}.{key}; give one of them)")


def config_from_dict(data: dict) -> WellConfig:
    data = si_mapping(data) if isinstance(data, dict) else data
    _check_exclusive(data)
    cfg = _parse(WellConfig, _material_defaults(data), "")
    _check_consistency(cfg)
    _check_resources(cfg)
    return cfg


def field_bounds(key: str) -> tuple[float, float]:
    """(lo, hi) of a numeric field given as 'section.field' (-inf / inf where unbounded): lets callers that
    perturb a value (the env's domain randomisation) keep it inside what the loader accepts."""
    section, name = key.split(".")
    cls = _type_hints(WellConfig)[section]
    meta = {f.name: f.metadata for f in dataclasses.fields(cls)}[name]
    return float(meta.get("lo", -math.inf)), float(meta.get("hi", math.inf))


def load_config(path_or_name: str | Path | WellConfig = "default",
                overrides: dict[str, Any] | list[str] | None = None) -> WellConfig:
    """Load a well config from a YAML path or a shipped name, with optional ``key.path`` overrides."""
    if isinstance(path_or_name, WellConfig):
        if not overrides:
            return path_or_name
        # to_dict's containers are fresh: owned, no deep copy
        return config_from_dict(apply_overrides(to_dict(path_or_name), overrides, owned=True))
    return config_from_dict(apply_overrides(read_raw(path_or_name), overrides))


def to_dict(cfg: Any) -> Any:
    if dataclasses.is_dataclass(cfg):  # a field another set field excludes is left out (it follows from it)
        skip = {ex for key, ex in getattr(cfg, "EXCLUDES", {}).items() if getattr(cfg, key) is not None}
        return {f.name: to_dict(getattr(cfg, f.name)) for f in dataclasses.fields(cfg) if f.name not in skip}
    if isinstance(cfg, tuple):
        return [to_dict(x) for x in cfg]
    return cfg


def _range_doc(meta: Any) -> str:
    """The accepted range of a numeric field, as in its error message ('' for non-numeric fields)."""
    if "check" not in meta:
        return ""
    lo_by_check = {"positive": "(0", "nonneg": "[0", "unit_interval": "[0", "angle": "[0", "azimuth": "[-360"}
    hi_by_check = {"unit_interval": "1]", "angle": "180]", "azimuth": "360]"}
    lo = f"[{meta['lo']:g}" if "lo" in meta else lo_by_check.get(meta["check"], "(-inf")
    hi = f"{meta['hi']:g}]" if "hi" in meta else hi_by_check.get(meta["check"], "inf)")
    return f"{lo}, {hi}"


def config_doc() -> str:
    """Markdown table of every config field with unit, default and meaning."""
    lines = ["| field | unit | default | range | meaning |", "|---|---|---|---|---|"]

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            tp = hints[f.name]
            key = f"{prefix}{f.name}"
            if typing.get_origin(tp) in (typing.Union, types.UnionType) and _is_dataclass_type(_optional(tp, key)):
                lines.append(f"| `{key}` | section | None | | {f.metadata.get('doc', '')} |")
                walk(_optional(tp, key), key + ".")
                continue
            if _is_dataclass_type(tp):
                walk(tp, key + ".")
                continue
            if typing.get_origin(tp) is tuple:
                item = typing.get_args(tp)[0]
                lines.append(f"| `{key}` | list | [] | | {f.metadata.get('doc', '')} |")
                walk(item, key + "[i].")
                continue
            default = "required" if f.default is dataclasses.MISSING else (
                "null" if f.default is None else repr(f.default))  # null: an optional field not given
            doc = f.metadata.get("doc", "")
            if "options" in f.metadata:
                doc = (doc + "; " if doc else "") + "one of " + ", ".join(f.metadata["options"])
            lines.append(f"| `{key}` | {f.metadata.get('unit', '')} | {default} | {_range_doc(f.metadata)} | {doc} |")

    walk(WellConfig, "")
    return "\n".join(lines)
