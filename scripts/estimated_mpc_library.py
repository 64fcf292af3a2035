"""Build the well library of ``estimated_mpc`` (agents/policies/estimated_mpc.py): the first field observation of
training wells 16..199 (wells 0..15 are the benchmark's tuning and validation wells: left out so that validation
measures the estimator on wells it has not seen), each at ``--draws`` initial levels (episode seeds i + 200 k: the
same well, the level and schedule drawn anew). Training split only; no episode is played.

    PYTHONPATH=. python scripts/estimated_mpc_library.py --out agents/policies/estimated_mpc_library.npz
"""

from __future__ import annotations

import argparse
import io
import sys

import numpy as np

from agents.policies.estimated_mpc import feature_names
from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.outputs import atomic_write
from srenv.task.well_family import N_TRAIN

FIRST_WELL = 16  # 0..9 tune the baselines, 0..15 are the validation episodes' wells (seeds 20000..20015 mod 200)


def build(draws: int, wells: range = range(FIRST_WELL, N_TRAIN)) -> tuple[np.ndarray, np.ndarray, list[str]]:
    env = SuckerRodV2Env(scenario="train", event_rate_scale=0.0, episode_hours=12.0, interval_s=300.0)
    names = feature_names(env.obs_names)
    idx = [env.obs_names.index(n) for n in names]
    rows, ids = [], []
    for w in wells:
        for k in range(draws):
            obs, info = env.reset(seed=w + N_TRAIN * k)
            assert info["well_id"] == f"train-{w:03d}"
            rows.append(obs[idx].astype(np.float64))
            ids.append(w)
    return np.array(ids), np.array(rows), names


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--draws", type=int, default=4)
    a = ap.parse_args()
    from srenv.errors import ConfigError
    from srenv.outputs import check_output_path

    try:
        if not 1 <= a.draws <= 50:
            raise ConfigError("--draws", a.draws, "an integer in [1, 50] initial levels per well")
        check_output_path("--out", a.out, (".npz",))
    except ConfigError as exc:
        print(f"estimated_mpc_library: {exc}", file=sys.stderr)
        sys.exit(2)
    wells, feats, names = build(a.draws)
    buf = io.BytesIO()
    np.savez(buf, wells=wells, features=feats, names=np.array(names))

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(buf.getvalue())

    atomic_write(a.out, write)
    print(f"{a.out}: {len(wells)} rows, {len(set(wells.tolist()))} training wells, {feats.shape[1]} features")


if __name__ == "__main__":
    main()
