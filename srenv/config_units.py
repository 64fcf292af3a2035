"""A well description in field units: the top-level ``units:`` block of a well YAML.

``units: {m: ft, mm: in, Pa: psi, N: lbf, kg/m: lb/ft}`` says that every numeric field of this file whose declared
unit (``num(unit=...)``, the unit column of docs/config.md) is ``m`` is written in ft, every ``mm`` field in in, and
so on. The keys are those declared SI units, exactly as declared; the values are units of ``field_units.UNITS`` of
the same quantity. Field names stay SI (``pump.depth_m`` is a depth whatever the file's units); only this file's
numbers are in field units, and :func:`si_mapping` converts them to SI once, when the file is read (so ``--set``
overrides, a fit's parameters and a sweep's values, applied after, are SI as their names say). The fields affected
follow from the declarations, never from a list here. Bounds are the SI ones, checked here on the converted value
so that a refusal shows the value as written, in its field unit, and the accepted range in that unit too.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
import types
import typing
from typing import Any

from . import field_units
from .config_scalar import _parse_scalar
from .errors import ConfigError, short_repr


def _inner(tp: Any) -> Any:
    """``T`` of an optional ``T | None``; any other type as it is."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return args[0] if len(args) == 1 else tp
    return tp


@functools.cache
def declared_units() -> dict[str, tuple[str, ...]]:
    """Declared unit -> the float fields declaring it (``rod.tapers[i].length_m``), walked from WellConfig."""
    from .config_sections import WellConfig

    out: dict[str, list[str]] = {}

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            tp, key = _inner(hints[f.name]), prefix + f.name
            if dataclasses.is_dataclass(tp):
                walk(tp, key + ".")
            elif typing.get_origin(tp) is tuple:
                walk(typing.get_args(tp)[0], key + "[i].")
            elif tp is float and "unit" in f.metadata:
                out.setdefault(f.metadata["unit"], []).append(key)

    walk(WellConfig, "")
    return {u: tuple(keys) for u, keys in out.items()}


@functools.cache
def unit_keys() -> dict[str, tuple[str, ...]]:
    """The keys a ``units:`` block accepts: each declared SI unit that has field units (``field_units.UNITS``)
    -> the units it may be written in. Dimensionless fields (``-``, ``%``) are not converted: a fraction, a
    coefficient and a percentage share no one field unit."""
    out = {}
    for unit in declared_units():
        dim = field_units.UNITS.get(unit, ("-", 1.0))[0]
        if dim != "-":
            out[unit] = tuple(u for u, (d, _) in field_units.UNITS.items() if d == dim)
    return out


def _read_block(block: Any) -> dict[str, tuple[str, float]]:
    """``units:`` -> {declared unit: (field unit, factor field unit -> declared unit)}; each bad entry refused."""
    keys = unit_keys()
    if not isinstance(block, dict):
        raise ConfigError("units", block, "a mapping {declared SI unit: field unit}, e.g. {m: ft, mm: in, Pa: psi, "
                          "N: lbf} (docs/config.md, 'Field units')")
    out = {}
    for key, unit in block.items():
        if key not in keys:
            if isinstance(key, str) and key in field_units.UNITS and field_units.UNITS[key][0] != "-":
                raise ConfigError(f"units.{key}", unit, f"a key some field uses (no field is declared in {key}): "
                                  "one of the declared SI units " + ", ".join(keys))
            near = [k for k in keys if isinstance(key, str) and k.lower().replace("^", "") == key.lower()
                    .replace("_per_", "/").replace("^", "").replace("_", "/")]
            raise ConfigError(f"units.{key}", unit, "a declared SI unit with field units as key: one of " + ", ".join(keys)
                              + (f" (did you mean {near[0]}?)" if near else ""))
        if not isinstance(unit, str) or unit not in field_units.UNITS:
            raise ConfigError(f"units.{key}", unit, f"a unit of {key}: one of " + ", ".join(keys[key]))
        if unit not in keys[key]:
            raise ConfigError(f"units.{key}", unit, f"a unit of the same quantity as {key} (this one measures "
                              f"{field_units.UNITS[unit][0]}): one of " + ", ".join(keys[key]))
        out[key] = (unit, field_units.factor(unit) / field_units.factor(key))
    return out


def si_mapping(data: dict) -> dict:
    """A raw config mapping with its ``units:`` block applied: the numbers in SI, the block gone (a copy; the
    mapping itself when it has no block)."""
    if "units" not in data:
        return data
    from .config_sections import WellConfig

    units = _read_block(data["units"])
    return _convert(WellConfig, {k: v for k, v in data.items() if k != "units"}, "", units, _number)


def field_mapping(data: dict, units: dict[str, str]) -> dict:
    """The inverse: an SI config mapping written in the field units ``units`` (a ``units:`` block), with that
    block. ``si_mapping(field_mapping(d, u))`` is ``d`` to rounding (a few ulp)."""
    from .config_sections import WellConfig

    block = _read_block(units)

    def number(value: Any, where: str, meta: Any, _: dict) -> Any:
        ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
        return field_units.convert(value, meta["unit"], block[meta["unit"]][0]) if ok else value

    return {"units": dict(units), **_convert(WellConfig, data, "", block, number)}


def _convert(cls: type, raw: dict, path: str, units: dict, number: typing.Callable) -> dict:
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    out = dict(raw)
    for name, value in raw.items():
        if name not in fields:
            continue  # the parse names an unknown field
        tp, where = _inner(hints[name]), f"{path}.{name}" if path else str(name)
        if dataclasses.is_dataclass(tp) and isinstance(value, dict):
            out[name] = _convert(tp, value, where, units, number)
        elif typing.get_origin(tp) is tuple and isinstance(value, list):
            item = typing.get_args(tp)[0]
            out[name] = [_convert(item, v, f"{where}[{i}]", units, number) if isinstance(v, dict) else v
                         for i, v in enumerate(value)]
        elif tp is float and fields[name].metadata.get("unit") in units:
            out[name] = number(value, where, fields[name].metadata, units)
    return out


def _number(value: Any, where: str, meta: Any, units: dict) -> Any:
    """One number in its field unit -> its declared unit, refused with the value as written if outside the
    field's SI range. Anything not a number is left to the parse (which names it as it is)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return value
    unit, ratio = units[meta["unit"]]
    try:
        si = field_units.convert(value, unit, meta["unit"])
        if not math.isfinite(si):
            raise OverflowError
        return _parse_scalar(float, si, where, dict(meta))
    except (ConfigError, OverflowError) as ex:
        expected = ex.expected if isinstance(ex, ConfigError) else "a finite number"
        shown = short_repr(value if isinstance(value, int) else float(value))  # a 5000-digit int: its size
        raise ConfigError(where, f"{shown} {unit}", f"{expected}; in {unit}: {_range_in(meta, ratio, unit)} "
                          f"(units.{meta['unit']}: {unit})") from None


def _range_in(meta: Any, ratio: float, unit: str) -> str:
    """The field's accepted range in the file's unit, as 'a number within [lo, hi] ft'."""
    lo_check = {"positive": ("(", 0.0), "nonneg": ("[", 0.0)}.get(meta.get("check", "any"), ("(", -math.inf))
    lo_br, lo = ("[", float(meta["lo"])) if "lo" in meta else lo_check
    hi_br, hi = ("]", float(meta["hi"])) if "hi" in meta else (")", math.inf)
    return f"a number within {lo_br}{lo / ratio:.6g}, {hi / ratio:.6g}{hi_br} {unit}"


def units_doc() -> str:
    """Markdown table of the ``units:`` keys: each declared SI unit, the units it may be written in, its fields."""
    lines = ["| key (declared unit) | may be written in | fields |", "|---|---|---|"]
    for key, allowed in unit_keys().items():
        fields = declared_units()[key]
        lines.append(f"| `{key}` | {', '.join(allowed)} | {len(fields)}: "
                     + ", ".join(f"`{f}`" for f in fields) + " |")
    return "\n".join(lines)
