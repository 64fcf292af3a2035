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
import time

import numpy as np

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
        ("            if nonsmooth:\n                set_bounds(", "            if nonsmooth and k == 0:\n"
         "                set_bounds(")],
    "energy accumulation": [
        ("            energy[E_GRAV] += f[i] * du\n", ""),
        ("            energy[E_REACT] -= 0.5 * (lam[i] + prev_lam[i]) * du\n", ""),
        ("            energy[E_VISC] += 0.5 * cd[i] * (v[i] + prev_v[i]) * du\n", "")],
    "force envelope": [("            emax[e] = max(emax[e], ne)\n            emin[e] = min(emin[e], ne)\n", "")],
    "stick / status bookkeeping": [("        for i in range(n):\n            s = ns[i] and v[i] == 0.0\n",
                                    "        for i in range(0):\n            s = ns[i] and v[i] == 0.0\n")],
    "reactions (lam = b - K*v)": [("        for i in range(n):\n            kv = ksd[i] * v[i]\n",
                                   "        for i in range(0):\n            kv = ksd[i] * v[i]\n")],
    "events (extremes, reversal returns)": [
        ("        if events(valve_p, prog, u[n - 1], v[n - 1]):\n            return EVENT\n", "")],
    "prediction's K u-tilde / M v-tilde pass": [
        ("        for i in range(n):\n            ku = kd[i] * rhs[i]\n", "        for i in range(0):\n"
         "            ku = kd[i] * rhs[i]\n")],
    "(added) a second pattern solve per step": [
        (CALL, CALL + "\n                    nc = solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, "
         "cp, dp, maxcorr, tolv, toll)")],
    "(added) a second plain Thomas solve per step": [
        (CALL, CALL + "\n                    thomas_pattern(ksd, kso, rhs, stuck, vk, cp, dp)")],
    "counters / path": [("        if path == PATH_QP:\n            cn.qp += 1\n", "        if path == 99:\n"
                         "            cn.qp += 1\n"),
                        ("        else:\n            cn.certified += 1\n", "")],
}


def variant(name: str, edits, tag: str):
    text = SRC.read_text().replace("cache=True", "cache=False")
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
    ap.add_argument("--only", nargs="*", help="substrings of the variants to run")
    args = ap.parse_args()
    base_run = K.run
    runs = {"base": base_run}
    chosen = {n: e for n, e in VARIANTS.items() if not args.only or any(s in n for s in args.only)}
    for i, (name, edits) in enumerate(chosen.items()):
        runs[name] = variant(name, edits, str(i)).run
    sims = {name: Simulator(load_config(args.case)) for name in runs}
    floor = FloorRun(next(iter(sims.values())))
    for name, run in runs.items():  # compile and warm up
        timed_stroke(sims[name], run, 1)
    floor.stroke()
    res = {name: ([], []) for name in runs}
    res["floor"] = ([], [])
    for _ in range(args.repeats):
        for name, run in runs.items():
            ck, tot = timed_stroke(sims[name], run, args.strokes)
            res[name][0].append(ck)
            res[name][1].append(tot)
        t = time.process_time()
        for _ in range(4 * args.strokes):
            floor.stroke()
        us = 1e6 * (time.process_time() - t) / (4 * args.strokes * floor.n_steps)
        res["floor"][0].append(us)
        res["floor"][1].append(us)
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
