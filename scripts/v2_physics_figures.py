"""The figures of docs/task.md "v2's per-well physics".

    python scripts/v2_physics_figures.py damping 7 29 6 18 3      # tau rule vs a fixed 0.03 s vs none
    python scripts/v2_physics_figures.py episodes 0 3 8 7 10 6 4 12  # v2 episodes before / unit / unit + tau

Arguments after the mode are train-well indices.
"""

import argparse

import gymnasium as gym
import numpy as np

import srenv  # noqa: F401
import srenv.envs.sucker_rod_v2 as v2
from srenv.analysis.stroke_summary import summarize
from srenv.config import load_config
from srenv.envs.sucker_rod_v1 import action_from_setpoints
from srenv.simulation.simulator import Simulator
from srenv.task import v2_physics as vp
from srenv.task import well_family as wf


def card_figures(cfg) -> tuple[float, float, float]:
    """(PPRL, MPRL, pump stroke) of strokes 5-6 at the config's setpoint."""
    sim = Simulator(cfg)
    runs = [sim.run_stroke(record=True) for _ in range(6)]
    s = summarize(sim, runs[-2:])
    return s["pprl_n"], s["mprl_n"], s["pump_stroke_m"]


def damping(k: int) -> None:
    spec = wf.build_spec("train", k)
    tau = vp.kv_tau_s(spec)
    base = card_figures(load_config(spec.cfg, {"damping.stiffness_proportional_s": 0.0}))
    f1 = spec.design["n0_spm"] / 60.0
    parts = []
    for name, t in (("rule", tau), ("fixed 0.03 s", 0.03)):
        v = card_figures(load_config(spec.cfg, {"damping.stiffness_proportional_s": t}))
        parts.append(f"{name}: PPRL {v[0] / base[0] - 1:+.2%} MPRL {v[1] / base[1] - 1:+.2%} "
                     f"pump stroke {v[2] / base[2] - 1:+.2%}")
    print(f"{spec.well_id} {spec.params.depth_m:.0f} m f1 {f1:.2f} Hz tau {tau:.4f} s "
          f"(zeta1 of 0.03 s: {0.03 * np.pi * f1:.3f}) | " + " | ".join(parts), flush=True)


def episode(k: int, physics) -> tuple:
    v2.physics_overrides = physics
    env = gym.make("srenv/SuckerRod-v2", episode_hours=4.0, event_rate_scale=0.0).unwrapped
    env.reset(seed=k)
    a = action_from_setpoints(env.well.cfg.surface.spm, env.well.cfg.surface.stroke_length_m, env.cfg.control)
    prod, pprl, rew, gb = [], [], [], []
    while True:
        _, r, term, trunc, info = env.step(a.astype(np.float32))
        prod.append(info["production_m3_day"])
        rew.append(r)
        pprl.append(env._last.summary["pprl_n"])
        gb.append(env._last.summary.get("gearbox_loading_pct", 0.0))
        if term or trunc:
            break
    unit = env.cfg.surface.beam_unit
    return np.mean(prod), np.max(pprl), np.mean(rew), np.max(gb), unit.geometry if unit else "harmonic"


def episodes(k: int) -> None:
    full = vp.overrides
    b = episode(k, lambda s: {})
    u = episode(k, lambda s: {key: v for key, v in full(s).items() if key.startswith("surface")})
    a = episode(k, full)
    print(f"train-{k:03d} {a[4]:12s} | production {b[0]:.2f} m3/d: unit {u[0] / b[0] - 1:+.1%}, unit+KV "
          f"{a[0] / b[0] - 1:+.1%} | PPRL {b[1] / 1e3:.1f} kN: unit {u[1] / b[1] - 1:+.1%}, unit+KV "
          f"{a[1] / b[1] - 1:+.1%} | reward {b[2]:.1f} USD/h: unit {u[2]:.1f}, unit+KV {a[2]:.1f} | "
          f"gearbox {a[3]:.0f} %", flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=("damping", "episodes"))
    ap.add_argument("wells", nargs="+", type=int, metavar="WELL", help="train-well indices")
    args = ap.parse_args()
    for k in args.wells:
        (damping if args.mode == "damping" else episodes)(k)
