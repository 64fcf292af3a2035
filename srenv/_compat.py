"""Deprecated import paths of the flat layout (before the packages: README and docs/scale.md, "Layout").

``srenv`` was one flat package; its modules now live in subpackages named for what they hold (``srenv.physics``,
``srenv.numerics``, ...). Every old dotted name keeps working, as an alias: ``import srenv.simulator`` returns the
very module object ``srenv.simulation.simulator`` (same classes, same globals: monkeypatching either name patches
both), ``from srenv.metrics import card_metrics`` and ``python -m srenv.cli`` work as before. The aliases are
deprecated: new code imports the new paths; they stay until a major version.

One meta-path finder does it (installed by ``srenv/__init__.py``): asked for an old name, it imports the new
module and puts that very object in ``sys.modules`` under the old name too. Nothing is imported before it is asked
for, so ``import srenv`` stays light.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import types

# package -> the modules (and the subpackage laws) that moved into it, by their old names under srenv
MOVED: dict[str, tuple[str, ...]] = {
    "physics": ("rod", "pump", "fluid", "survey", "inflow", "laws"),
    "surface_unit": ("beam_unit", "gearbox", "surface", "unit_catalogue", "measured_motion"),
    "numerics": ("kernel", "kernel_layout", "step_qp", "active_set", "convexity"),
    "simulation": ("simulator", "pump_cycle", "run_result", "hopf"),
    "analysis": ("metrics", "stick_metrics", "trace_arrays", "stroke_summary", "stroke_pass", "pump_card",
                 "card_features", "diagnose", "fit", "render"),
    "task": ("well_family", "interval", "economics", "reward"),
    "tools": ("cli", "sweep", "sweep_cases", "sweep_runners", "bench", "action_sweep"),
}
# old dotted name -> new dotted name (the subpackage's own modules, srenv.laws.*, are mapped by prefix)
ALIASES: dict[str, str] = {f"srenv.{m}": f"srenv.{pkg}.{m}" for pkg, mods in MOVED.items() for m in mods}


def new_name(old: str) -> str | None:
    """The current dotted name of a deprecated one, or None if `old` is not an alias."""
    head, dot, tail = old.partition(".")
    if head != "srenv" or not dot:
        return None
    first, dot2, rest = tail.partition(".")
    new = ALIASES.get(f"srenv.{first}")
    if new is None:
        return None
    return f"{new}.{rest}" if dot2 else new


class _AliasLoader(importlib.abc.Loader):
    """Loads an old name as the new module: the very object, registered under both names."""

    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        # a placeholder: the import system stamps its attributes (__spec__, ...) on it, never on the real module
        return types.ModuleType(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        # the import system returns whatever sys.modules holds under the name after exec_module
        sys.modules[module.__name__] = importlib.import_module(self.new)

    def get_code(self, fullname: str) -> types.CodeType:
        # `python -m srenv.cli`: run the new module as __main__ (its relative imports need its own package)
        return compile(f"import runpy\nrunpy.run_module({self.new!r}, run_name='__main__', alter_sys=True)\n",
                       f"<srenv alias {fullname} -> {self.new}>", "exec")

    def is_package(self, fullname: str) -> bool:
        return False


class AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the deprecated flat names (:data:`ALIASES`) of srenv's modules."""

    def find_spec(self, fullname: str, path=None, target=None) -> importlib.machinery.ModuleSpec | None:
        new = new_name(fullname)
        if new is None:
            return None
        real = importlib.util.find_spec(new)
        if real is None:
            return None
        # an aliased package (srenv.laws) keeps its submodule search path, so srenv.laws.valve is found (by us)
        spec = importlib.machinery.ModuleSpec(fullname, _AliasLoader(new),
                                              is_package=real.submodule_search_locations is not None)
        if real.submodule_search_locations is not None:
            spec.submodule_search_locations = list(real.submodule_search_locations)
        return spec


def install() -> None:
    """Put the alias finder first on ``sys.meta_path`` (idempotent)."""
    if not any(isinstance(f, AliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, AliasFinder())
