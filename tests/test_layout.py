"""The package layout (docs/scale.md, "Layout"): deprecated flat names alias the very modules, no import cycles
between modules or packages, no module over 400 lines, entry points that resolve."""

from __future__ import annotations

import ast
import importlib
import pickle
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

import srenv
from srenv._compat import ALIASES, new_name

SRENV = Path(srenv.__file__).parent
REPO = SRENV.parent
MAX_LINES = 400


@pytest.mark.parametrize("old", sorted(ALIASES))
def test_every_flat_name_is_the_moved_module(old: str) -> None:
    new = importlib.import_module(ALIASES[old])
    assert importlib.import_module(old) is new
    assert sys.modules[old] is new and new.__name__ == ALIASES[old] and new.__spec__.name == ALIASES[old]
    # `from srenv.X import Y` gives the object the new module holds
    public = [k for k, v in vars(new).items() if not k.startswith("__") and getattr(v, "__module__", None) == new.__name__]
    if hasattr(new, "__path__"):  # a package: its first module
        public = [next(pkgutil.iter_modules(new.__path__)).name]
    assert public, f"{new.__name__} defines no name"
    imported = __import__(old, fromlist=[public[0]])  # what `from {old} import {name}` executes
    assert getattr(imported, public[0]) is getattr(new, public[0])


def test_a_moved_subpackage_aliases_its_modules() -> None:
    import srenv.laws.valve as old_valve
    from srenv.laws import rod_friction

    from srenv.physics.laws import valve

    assert old_valve is valve and rod_friction is importlib.import_module("srenv.physics.laws.rod_friction")
    assert new_name("srenv.laws.gas_spring") == "srenv.physics.laws.gas_spring"
    assert new_name("srenv.config") is None and new_name("srenv.simulatorx") is None


def test_a_pickle_naming_the_old_module_loads_the_new_object() -> None:
    from srenv.analysis.pump_card import analyse_pump_card

    assert pickle.loads(b"csrenv.pump_card\nanalyse_pump_card\n.") is analyse_pump_card  # protocol 0: GLOBAL


def test_monkeypatching_the_old_name_patches_the_new_module(monkeypatch: pytest.MonkeyPatch) -> None:
    from srenv.analysis import metrics

    monkeypatch.setattr("srenv.metrics.ROD_GRADE_TENSILE_PA", {"X": 1.0})
    assert metrics.ROD_GRADE_TENSILE_PA == {"X": 1.0}


def _modules() -> dict[str, Path]:
    out = {}
    for path in SRENV.rglob("*.py"):
        parts = list(path.relative_to(REPO).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """srenv modules `name` imports anywhere in its code (functions included), TYPE_CHECKING blocks excepted."""
    tree = ast.parse(path.read_text())
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)
                   and "TYPE_CHECKING" in ast.unparse(block.test) for n in ast.walk(block)}
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in modules:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.add(t)
    return found


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _package(module: str) -> str:
    """srenv.<package> for a module of a subpackage, the module itself at the top level."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 2 or (SRENV / parts[-1]).is_dir() and len(parts) == 2 else module


def test_no_import_cycles_between_modules_or_packages() -> None:
    modules = _modules()
    graph = {m: _imports(m, p, modules) for m, p in modules.items()}
    assert _cycles(graph) == []
    # the package `srenv` itself (its __init__) is every module's parent: it is left out of the package graph
    packages: dict[str, set[str]] = {}
    for m, deps in graph.items():
        if m != "srenv":
            packages.setdefault(_package(m), set()).update(_package(d) for d in deps if d != "srenv")
    for p, deps in packages.items():
        deps.discard(p)
    assert _cycles(packages) == []
    assert "srenv.physics" not in packages["srenv.numerics"] or "srenv.numerics" not in packages["srenv.physics"]


def test_no_module_over_400_lines() -> None:
    long = {m: n for m, p in _modules().items() if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert long == {}


def test_entry_points_resolve() -> None:
    script = re.search(r'^srenv = "([\w.]+):(\w+)"', (REPO / "pyproject.toml").read_text(), re.MULTILINE)
    module, func = script.groups()
    assert callable(getattr(importlib.import_module(module), func))
    for flat in ("srenv.cli", "srenv.tools.cli"):  # python -m with the flat name too (the alias runs the new one)
        p = subprocess.run([sys.executable, "-m", flat, "--help"], capture_output=True, text=True, timeout=120,
                           cwd=REPO, check=False)
        assert p.returncode == 0 and "simulate" in p.stdout, p.stderr
        assert "RuntimeWarning" not in p.stderr
