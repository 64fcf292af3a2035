"""The README and docs/*.md walked as a user walks them (issue u40): every command they show names a subcommand,
module or script that exists and only flags its parser declares; the README's worked examples parse whole,
its Python snippets run, the files its commands name exist, and the quick start keeps its two commands.

A documented flag that is renamed or removed, or a script that goes, fails here; what the commands print is
checked by their own tests (tests/srenv/tools/test_cli.py, tests/agents/...). Fast: parsing, one env step each.
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.cli import build_parser as agents_parser
from srenv.tools.cli import build_parser as srenv_parser

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]
FLAG = re.compile(r"(?<![\w-])(--[a-z][a-z0-9-]*)")
UNTIL_NEXT = r"((?:(?!\bsrenv |\bpython3? ).)*)"  # a command's words, up to the next command on the line
INSTALL = 'python3 -m venv .venv && . .venv/bin/activate && pip install torch==2.13.0 && pip install -e ".[{}]"'
QUICK_START = (INSTALL.format("rl") + " && python -m agents quickstart", INSTALL.format("dev") + " && pytest -q -n 2")


def _subcommand_flags(parser: argparse.ArgumentParser) -> dict[str, set[str]]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: set(p._option_string_actions) for name, p in sub.choices.items()}


SRENV, AGENTS = _subcommand_flags(srenv_parser()), _subcommand_flags(agents_parser())


def fenced_blocks(text: str, lang: str = r"[a-z]*") -> list[str]:
    return re.findall(rf"^ *```{lang}\n(.*?)^ *```", text, re.DOTALL | re.MULTILINE)


def commands(text: str) -> list[str]:
    """Every command a user would copy: a fenced block's lines (indented continuation lines joined, comments
    cut), and every inline code span that starts with ``srenv``/``python`` (or ``nice``/``VAR=`` before them)."""
    start = re.compile(r"(\S+=\S+ )?(nice -n \d+ )?(srenv|python3?) ")
    out: list[str] = []
    for block in fenced_blocks(text):
        cur = None
        for line in block.splitlines():
            body = re.split(r"\s#\s|^\s*#", line)[0]
            if start.match(body):
                out += [cur] if cur else []
                cur = body
            elif cur is not None and line.startswith(" ") and body.strip():
                cur += " " + body.strip()
            else:
                out += [cur] if cur else []
                cur = None
        out += [cur] if cur else []
    prose = re.sub(r"^ *```.*?^ *```", "", text, flags=re.DOTALL | re.MULTILINE)
    return out + [s for s in re.findall(r"`([^`\n]+)`", prose) if start.match(s)]


def documented() -> list[tuple[str, str]]:
    return [(f.relative_to(ROOT).as_posix(), c) for f in DOCS for c in commands(f.read_text())]


def unknown_flags(doc: str, cmd: str) -> list[str]:
    """What in one documented command does not exist: a subcommand, module, script or one of their flags."""
    bad = []
    for tool, table, pattern in (("srenv", SRENV, r"(?:^|[\s;(&])srenv "), ("agents", AGENTS, r"python3? -m agents ")):
        for m in re.finditer(pattern + r"([a-z][a-z-]*)" + UNTIL_NEXT, cmd):
            # "a | b --x | c": the synopsis' alternatives, each a subcommand of its own
            for alt in re.split(r"\s\|\s(?=[a-z][a-z-]* )", m.group(1) + m.group(2)):
                sub, _, rest = alt.partition(" ")
                if sub not in table:
                    bad.append(f"{tool} {sub}: no such subcommand")
                bad += [f"{tool} {sub} {f}" for f in FLAG.findall(rest) if sub in table and f not in table[sub]]
    for m in re.finditer(r"python3? (?:-W \S+ )?(?:-m ((?:srenv|agents)\.[\w.]+)|(scripts/\w+\.py))" + UNTIL_NEXT, cmd):
        module, script, rest = m.groups()
        path = ROOT / (script or module.replace(".", "/") + ".py")
        if not path.exists():
            bad.append(f"{path.relative_to(ROOT)}: no such file")
            continue
        source = path.read_text()  # a script's parser is built in its main(): its flags are its literals
        bad += [f"{path.name} {f}" for f in FLAG.findall(rest) if f'"{f}"' not in source and f != "--help"]
    return [f"{doc}: {b}   <- {cmd.strip()[:100]}" for b in bad]


def test_the_walk_finds_the_commands():
    """The extraction itself: the README's synopsis, examples and RLlib block, and the docs' inline commands."""
    found = documented()
    readme = [c for d, c in found if d == "README.md"]
    assert len(readme) >= 25 and len(found) >= 150
    for needle in ("srenv simulate CONFIG", "srenv sweep paper_fig7_pullout", "python -m agents replay",
                   "python -m rl_zoo3.train", "python scripts/reward_sweep.py"):
        assert any(c.startswith(needle) for c in readme), needle
    assert unknown_flags("x", "srenv sweep C --executor ray") == ["x: srenv sweep --executor   <- srenv sweep C --executor ray"]
    assert unknown_flags("x", "python scripts/no.py --a") == ["x: scripts/no.py: no such file   <- python scripts/no.py --a"]


def test_every_documented_command_and_flag_exists():
    bad = [b for doc, cmd in documented() for b in unknown_flags(doc, cmd)]
    assert not bad, "\n".join(bad)


def test_quick_start_keeps_its_two_commands():
    blocks = [b.strip() for b in fenced_blocks(README, "bash")]
    assert blocks[0] == QUICK_START[0] and blocks[1] == QUICK_START[1]


def _examples() -> list[str]:
    block = next(b for b in fenced_blocks(README, "bash") if "srenv sweep paper_fig7_pullout" in b)
    return [c for c in commands(f"```bash\n{block}```\n")]


@pytest.mark.parametrize("cmd", [c for c in _examples() if c.startswith("srenv ")])
def test_readme_srenv_examples_parse(cmd: str):
    args = srenv_parser().parse_args(cmd.replace("\\", " ").split()[1:])
    assert args.command == cmd.split()[1]


def test_readme_files_named_in_commands_exist():
    names = {n for _, c in documented() for n in re.findall(r"(?<![\w/.])((?:configs|docs|models|tests/data)/[\w./-]+\.\w+)", c)
             if "*" not in n}
    names |= set(re.findall(r"\]\(((?:docs|srenv)/[\w./-]+\.(?:md|py))", README))
    missing = sorted(n for n in names if not (ROOT / n).exists() and not n.startswith("docs/figures/"))
    assert not missing, missing


@pytest.mark.parametrize("snippet", [b for b in fenced_blocks(README, "python")], ids=["v1", "v0"])
def test_readme_python_snippets_run(snippet: str, tmp_path: Path):
    code = tmp_path / "snippet.py"
    code.write_text(snippet)
    scope = runpy.run_path(str(code))  # the README's own code: one reset and one step
    env, obs, info, reward = scope["env"], scope["obs"], scope["info"], scope["reward"]
    assert env.observation_space.contains(obs) and np.isfinite(reward)
    if "SuckerRod-v1" in snippet:  # "info['well_id'] == 'train-000'" after reset; the constraint cost in info
        assert env.unwrapped.well.well_id == "train-000" and info["cost"] >= 0.0
    else:  # "Observation (72 float32)", the reward terms "summing to the reward"
        terms = ("reward_production", "reward_stick_slip", "reward_peak_load", "reward_failure")
        assert obs.shape == (72,) and sum(info[k] for k in terms) == pytest.approx(reward, abs=1e-9)
    env.close()


def test_readme_one_liner_and_script_help():
    cmd = next(c for c in _examples() if c.startswith("python -c"))
    code = re.search(r'-c "(.*)"', cmd).group(1)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT,
                         check=False)
    assert out.returncode == 0 and out.stdout.strip() == "train-000", out.stderr[-2000:]
    script = next(c for c in _examples() if c.startswith("python scripts/")).split()[1]
    out = subprocess.run([sys.executable, script, "--help"], capture_output=True, text=True, timeout=120, cwd=ROOT,
                         check=False)
    assert out.returncode == 0 and out.stdout.startswith("usage:"), out.stderr[-2000:]


def _table_numbers(text: str) -> list[list[float]]:
    rows = [r for r in text.splitlines() if r.startswith("| paper_")]
    return [[float(x) for x in re.findall(r"[-+]?\d+\.\d+", r)] for r in rows]


def test_convergence_doc_table_is_what_its_command_prints():
    """docs/convergence.md's table, reproduced by the command it names (a few seconds), to its last digit."""
    doc = (ROOT / "docs" / "convergence.md").read_text()
    assert "Reproduce: `python scripts/convergence.py`" in doc
    out = subprocess.run([sys.executable, "scripts/convergence.py"], capture_output=True, text=True, timeout=300,
                         cwd=ROOT, check=False)
    assert out.returncode == 0, out.stderr[-2000:]
    printed, documented_rows = _table_numbers(out.stdout), _table_numbers(doc)
    assert len(printed) == len(documented_rows) == 8
    assert np.allclose(printed, documented_rows, rtol=0, atol=0.011), (printed, documented_rows)


def _numbers(text: str) -> list[float]:
    """The numbers of a text, not the digits of a name (f1, zeta1, m3/d)."""
    return [float(x) for x in re.findall(r"(?<![A-Za-z\d.])[-+]?\d+(?:\.\d+)?", text.replace("−", "-"))]


def _task_table(header: str) -> dict[str, list[float]]:
    lines = (ROOT / "docs" / "task.md").read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(header))
    rows = {}
    for line in lines[i + 2:]:
        if not line.startswith("| train-"):
            break
        well, *cells = [c.strip() for c in line.strip("|").split("|")]
        rows[well] = _numbers(" ".join(cells))
    return rows


def _printed(*args: str) -> dict[str, list[float]]:
    out = subprocess.run([sys.executable, "scripts/v2_physics_figures.py", *args], capture_output=True, text=True,
                         timeout=300, cwd=ROOT, check=False)
    assert out.returncode == 0, out.stderr[-2000:]
    return {line.split()[0]: _numbers(line.split(maxsplit=1)[1]) for line in out.stdout.splitlines()}


def test_task_doc_v2_physics_tables_are_what_their_commands_print():
    """docs/task.md's two v2-physics tables against the commands they name, to one unit of their last digit."""
    text = (ROOT / "docs" / "task.md").read_text()
    damping, episodes = (re.search(rf"`python scripts/v2_physics_figures.py ({m} [\d ]+)`", text).group(1).split()
                         for m in ("damping", "episodes"))
    doc, out = _task_table("| well | depth | f₁ |"), _printed(*damping)
    assert list(doc) == list(out)
    for w, (depth, f1, _tau, _fixed, zeta, p, m, s, _fixed_again, fp, fm, fs) in out.items():
        assert zeta > 0 and doc[w][:2] == [round(depth), f1], w
        assert np.allclose(doc[w][2:], [p, fp, m, fm, s, fs], rtol=0, atol=0.051), (w, doc[w], out[w])
    doc, out = _task_table("| well | unit | production |"), _printed(*episodes)
    assert list(doc) == list(out)
    for w, (_prod, p1, p2, _pprl, l1, l2, r0, r1, r2, g) in out.items():
        assert np.allclose(doc[w], [p1, p2, l1, l2, r0, r1, r2, g], rtol=0, atol=0.11), (w, doc[w], out[w])


def test_agents_usage_names_the_command_that_runs_it():
    """A checkout's usage says `python -m agents`; the installed copy (`srenv_agents`, command `srenv-agents`, which
    has no `agents` package to run with -m) says `srenv-agents`."""
    assert agents_parser().prog == "python -m agents"
    if importlib.util.find_spec("srenv_agents") is None:  # a bare PYTHONPATH checkout: nothing installed
        pytest.skip("srenv_agents is not installed")
    out = subprocess.run([sys.executable, "-c", "import srenv_agents.cli as c; print(c.build_parser().prog)"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT.parent, check=False)
    assert out.returncode == 0 and out.stdout.strip() == "srenv-agents", out.stderr[-2000:]
