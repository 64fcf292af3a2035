"""Issue 25 (speed): the floor program is the linear Newmark step; the native vector env equals N single envs and
trains under SB3; the fast stepping option stays off in v1 and stays close to simulating every stroke."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401 - registers the envs
from srenv.config import load_config
from srenv.envs.sucker_rod_v1 import SuckerRodV1Env
from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.envs.vector import KernelVectorEnv, sb3_vec_env
from srenv.simulation.simulator import Simulator
from srenv.tools.bench_kernel import FloorRun
from srenv.tools.stepping_error import compare

SHORT = {"episode_hours": 0.25}  # 3 five-minute intervals: episodes end (and autoreset) inside a short test


def test_floor_program_is_the_kernels_linear_step() -> None:
    """Same mesh, time step and top motion: the floor's linear trajectory equals the kernel's linear path."""
    cfg = load_config("paper_fig3_vertical")
    lin = Simulator(cfg)
    lin.linear_reference = True
    floor = FloorRun(lin)
    u0 = lin.u.copy()
    lin.run_velocity(floor.va, floor.dt, record=False, start_velocity_m_s=0.0, start_acceleration_m_s2=0.0)
    floor.stroke()
    u, v = floor.state[0], floor.state[1]
    assert np.max(np.abs(u - u0)) > 1e-3  # the string moved
    np.testing.assert_allclose(u, lin.u, rtol=0, atol=1e-12 * np.max(np.abs(u)))
    np.testing.assert_allclose(v, lin.v, rtol=0, atol=1e-9 * np.max(np.abs(v)))


@pytest.mark.parametrize("env_id", ["srenv/SuckerRod-v1", "srenv/SuckerRod-v2"])
def test_vector_env_is_registered_and_declares_its_autoreset_mode(env_id) -> None:
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", **SHORT)
    try:
        assert isinstance(venv, KernelVectorEnv)
        assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        assert venv.observation_space.shape == (2, *venv.single_observation_space.shape)
    finally:
        venv.close()


@pytest.mark.parametrize("backend", [{"threads": 2}, {"processes": 2}, {"processes": 3}],
                         ids=["threads", "processes", "driver+2 workers"])
@pytest.mark.parametrize("env_cls", [SuckerRodV1Env, SuckerRodV2Env])
def test_vector_env_matches_single_envs_through_an_autoreset(env_cls, backend) -> None:
    n, steps = 3, 5
    venv = KernelVectorEnv(env_cls, n, **backend, **SHORT)
    singles = [env_cls(**SHORT) for _ in range(n)]
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (steps, n, 2)).astype(np.float32)
    try:
        obs, _ = venv.reset(seed=40)
        wells = {w.well_id for w in venv.env_call("get", "well", range(n))}
        assert len(wells) == n  # different wells, different meshes
        done = np.zeros(n, bool)
        ref = [e.reset(seed=40 + i)[0] for i, e in enumerate(singles)]
        np.testing.assert_array_equal(obs, np.stack(ref))
        for k in range(steps):
            obs, rew, term, trunc, _ = venv.step(actions[k])
            for i, e in enumerate(singles):
                if done[i]:
                    o, r, t, u = e.reset()[0], 0.0, False, False
                else:
                    o, r, t, u, _ = e.step(actions[k, i])
                np.testing.assert_array_equal(obs[i], o)
                assert rew[i] == r and term[i] == t and trunc[i] == u
            done = term | trunc
        assert done.any() or k == steps - 1
    finally:
        venv.close()


def test_sb3_adapter_trains_ppo_briefly() -> None:
    sb3 = pytest.importorskip("stable_baselines3")
    venv = sb3_vec_env(KernelVectorEnv(SuckerRodV1Env, 2, threads=2, **SHORT))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = sb3.PPO("MlpPolicy", venv, n_steps=4, batch_size=8, n_epochs=1, seed=0)
        model.learn(total_timesteps=8)
    assert model.num_timesteps >= 8
    venv.close()


def test_process_backend_serves_sb3_and_refuses_bad_sizes() -> None:
    """The SB3 adapter on worker processes equals it on threads (same-step resets through an episode's end), its
    get_attr / env_method reach the workers' envs; bad `processes` values and a worker that cannot build its env
    are one clear error each."""
    acts = np.random.default_rng(1).uniform(-1, 1, (5, 2, 2)).astype(np.float32)
    runs = []
    for backend in ({"threads": 1}, {"processes": 2}):
        venv = sb3_vec_env(KernelVectorEnv(SuckerRodV1Env, 2, **backend, **SHORT))
        try:
            venv.seed(7)
            rec = [venv.reset()]
            for a in acts:
                venv.step_async(a)
                obs, rew, done, infos = venv.step_wait()
                rec += [obs, rew, done, [i.get("terminal_observation") for i in infos]]
            assert venv.get_attr("horizon_s") == [0.25 * 3600.0] * 2
            rec.append(venv.env_method("inflow_multiplier", 100.0, indices=[1]))
            assert venv.env_is_wrapped(gym.Wrapper) == [False, False]
        finally:
            venv.close()
        runs.append(rec)
    assert any(d.any() for d in runs[0][3::4])  # an episode ended inside the run
    for x, y in zip(*runs):
        if isinstance(x, list):
            for a, b in zip(x, y):
                assert (a is None and b is None) or np.array_equal(a, b)
        else:
            np.testing.assert_array_equal(x, y)
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="processes"):
            KernelVectorEnv(SuckerRodV1Env, 2, processes=bad, **SHORT)
    with pytest.raises(RuntimeError, match="building env 0"):
        KernelVectorEnv(SuckerRodV1Env, 2, processes=2, scenario="no-such-split", **SHORT)


def test_fast_stepping_is_off_in_v1_and_reuses_strokes_when_on() -> None:
    a = np.array([1.0, 1.0], np.float32)
    plain, fast = SuckerRodV1Env(episode_hours=1.0), SuckerRodV1Env(episode_hours=1.0, fast_stepping=True)
    plain.reset(seed=12)
    fast.reset(seed=12)
    assert not plain.runner.reuse_periodic
    ex_plain = ex_fast = 0
    for _ in range(6):
        ex_plain += plain.step(a)[4]["exact_strokes"]
        ex_fast += fast.step(a)[4]["exact_strokes"]
    assert ex_fast < ex_plain


def test_fast_stepping_error_on_a_steady_sample() -> None:
    """A test well pumping steadily at the VSD minimum for half an hour: production, PPRL and the return within
    0.5 % of simulating every stroke, with a fraction of the exact strokes. (Pounding wells are not within 0.5 %,
    for v1's own fast-forward either: docs/speed.md's table.)"""
    r = compare("vsd_minimum", 3, 0.5, options={"fast": {"fast_stepping": True}})
    err = r["fast"]["relative_error"]
    for key in ("production_m3", "pprl_max_n", "return"):
        assert err[key] < 0.005, (key, err[key])
    assert 0 < r["fast"]["figures"]["exact_strokes"] < r["reference"]["exact_strokes"] / 4


@pytest.mark.parametrize("backend", [{"threads": 2}, {"processes": 2}], ids=["threads", "processes"])
def test_env_wrapper_wraps_every_slot_in_both_backends(backend) -> None:
    """``env_wrapper`` wraps each slot where it is built (the workers too): the wrapper is seen by env_is_wrapped,
    its episode statistics arrive in the infos, attributes are read through it, and the steps are the bare envs'."""
    acts = np.random.default_rng(2).uniform(-1, 1, (4, 2, 2)).astype(np.float32)
    runs = []
    for wrapper in (None, gym.wrappers.RecordEpisodeStatistics):
        venv = sb3_vec_env(gym.make_vec("srenv/SuckerRod-v1", num_envs=2, vectorization_mode="vector_entry_point",
                                        env_wrapper=wrapper, **backend, **SHORT))
        try:
            venv.seed(5)
            rec = [venv.reset()]
            for a in acts:
                venv.step_async(a)
                obs, rew, done, infos = venv.step_wait()
                rec += [obs, rew, done]
                if wrapper is not None and done.any():
                    assert all("episode" in i for i, d in zip(infos, done) if d)
            assert venv.env_is_wrapped(gym.wrappers.RecordEpisodeStatistics) == [wrapper is not None] * 2
            assert venv.get_attr("horizon_s") == [0.25 * 3600.0] * 2
        finally:
            venv.close()
        runs.append(rec)
    assert any(d.any() for d in runs[0][3::3])
    for x, y in zip(*runs):
        np.testing.assert_array_equal(x, y)


def test_the_driver_steps_the_first_block_and_the_workers_the_rest() -> None:
    """processes=P: the driver steps the first block itself and P - 1 workers the others (docs/speed.md §3);
    ``driver_block=False`` keeps P workers. Both step the envs as single envs do."""
    from srenv.envs.vector_procs import ProcessShards, _DriverBlock

    for driver, workers in ((True, 1), (False, 2)):
        shards = ProcessShards(SuckerRodV1Env, 4, 2, dict(SHORT), driver_block=driver)
        try:
            assert len(shards.procs) == workers and isinstance(shards.conns[0], _DriverBlock) is driver
            assert shards.blocks == [[0, 1], [2, 3]]
            res = shards.run("reset", [(7 + i, None) for i in range(4)])
            single = [SuckerRodV1Env(**SHORT).reset(seed=7 + i)[0] for i in range(4)]
            assert all(np.array_equal(r[0], o) for r, o in zip(res, single))
        finally:
            shards.close()


def test_a_failing_block_is_raised_after_every_block_answered() -> None:
    """run_parts (the step's block-by-block collection) raises a block's error only after collecting every block,
    so the pipes stay in step and the next command works."""
    from srenv.envs.vector_procs import ProcessShards

    shards = ProcessShards(SuckerRodV1Env, 4, 2, dict(SHORT))
    try:
        with pytest.raises(RuntimeError, match="bogus in the worker of envs 0..1"):
            list(shards.run_parts("bogus", [None] * 4))
        res = shards.run("reset", [(7 + i, None) for i in range(4)])
        assert np.array_equal(res[3][0], SuckerRodV1Env(**SHORT).reset(seed=10)[0])
    finally:
        shards.close()


def test_a_script_without_a_main_guard_gets_one_clear_error(tmp_path) -> None:
    """processes=P from a script with no `if __name__ == "__main__":` (forkserver imports it again in the worker,
    which dies starting processes of its own): the parent raises one RuntimeError that says so, not an EOFError."""
    import subprocess
    import sys

    script = tmp_path / "no_guard.py"
    script.write_text("import gymnasium as gym, srenv\n"
                      "gym.make_vec('srenv/SuckerRod-v1', num_envs=2, vectorization_mode='vector_entry_point', "
                      "processes=2, episode_hours=0.25)\n")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, check=False)
    last = out.stderr.strip().splitlines()[-1]
    assert out.returncode == 1 and last.startswith("RuntimeError: the worker of envs 1..1 exited before"), last
    assert 'if __name__ == "__main__":' in last
