"""Where the exact step's time goes: the kernel with one piece of its per-step work removed, timed against the
unmodified kernel and the floor program in one process, interleaved, min of N (docs/speed.md §1b).

Each variant is srenv/numerics/kernel.py with a text edit (written to a temporary module next to it and compiled
without numba's cache); its results are wrong on purpose, only its time matters. Every repeat times the base
kernel, each variant and the floor one after the other on the Fig. 4 well (unrecorded strokes); the table gives
each one's min-of-N µs per step of the compiled calls alone (``kernel.run`` timed around), of the whole
``run_stroke``, and the saving against the base:

    python scripts/kernel_ablation.py --repeats 15 --strokes 4
"""
from __future__ import annotations

import argparse
import importlib
import json
import pathlib
import subprocess
import time

import numpy as np
from numba import njit

import srenv.numerics.kernel as K
from srenv.config import load_config
from srenv.simulation.simulator import Simulator
from srenv.tools.bench_kernel import FloorRun

SRC = pathlib.Path(K.__file__)
CALL = "nc = solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, cp, dp, maxcorr, tolv,\n" \
       "                                       toll)"
# name -> [(old, new), ...]: each old text must occur in kernel.py
VARIANTS = {
    "certificate (pattern solve -> one plain Thomas solve)": [
        (CALL, "thomas_pattern(ksd, kso, b, stuck, v, cp, dp)\n                    nc = 0")],
    "bounds (laws' intervals on the first step only)": [
        ("            if nonsmooth:\n                set_bounds(", ("            if nonsmooth and k == 0:\n"
                                                       "                set_bounds(")
         )],
    "energy accumulation": [
        ("            e_grav += f[i] * du\n", ""),
        ("            e_react -= 0.5 * (li + prev_lam[i]) * du\n", ""),
        ("            e_visc += 0.5 * cd[i] * (vi + vo) * du\n", "")],
    "force envelope": [("            emax[e] = max(emax[e], ne)\n            emin[e] = min(emin[e], ne)\n", "")],
    "stick / status bookkeeping": [("        for i in range(n):\n            s = ns[i] and v[i] == 0.0\n",
                                    "        for i in range(0):\n            s = ns[i] and v[i] == 0.0\n")],
    "reactions (lam = b - K*v)": [("        for i in range(n):\n            kv = ksd[i] * v[i]\n",
                                   "        for i in range(0):\n            kv = ksd[i] * v[i]\n")],
    "events (extremes, reversal returns)": [
        ("        if events(valve_p, prog, u[n - 1], v[n - 1]):\n            return EVENT\n", "")],
    "(added) a second pattern solve per step": [
        (CALL, CALL + "\n                    nc = solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, "
         "cp, dp, maxcorr, tolv, toll)")],
    "(added) a second plain Thomas solve per step": [
        (CALL, CALL + "\n                    thomas_pattern(ksd, kso, rhs, stuck, vk, cp, dp)")],
    "counters / path": [("        if path == PATH_QP:\n            cn.qp += 1\n",
                         "        if path == 99:\n            cn.qp += 1\n"),
                        ("        else:\n            cn.certified += 1\n", "")],
}


@njit(cache=False)
def floor_divide_steps(kd, ko, md, mo, f, ksd, kso, cp, den, u, v, a, top, va_t, dt, beta, gamma, kc, mc, d, refactor):
    """The floor program (srenv/numerics/floor.py) with the kernel's arithmetic in the substitution: divisions
    by the pivots instead of multiplications by their reciprocals, and (refactor) the factors computed again at
    every step as the kernel's pattern solve does."""
    n = u.shape[0]
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    h = dt * (1.0 - gamma)
    q = dt * dt * (0.5 - beta)
    for k in range(va_t.shape[0]):
        va_new = va_t[k]
        vpa = top[1] + h * top[2]
        ua_new = top[0] + dt * top[1] + q * top[2] - c2 * vpa + c2 * va_new
        aa_new = (va_new - vpa) * c1
        vp_next = v[0] + h * a[0]
        ut_next = u[0] + dt * v[0] + q * a[0] - c2 * vp_next
        vp_prev = 0.0
        ut_prev = 0.0
        prev = 0.0
        cprev = 0.0
        for i in range(n):
            vp_i, ut_i = vp_next, ut_next
            b = f[i] + c1 * md[i] * vp_i - kd[i] * ut_i
            if i > 0:
                b += c1 * mo[i - 1] * vp_prev - ko[i - 1] * ut_prev
            else:
                b -= kc * ua_new + mc * aa_new
            if i < n - 1:
                vp_next = v[i + 1] + h * a[i + 1]
                ut_next = u[i + 1] + dt * v[i + 1] + q * a[i + 1] - c2 * vp_next
                b += c1 * mo[i] * vp_next - ko[i] * ut_next
            if refactor:
                dn = ksd[i] - kso[i - 1] * cprev if i > 0 else ksd[i]
                cprev = kso[i] / dn if i < n - 1 else 0.0
                cp[i] = cprev
            else:
                dn = den[i]
            if i > 0:
                b -= kso[i - 1] * prev
            prev = b / dn
            d[i] = prev
            vp_prev, ut_prev = vp_i, ut_i
        vn = 0.0
        for i in range(n - 1, -1, -1):
            vn = d[i] - cp[i] * vn if i < n - 1 else d[i]
            vpr = v[i] + h * a[i]
            u[i] = u[i] + dt * v[i] + q * a[i] - c2 * vpr + c2 * vn
            a[i] = (vn - vpr) * c1
            v[i] = vn
        top[0] = ua_new
        top[1] = va_new
        top[2] = aa_new


class DivideFloor:
    """floor_divide_steps on a FloorRun's mesh."""

    def __init__(self, sim: Simulator, fl: FloorRun, refactor: bool) -> None:
        kd, ko, md, mo, f, kso, cp, _ = fl.model
        ksd, kso = sim._kstar(fl.dt)
        den = np.array([ksd[i] - (kso[i - 1] * cp[i - 1] if i > 0 else 0.0) for i in range(len(ksd))])
        self.args = (kd, ko, md, mo, f, ksd, kso, cp.copy(), den)
        self.fl, self.refactor = fl, refactor

    def stroke(self) -> None:
        fl = self.fl
        floor_divide_steps(*self.args, *fl.state, fl.va, fl.dt, *fl.newmark, *fl.coupling, fl.scratch, self.refactor)


def variant(name: str, edits, tag: str, text: str | None = None):
    text = (SRC.read_text() if text is None else text).replace("cache=True", "cache=False")
    for old, new in edits:
        if old not in text:
            raise SystemExit(f"variant {name!r}: its edit's text is not in kernel.py any more")
        text = text.replace(old, new)
    path = SRC.with_name(f"_ablation_{tag}.py")
    path.write_text(text)
    try:
        return importlib.import_module(f"srenv.numerics._ablation_{tag}")
    finally:
        path.unlink()


def timed_stroke(sim, run, strokes):
    """(µs/step of the compiled calls, µs/step of run_stroke) over `strokes` strokes with K.run = run."""
    spent = [0.0]

    def wrapped(st, va, t0, k_end):
        t = time.process_time()
        code = run(st, va, t0, k_end)
        spent[0] += time.process_time() - t
        return code

    K.run = wrapped
    t, steps = time.process_time(), 0
    for _ in range(strokes):
        steps += sim.run_stroke(record=False).n_steps
    total = time.process_time() - t
    return 1e6 * spent[0] / steps, 1e6 * total / steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", default="paper_fig4_deviated")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--strokes", type=int, default=4)
    ap.add_argument("--against", nargs="*", default=[],
                    help="commits whose kernel.py (with their active_set.py, and with today's) to time as well")
    ap.add_argument("--only", nargs="*", help="substrings of the variants to run (none: --only nothing)")
    args = ap.parse_args()
    base_run = K.run
    runs = {"base": base_run}
    chosen = {n: e for n, e in VARIANTS.items() if not args.only or any(s in n for s in args.only)}
    for i, (name, edits) in enumerate(chosen.items()):
        runs[name] = variant(name, edits, str(i)).run
    for commit in args.against:
        root = SRC.parents[2]
        old = subprocess.run(["git", "show", f"{commit}:srenv/numerics/kernel.py"], cwd=root, check=True,
                             capture_output=True, text=True).stdout
        solve = subprocess.run(["git", "show", f"{commit}:srenv/numerics/active_set.py"], cwd=root, check=True,
                               capture_output=True, text=True).stdout
        mod = variant("solve", [], f"{commit}_as", solve)
        runs[f"kernel.py at {commit}, today's pattern solve"] = variant(commit, [], f"{commit}_k", old).run
        runs[f"kernel.py and active_set.py at {commit}"] = variant(
            commit, [], f"{commit}_ka", old.replace("from .active_set import", f"from .{mod.__name__.split('.')[-1]} import")).run
    sims = {name: Simulator(load_config(args.case)) for name in runs}
    floor = FloorRun(next(iter(sims.values())))
    floors = {"floor": floor, "floor, dividing by the pivots": DivideFloor(sims["base"], floor, False),
              "floor, dividing, factored at every step": DivideFloor(sims["base"], floor, True)}
    for name, run in runs.items():  # compile and warm up
        timed_stroke(sims[name], run, 1)
    res = {name: ([], []) for name in runs}
    for name, fl in floors.items():
        fl.stroke()
        res[name] = ([], [])
    for _ in range(args.repeats):
        for name, run in runs.items():
            ck, tot = timed_stroke(sims[name], run, args.strokes)
            res[name][0].append(ck)
            res[name][1].append(tot)
        for name, fl in floors.items():
            t = time.process_time()
            for _ in range(4 * args.strokes):
                fl.stroke()
            us = 1e6 * (time.process_time() - t) / (4 * args.strokes * floor.n_steps)
            res[name][0].append(us)
            res[name][1].append(us)
    K.run = base_run
    fl = min(res["floor"][0])
    bk, bt = min(res["base"][0]), min(res["base"][1])
    print(f"| removed | compiled µs/step (min of {args.repeats}) | run_stroke µs/step | compiled saving vs base "
          f"| ratio to floor (run_stroke) |")
    print("|---|---|---|---|---|")
    for name, (ck, tot) in res.items():
        print(f"| {name} | {min(ck):.3f} | {min(tot):.3f} | {100 * (1 - min(ck) / bk):+.1f} % | "
              f"{min(tot) / fl:.2f} |")
    print(json.dumps({n: [float(np.min(a)), float(np.min(b))] for n, (a, b) in res.items()}))
    _ = bt


if __name__ == "__main__":
    main()
