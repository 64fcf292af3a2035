"""The repository's layout (docs/scale.md, "Layout"), across ``srenv/`` and ``agents/``: no import cycles between
modules or packages, no module over 400 lines, no function over 80 (numba-jitted kernels excepted), the old flat
names gone, entry points that resolve."""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

import srenv

SRENV = Path(srenv.__file__).parent
REPO = SRENV.parent
PACKAGES = ("srenv", "agents")  # every package of the repository (tests and scripts are not modules)
MAX_LINES = 400
MAX_FUNCTION_LINES = 80


def _modules() -> dict[str, Path]:
    out = {}
    for path in (p for top in PACKAGES for p in (REPO / top).rglob("*.py")):
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
    """<top>.<package> for a module of a subpackage, the module itself at the top level."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 2 or (REPO.joinpath(*parts)).is_dir() and len(parts) == 2 else module


def test_no_import_cycles_between_modules_or_packages() -> None:
    modules = _modules()
    graph = {m: _imports(m, p, modules) for m, p in modules.items()}
    assert _cycles(graph) == []
    # a top package itself (its __init__) is every module's parent: it is left out of the package graph
    packages: dict[str, set[str]] = {}
    for m, deps in graph.items():
        if m not in PACKAGES:
            packages.setdefault(_package(m), set()).update(_package(d) for d in deps if d not in PACKAGES)
    for p, deps in packages.items():
        deps.discard(p)
    assert _cycles(packages) == []
    assert "srenv.physics" not in packages["srenv.numerics"] or "srenv.numerics" not in packages["srenv.physics"]
    # the agents' layers: policies below evaluation below training below benchmark, srenv never above
    order = ["agents.envs", "agents.policies", "agents.evaluation", "agents.training", "agents.benchmark"]
    for low, high in ((a, b) for i, a in enumerate(order) for b in order[i + 1:]):
        assert high not in packages[low], f"{low} imports {high}"
    assert not any(d.startswith("agents") for p, deps in packages.items() if p.startswith("srenv") for d in deps)


def test_no_module_over_400_lines() -> None:
    long = {m: n for m, p in _modules().items() if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert long == {}


def test_no_function_over_80_lines() -> None:
    """A compiled numba kernel may stay whole (splitting it costs speed); every other function is short."""
    long = {}
    for m, p in _modules().items():
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES and not any("jit" in ast.unparse(d) for d in node.decorator_list):
                    long[f"{m}.{node.name}"] = n
    assert long == {}


def test_the_flat_names_are_gone() -> None:
    """0.2.0 removed the silent aliases of the flat layout: an old name is not importable, a new one is."""
    for old in ("srenv.simulator", "srenv.metrics", "srenv.cli", "srenv.laws", "srenv.rllib"):
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(old)
    assert importlib.import_module("srenv.physics.laws.valve").__name__ == "srenv.physics.laws.valve"


def test_entry_points_resolve() -> None:
    text = (REPO / "pyproject.toml").read_text()
    script = re.search(r'^srenv = "([\w.]+):(\w+)"', text, re.MULTILINE)
    module, func = script.groups()
    assert callable(getattr(importlib.import_module(module), func))
    # the wheel installs agents/ as srenv_agents: its entry point names the same module under that name
    agents_script = re.search(r'^srenv-agents = "srenv_agents\.([\w.]+):(\w+)"', text, re.MULTILINE)
    assert callable(getattr(importlib.import_module("agents." + agents_script.group(1)), agents_script.group(2)))
    for argv in (["srenv.tools.cli", "--help"], ["agents", "--help"]):
        p = subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True, timeout=120, cwd=REPO,
                           check=False)
        assert p.returncode == 0 and "usage" in p.stdout, p.stderr
        assert "Warning" not in p.stderr


def _writes_into_the_simulator(tree: ast.AST) -> list[str]:
    """Assignments whose target reaches into a simulator or its annulus (``sim.x = ``, ``self.sim.annulus.y += ``,
    ``ann.volume_m3 -= ``): the object is named sim / annulus / ann somewhere in the target's chain."""
    out = []
    for node in ast.walk(tree):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, (ast.AugAssign, ast.AnnAssign)) else []
        for t in targets:
            if not isinstance(t, (ast.Attribute, ast.Subscript)):
                continue
            chain, x = [], t.value
            while isinstance(x, (ast.Attribute, ast.Subscript)):
                if isinstance(x, ast.Attribute):
                    chain.append(x.attr)
                x = x.value
            if isinstance(x, ast.Name):
                chain.append(x.id)
            if {"sim", "annulus", "ann"} & set(chain):
                out.append(f"line {node.lineno}: {ast.unparse(t)}")
    return out


def test_the_simulator_state_changes_only_through_its_own_methods() -> None:
    """Outside srenv/simulation and the annulus' own module, code calls the simulator's methods
    (set_inflow_multiplier, return_liquid, fast_forward, switch_config, idle, ...) instead of writing its fields."""
    own = (SRENV / "simulation", SRENV / "physics" / "inflow.py")
    found = {m: w for m, p in _modules().items() if not any(p == o or o in p.parents for o in own)
             if (w := _writes_into_the_simulator(ast.parse(p.read_text())))}
    assert found == {}
    # the check sees a write: the form the interval runner used before
    assert _writes_into_the_simulator(ast.parse("ann.volume_m3 -= take\nsim.time_s = t")) == [
        "line 1: ann.volume_m3", "line 2: sim.time_s"]
