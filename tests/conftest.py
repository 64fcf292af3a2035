"""The tests' shared doubles, for every test file under tests/ (import them: ``from conftest import ...``).

1. :class:`FakeSuckerRodV1` (:data:`FAKE_ENV`, the id with its module for worker processes): a tiny stand-in
   for ``srenv/SuckerRod-v1`` that implements only its contract (docs: notes/v1_contract): the field
   observation's names, the action map, ``info`` keys, the train/test splits by ``reset(seed)``,
   ``env.unwrapped.cfg`` / ``well`` / ``inflow_multiplier`` / ``time_s``, deep-copyable. The physics is a tank:
   the annulus fills from an inflow that falls with the level and steps once per episode; the pump lifts
   ``k * SPM * stroke`` while there is liquid. Fast enough for unit tests of the harness (thousands of steps per
   second); it says nothing about the real well.
2. :func:`assert_cli_refuses`: one check for the CLI's bad-input contract, shared by the tests of each command
   that reads a file; :func:`record_by_hand`: a dynacard record's described well written by hand (the route
   ``srenv classify / diagnose RECORD.json`` replaces), on the records in :data:`FIELD_DATA`.
3. The ``wheel`` fixture: srenv's wheel, built once per session (tests/test_wheel.py, test_core_install.py).
4. :func:`run_on_avx2_numpy`: a snippet in a fresh interpreter on numpy's AVX2 kernels, for the tests that pin
   results to the bit.
5. The ``described_student`` fixture: a small student fitted on inputs of the described width (the acting
   described student, tests/agents/test_described_features.py, and under a guard, test_guard_described.py).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

ENV_ID = "agents-fake/SuckerRod-v1"
CARD = [f"card_up_{i:02d}" for i in range(32)] + [f"card_down_{i:02d}" for i in range(32)]
FIELD_OBS_NAMES = tuple(CARD + ["spm", "avg_spm", "stroke", "duty", "idle_s", "fillage_est", "power_mean",
                                "power_peak", "pprl", "mprl", "time_remaining", "level_shot",
                                "level_shot_age"])
PRIVILEGED_OBS_NAMES = (*FIELD_OBS_NAMES, "level", "inflow")  # the field names, then the hidden truth
N_WELLS = {"train": 20, "test": 10}


@dataclass(frozen=True)
class FakeWell:
    well_id: str
    cfg: SimpleNamespace
    hidden: dict = field(default_factory=dict)


def _well(split: str, number: int) -> FakeWell:
    rng = np.random.default_rng((0 if split == "train" else 1) * 1000 + number)
    control = SimpleNamespace(spm_min=3.0, spm_max=float(rng.uniform(8, 12)), stroke_min_m=1.0,
                              stroke_max_m=float(rng.uniform(2.0, 3.0)))
    task = SimpleNamespace(interval_s=300.0, episode_hours=4.0)
    surface = SimpleNamespace(spm=float(rng.uniform(4, 8)), stroke_length_m=1.5)
    cfg = SimpleNamespace(control=control, task=task, surface=surface)
    hidden = {"inflow_m3_day": float(rng.uniform(10, 40)), "k_m3_day": float(rng.uniform(1.5, 3.0))}
    return FakeWell(f"{split}-{number:03d}", cfg, hidden)


class FakeSuckerRodV1(gym.Env):
    metadata = {"render_modes": []}  # noqa: RUF012 (gymnasium's own convention)

    def __init__(self, scenario: str = "train", observation: str = "field") -> None:
        if scenario not in N_WELLS:
            raise ValueError(f"scenario = {scenario!r}: expected train or test")
        if observation not in ("field", "privileged"):
            raise ValueError(f"observation = {observation!r}: expected field or privileged")
        self.scenario, self.observation = scenario, observation
        self.obs_names = FIELD_OBS_NAMES if observation == "field" else PRIVILEGED_OBS_NAMES
        self.observation_space = gym.spaces.Box(-2.0, 2.0, (len(self.obs_names),), np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.well = _well(scenario, 0)
        self.cfg = self.well.cfg

    def inflow_multiplier(self, t_s: float) -> float:
        return 1.0 if t_s < self._t_step else self._step_to

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        number = (seed if seed is not None else int(self.np_random.integers(1 << 30))) % N_WELLS[self.scenario]
        self.well = _well(self.scenario, number)
        self.cfg = self.well.cfg
        self.time_s, self.k = 0.0, 0
        self.horizon = int(self.cfg.task.episode_hours * 3600 / self.cfg.task.interval_s)
        self._t_step = float(self.np_random.uniform(0.3, 0.7)) * self.horizon * self.cfg.task.interval_s
        self._step_to = float(self.np_random.uniform(0.5, 1.5))
        self.stored_m3, self.fill, self.last_a0 = 2.0, 1.0, 0.0
        self._last = {"spm": 0.0, "avg": 0.0, "stroke": 1.5, "duty": 0.0, "idle": 0.0}
        return self._obs(), {"well_id": self.well.well_id}

    def _obs(self) -> np.ndarray:
        c = self.cfg.control
        o = np.zeros(len(FIELD_OBS_NAMES), np.float32)
        o[:64] = self.fill * np.sin(np.linspace(0, np.pi, 64)) * 0.5
        vals = [self._last["spm"] / c.spm_max, self._last["avg"] / c.spm_max,
                2 * (self._last["stroke"] - c.stroke_min_m) / (c.stroke_max_m - c.stroke_min_m) - 1,
                self._last["duty"], self._last["idle"] / 3600, self.fill, 0.3, 0.5, 0.6, 0.2,
                1 - self.k / self.horizon, self.stored_m3 / 10, 0.0]
        o[64:] = vals
        if self.observation == "privileged":
            q = self.well.hidden["inflow_m3_day"] * self.inflow_multiplier(self.time_s)
            o = np.concatenate([o, np.array([self.stored_m3 / 10, q / 40], np.float32)])
        return o

    def step(self, action):
        c, h, task = self.cfg.control, self.well.hidden, self.cfg.task
        a = np.clip(np.asarray(action, np.float64), -1, 1)
        avg = 0.5 * (a[0] + 1) * c.spm_max
        stroke = c.stroke_min_m + 0.5 * (a[1] + 1) * (c.stroke_max_m - c.stroke_min_m)
        spm, duty = (avg, 1.0) if avg >= c.spm_min else (c.spm_min, avg / c.spm_min)
        dt_day = task.interval_s / 86400
        q_in = h["inflow_m3_day"] * self.inflow_multiplier(self.time_s) * max(0.0, 1 - self.stored_m3 / 20)
        cap = h["k_m3_day"] * spm * stroke * duty * dt_day
        avail = self.stored_m3 + q_in * dt_day
        lifted = min(cap, avail)
        prev = self.stored_m3
        self.stored_m3 = avail - lifted
        if duty > 0:
            self.fill = lifted / cap if cap > 0 else 1.0
        hours = task.interval_s / 3600
        terms = {"reward_revenue": 60.0 * lifted / dt_day / 24, "reward_inventory": 20.0 * (self.stored_m3 - prev) / hours,
                 "reward_energy": -0.4 * spm * stroke * duty, "reward_pound": -3.0 * (1 - self.fill) * spm * duty,
                 "reward_ramp": -2.0 * abs(a[0] - self.last_a0)}
        self.last_a0 = a[0]
        reward = float(sum(terms.values()))
        self.time_s += task.interval_s
        self.k += 1
        self._last = {"spm": spm if duty > 0 else 0.0, "avg": avg, "stroke": stroke, "duty": duty,
                          "idle": 0.0 if duty > 0 else self._last["idle"] + task.interval_s}
        info = {"well_id": self.well.well_id, **terms, "cost": 0.1 * (1 - self.fill) * duty,
                "cost_pound": 0.1 * (1 - self.fill) * duty, "spm": spm, "avg_spm": avg, "duty": duty,
                "stroke_length_m": stroke, "fillage": self.fill, "fillage_est": self.fill,
                "production_m3_day": lifted / dt_day, "oil_m3_day": 0.5 * lifted / dt_day,
                "inflow_m3_day": q_in, "fluid_level_m": self.stored_m3 * 10}
        return self._obs(), reward, False, self.k >= self.horizon, info


if ENV_ID not in gym.registry:
    gym.register(ENV_ID, entry_point=FakeSuckerRodV1)

FAKE_ENV = f"{__name__}:{ENV_ID}"  # gymnasium's module:id form: a spawned worker imports this module to find it


def assert_cli_refuses(args: list[str], out: Path, *needles: str, tmpdir: Path | None = None) -> str:
    """``python -m srenv.tools.cli ARGS`` exits 2 with one stderr line holding every needle, and writes no ``out``;
    with ``tmpdir`` the command's temporary files go there (TMPDIR) and none may be left behind."""
    env = None if tmpdir is None else dict(os.environ, TMPDIR=str(tmpdir))
    p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", *args], check=False, capture_output=True, text=True,
                       env=env)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and all(n in lines[0] for n in needles), p.stderr
    assert not out.exists()
    assert tmpdir is None or not any(tmpdir.iterdir()), sorted(tmpdir.iterdir())
    return lines[0]


FIELD_DATA = Path(__file__).resolve().parent / "data" / "field"  # the two public dynacard records (its README)


def record_by_hand(record: Path, work: Path):
    """The manual route a record's described well replaces: (the record, a well YAML, its stored card as a CSV with
    t_s for ``diagnose``, the same as two columns for ``classify``), written by hand in ``work`` from the record as
    ``srenv validate`` reads it (the measured motion, pump full, the intake pressure and plunger friction of
    ``validate.pump_state``)."""
    import yaml

    from srenv.analysis.field_model import well_config
    from srenv.tools.validate import card_motion, pump_state, read_record, write_motion_csv

    rec = read_record(str(record), None, False)
    write_motion_csv(card_motion(rec), str(work / "motion.csv"))
    st = pump_state(rec, str(work))
    cfg = well_config(rec, str(work / "motion.csv"), st["intake_pressure_pa"], 1.0, st["plunger_friction_n"])
    (work / "well.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    np.savetxt(work / "card.csv", np.c_[rec.t_s, rec.position_m, rec.load_n], delimiter=",", comments="",
               header="t_s,polished_rod_position_m,polished_rod_load_n", fmt="%.17g")
    np.savetxt(work / "surface.csv", np.c_[rec.position_m, rec.load_n], delimiter=",", comments="",
               header="polished_rod_position_m,polished_rod_load_n", fmt="%.17g")
    return rec, work / "well.yaml", work / "card.csv", work / "surface.csv"


# ------------------------------------------------------------------------------------------------ the wheel
ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("srenv", "agents", "configs", "setup.py", "pyproject.toml", "README.md")


def _has_build_backend() -> bool:
    """setuptools >= 68 (pyproject's build requirement) in this interpreter."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return int(version("setuptools").split(".")[0]) >= 68
    except (PackageNotFoundError, ValueError):
        return False


@pytest.fixture(scope="session")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(ROOT / name, src / name)
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(src), "-w", str(tmp / "dist")]
    if _has_build_backend():
        cmd.insert(4, "--no-build-isolation")  # build with the installed setuptools: nothing downloaded
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
    assert p.returncode == 0, p.stderr[-2000:]
    (whl,) = (tmp / "dist").glob("srenv-*.whl")
    return whl


def _beyond_avx2() -> list[str]:
    """numpy's dispatch targets above AVX2 (X86_V3) on this CPU: AVX-512's."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__
    except ImportError:  # numpy 1.x
        from numpy.core._multiarray_umath import __cpu_dispatch__
    return [name for name in __cpu_dispatch__ if "512" in name or name == "X86_V4"]


def run_on_avx2_numpy(code: str) -> str:
    """Run ``code`` in a fresh interpreter (the repository root as working directory, it and tests/ on the path)
    with numpy's AVX-512 kernels switched off, and return its stdout.

    Why: the digests the tests pin were computed on AVX2 machines, and numpy's AVX-512 kernels of the
    transcendental functions (sin, exp, tanh, ...) round some results differently in the last bit. On an AVX-512
    CPU the same code then gives other bits (v2's episodes differ by at most 4e-12 relative over 3 x 20 steps, the
    card augmentation likewise), and with ``NPY_DISABLE_CPU_FEATURES`` naming those kernels the pinned bits come
    back. numpy reads the variable when it is imported, hence the fresh interpreter."""
    root = Path(__file__).resolve().parents[1]
    path = [str(root), str(root / "tests"), os.environ.get("PYTHONPATH")]
    env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=" ".join(_beyond_avx2()),
               PYTHONPATH=os.pathsep.join(filter(None, path)))
    done = subprocess.run([sys.executable, "-c", code], check=False, cwd=root, env=env, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.fixture
def with_couplings():
    """A shipped well with every taper's couplings at `coupling_kg_m` and a wellhead pressure (the couplings'
    buoyancy and the static load budget: tests/srenv/physics/test_coupling_buoyancy.py, test_load_budget.py)."""
    from srenv.config import apply_overrides, config_from_dict, read_raw

    def make(name: str, coupling_kg_m: float = 0.3, p_wh: float = 5e5):
        raw = read_raw(name)
        tapers = raw["rod"]["tapers"]
        for t in tapers:
            t["coupling_mass_kg_per_m"] = coupling_kg_m
        return config_from_dict(apply_overrides(raw, {"rod.tapers": tapers, "fluid.wellhead_pressure_pa": p_wh}))

    return make



@pytest.fixture(scope="session")
def described_student(tmp_path_factory):
    """A small student fitted on inputs of the described width: field observation + base action + the 13 features."""
    from agents.policies.described_features import FEATURES
    from agents.training.pooled_fit import fit_student

    rng = np.random.default_rng(0)
    x = rng.normal(size=(64, 89 + 2 + len(FEATURES))).astype(np.float32)
    y = np.tanh(x[:, -2:] + x[:, :2]).astype(np.float32)
    dest = tmp_path_factory.mktemp("described") / "s_v2_seed0.zip"
    fit_student(x, y, {"epochs": 2, "weight_decay": 0.0, "net_arch": [8]}, {"activation_fn": "tanh"}, 0, dest)
    return {"path": str(dest), "obs_norm": str(dest.with_name(dest.stem + "_obs_norm.npz"))}
