"""The cases of issue 28 (hardening, second round), run as a user would, each in a subprocess under a 3 GiB
address-space limit and a 120 s timeout; prints the markdown table of docs/reliability.md §6.

    python scripts/hardening2_cases.py            # from the project root; ~3 min on one core

A case passes when it ends with exit 2 (130 for an interruption), one stderr line, no traceback, and
leaves nothing behind (a symlink's target untouched). Cases that need the card-content checks of the
realism branch are marked as such.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
SRENV = [PY, "-m", "srenv.cli"]
AGENTS = [PY, "-m", "agents"]
FIG3 = "paper_fig3_vertical"
LIMIT = 3 * 2**30


def card(path: Path, n: int = 200, period: float = 10.0, pos=None, load=None, t=None) -> None:
    tt = np.arange(n) * period / n if t is None else t
    x = 1.2 * (1 - np.cos(2 * np.pi * tt / period)) if pos is None else pos
    f = 40e3 + 8e3 * np.sin(2 * np.pi * tt / period) if load is None else load
    np.savetxt(path, np.c_[tt, x, f], delimiter=",", header="t_s,polished_rod_position_m,polished_rod_load_n",
               comments="")


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def run(argv: list[str], d: Path, sigint_after: float | None = None) -> tuple[object, str, float]:
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=_limit, start_new_session=True,  # noqa: PLW1509 (no threads here)
                         env={**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)})
    try:
        if sigint_after is not None:
            time.sleep(sigint_after)
            os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
        rc: object = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        _, err = p.communicate()
        rc = "timeout"
    return rc, err, time.perf_counter() - t0


def main() -> int:
    base = Path(tempfile.mkdtemp())
    rows = []
    bad_rep = json.loads((ROOT / "docs" / "benchmark.json").read_text())

    def case(name: str, argv: list[str], setup=None, code: int = 2, sigint_after: float | None = None,
             realism: bool = False) -> None:
        d = base / f"c{len(rows)}"
        d.mkdir()
        card(d / "card.csv")
        if setup:
            setup(d)
        before = {p.name: p.read_bytes() if p.is_file() else None for p in d.iterdir()}
        rc, err, wall = run([a.replace("{d}", str(d)) for a in argv], d, sigint_after)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        left = sorted({p.name for p in d.iterdir()} - set(before) - {"o"})
        changed = [n for n, b in before.items() if b is not None and (d / n).is_file() and (d / n).read_bytes() != b]
        ok = rc == code and len(lines) == 1 and "Traceback" not in err and not left and not changed
        what = (lines[-1] if lines else "").replace(str(d) + "/", "").replace("|", "/")[:150]
        status = "pass" if ok else ("fails: card checks (realism branch)" if realism else "FAIL")
        extra = (f"; left {left}" if left else "") + (f"; changed {changed}" if changed else "")
        rows.append(f"| {name} | {rc} | {wall:.1f} | `{what}`{extra} | {status} |")
        print(rows[-1], flush=True)

    dg = [*SRENV, "diagnose", "{d}/card.csv", "--config", FIG3, "--out", "{d}/p.csv"]
    fit = [*SRENV, "fit", "{d}/card.csv", "--config", FIG3, "--param", "damping.damping_factor", "--out", "{d}/f.yaml"]
    long_card = lambda d: card(d / "card.csv", n=20, period=1e5)
    meas = ["--set", "surface.motion=measured", "--set", "surface.measured_card_csv={d}/card.csv"]
    # flags
    case("diagnose --harmonics 999999999999999999", [*dg, "--harmonics", "999999999999999999"])
    case("diagnose --harmonics 50000000", [*dg, "--harmonics", "50000000"])
    case("diagnose --spm 1e300", [*dg, "--spm", "1e300"])
    case("fit --strokes 100000", [*fit, "--strokes", "100000"])
    case("diagnose, 20-sample card spanning 1e5 s", dg, setup=long_card, realism=True)
    # a measured card's own period
    case("simulate --strokes 1, measured 20-row card of 1e5 s", [*SRENV, "simulate", FIG3, *meas, "--strokes", "1",
                                                              "--out", "{d}/s.csv"], setup=long_card)
    case("simulate, surface.measured_spm = 1e-3", [*SRENV, "simulate", FIG3, *meas, "--set",
                                                   "surface.measured_spm=0.001", "--strokes", "1", "--out", "{d}/s.csv"])
    case("fit --param surface.measured_spm", [*SRENV, "fit", "{d}/card.csv", "--config", FIG3, "--param",
                                              "surface.measured_spm", "--strokes", "1", "--out", "{d}/f.yaml"])
    # degenerate cards
    t = np.arange(200) * 10.0 / 200
    case("diagnose, card not closed", dg, setup=lambda d: card(d / "card.csv", pos=t * 0.2), realism=True)
    case("diagnose, zero stroke", dg, setup=lambda d: card(d / "card.csv", pos=np.full(200, 1.0)), realism=True)
    case("diagnose, loads 1e300", dg, setup=lambda d: card(d / "card.csv", load=np.full(200, 1e300)), realism=True)
    case("diagnose, positions 1e300", dg, setup=lambda d: card(d / "card.csv", pos=1e300 * (1 - np.cos(t))),
         realism=True)
    case("diagnose, time spacing 1e298", dg, setup=lambda d: card(d / "card.csv", t=np.arange(200) * 1e298,
                                                                 period=2e300), realism=True)
    case("fit, all-zero loads", fit, setup=lambda d: card(d / "card.csv", load=np.zeros(200)))
    # outputs
    case("diagnose --plot pump.xyz", [*dg, "--plot", "{d}/pump.xyz"])
    case("diagnose --out pump.txt", [*SRENV, "diagnose", "{d}/card.csv", "--config", FIG3, "--out", "{d}/pump.txt"])
    case("simulate --out x.csv --plot x.csv (same file)", [*SRENV, "simulate", FIG3, "--strokes", "1", "--out",
                                                          "{d}/x.csv", "--plot", "{d}/x.csv"])

    def sym(d: Path, name: str = "link.png") -> None:
        (d / "target.png").write_bytes(b"keep me")
        os.symlink(d / "target.png", d / name)
    case("agents evaluate --plot onto a symlink", [*AGENTS, "evaluate", "--policy", "rocking", "--episodes", "1",
                                                   "--plot", "{d}/link.png"], setup=sym)
    case("diagnose --plot onto a directory", [*dg, "--plot", "{d}/dir.png"], setup=lambda d: (d / "dir.png").mkdir())
    case("SIGINT during simulate --plot (all or nothing)", [*SRENV, "simulate", FIG3, "--strokes", "200", "--out",
                                                            "{d}/s.csv", "--plot", "{d}/s.png"], code=130,
         sigint_after=8.0)
    case("SIGINT in agents replay", [*AGENTS, "replay", "docs/benchmark.json", "--policy", "pump_off", "--episodes",
                                     "3"], code=130, sigint_after=12.0)
    # strict JSON
    case("fit --param economics.oil_price_usd_m3", [*SRENV, "fit", "{d}/card.csv", "--config", FIG3, "--param",
                                                    "economics.oil_price_usd_m3", "--strokes", "1", "--out", "{d}/f.yaml"])

    # agents files
    def report(mutate):
        def setup(d: Path) -> None:
            rep = json.loads(json.dumps(bad_rep))
            mutate(rep)
            (d / "rep.json").write_text(json.dumps(rep))
        return setup

    def each(rep, fn):
        for p in rep["policies"].values():
            for i, e in enumerate(p.get("episodes", [])):
                p["episodes"][i] = fn(e)
    rp = [*AGENTS, "replay", "{d}/rep.json", "--policy", "pump_off", "--episodes", "1"]
    case("replay: episodes without reward", rp, setup=report(lambda r: each(r, lambda e: {"seed": e["seed"]})))
    case("replay: episodes not mappings", rp, setup=report(lambda r: each(r, lambda e: 1)))
    case("replay: baseline params of the wrong type", rp,
         setup=report(lambda r: r["policies"]["pump_off"].__setitem__("params", {"threshold": "high"})))
    case("replay: env kwargs 8760 h at 10 s", rp, setup=report(lambda r: r["env_kwargs"].update(
        {"episode_hours": 8760, "interval_s": 10})))
    py = [PY, "-c"]
    npz = "from agents.rollout_v1 import ObsNormalizer as O; import sys; O.load(sys.argv[2])"
    wrap = ("import sys\nfrom srenv.errors import ConfigError\ntry:\n    exec(sys.argv[1])\nexcept (ConfigError, "
            "ValueError) as e:\n    print('error:', e, file=sys.stderr); sys.exit(2)\n")
    case("obs-norm npz without keys", [*py, wrap, npz, "{d}/n.npz"],
         setup=lambda d: np.savez(d / "n.npz", mean=np.zeros(3)))
    case("obs-norm npz truncated", [*py, wrap, npz, "{d}/n.npz"],
         setup=lambda d: (np.savez(d / "n.npz", mean=np.zeros(3), var=np.ones(3), clip_obs=10.0, epsilon=1e-8),
                          (d / "n.npz").write_bytes((d / "n.npz").read_bytes()[:120])))
    shp = "from agents.model_io import space_shape; space_shape({'observation_space': {'_shape': [10**9]}}, 'observation_space', 'm.zip')"
    case("model zip observation shape 1e9", [*py, wrap, shp])
    arch = ("from agents.model_io import policy_kwargs; "
            "policy_kwargs({'policy_kwargs': {'net_arch': '[200000, 200000]'}}, 'm.zip')")
    case("model zip net_arch [200000, 200000]", [*py, wrap, arch])
    rl = "from agents.inputs import policy_json; policy_json([1, 2], 'srenv_policy.json')"
    case("RLlib srenv_policy.json a list", [*py, wrap, rl])

    def bench(text: str):
        def setup(d: Path) -> None:
            src = (ROOT / "configs" / "benchmark" / "v1_quick.yaml").read_text()
            (d / "b.yaml").write_text(src + text)
        return setup
    bm = [*AGENTS, "benchmark", "{d}/b.yaml", "--quick", "--out-dir", "{d}/o"]
    bomb = "".join(f"x{i}: &x{i} [{', '.join([f'*x{i - 1}' if i else 'lol'] * 10)}]\n" for i in range(8))
    case("benchmark YAML: alias bomb", bm, setup=bench("bomb:\n" + "".join("  " + ln + "\n" for ln in
                                                                           bomb.splitlines())))
    case("benchmark YAML: duplicate key", bm, setup=bench("workers: 3\n"))
    case("benchmark YAML: syntax error", bm, setup=lambda d: (d / "b.yaml").write_text("env_id: x\n  bad: [\n"))
    case("benchmark YAML: seeds {count: 10^9}", bm, setup=lambda d: (d / "b.yaml").write_text(
        (ROOT / "configs" / "benchmark" / "v1_quick.yaml").read_text().replace("{start: 100000, count: 6}",
                                                                               "{start: 100000, count: 1000000000}")))
    case("benchmark YAML: workers 1000000", bm, setup=lambda d: (d / "b.yaml").write_text(
        (ROOT / "configs" / "benchmark" / "v1_quick.yaml").read_text().replace("workers: 2", "workers: 1000000")))
    case("benchmark YAML: n_timesteps 1e30", bm, setup=lambda d: (d / "b.yaml").write_text(
        (ROOT / "configs" / "benchmark" / "v1_quick.yaml").read_text().replace("n_timesteps: 3072",
                                                                               "n_timesteps: 1.0e+30")))
    # env kwargs and actions
    env = ("import gymnasium as gym, srenv\n"
           "e = gym.make('srenv/SuckerRod-v1', {kw})\n")
    case("env overrides a string", [*py, wrap, env.format(kw="overrides='task.interval_s=600'")])
    case("env overrides with non-string keys", [*py, wrap, env.format(kw="overrides={1: 2}")])
    act = ("import gymnasium as gym, srenv\ne = gym.make('srenv/SuckerRod-v0'); e.reset(seed=0); "
           "e.step({'spm': 1})\n")
    case("env action a mapping", [*py, wrap, act])
    case("env card_points=0", [*py, wrap, "import gymnasium as gym, srenv\ngym.make('srenv/SuckerRod-v0', card_points=0)"])
    # first-round classes
    case("--set surface.spm=010 (octal)", [*SRENV, "simulate", FIG3, "--set", "surface.spm=010", "--strokes", "1",
                                           "--out", "{d}/s.csv"])
    case("--stroke-length-m with a conventional unit", [*SRENV, "simulate", "conventional_fig4", "--stroke-length-m",
                                                        "2", "--strokes", "1", "--out", "{d}/s.csv"])
    case("simulate --out onto a symlink", [*SRENV, "simulate", FIG3, "--strokes", "1", "--out", "{d}/link.csv"],
         setup=lambda d: sym(d, "link.csv"))
    shutil.rmtree(base, ignore_errors=True)
    fails = [r for r in rows if r.endswith("FAIL |")]
    print(f"{len(rows) - len(fails)}/{len(rows)} pass or wait only for the realism branch's card checks")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
