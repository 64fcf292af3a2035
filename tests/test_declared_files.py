"""Hardening, second round (issue 28), part 2: the fields of the files the commands read (benchmark and
training YAML, reports, checkpoint JSON, obs-norm npz, model metadata, RLlib policy JSON, baseline
parameters), env kwargs and actions, and the first round's classes that still failed - generated from the
declarations of agents/inputs.py where a table exists. Every refusal: one line naming the field, the value
and what is expected; nothing left behind.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from declared_helpers import FIG3, FIG7, one_line, run_agents, run_srenv, write_card

from agents import inputs as ag_inputs
from srenv.envs.env_kwargs import CARD_POINTS
from srenv.errors import ConfigError, short_repr


# ------------------------------------------------------------------------ report and config fields
def _field_cases(kinds: tuple[str, ...]) -> list[Any]:
    return [pytest.param(kind, name, v, id=f"{kind}:{name}={short_repr(v, 12)}")
            for kind in kinds for name, d in ag_inputs.FIELDS[kind].items() for v in d.bad_values()]


@pytest.mark.parametrize(("kind", "name", "value"), _field_cases(tuple(ag_inputs.FIELDS)))
def test_every_declared_file_field_refuses_bad_values(kind: str, name: str, value: Any) -> None:
    with pytest.raises(ConfigError) as ex:
        ag_inputs.field(kind, name, value, "where.")
    msg = str(ex.value)
    assert f"where.{name}" in msg and "expected" in msg and len(msg.splitlines()) == 1


BENCH_CASES = [("workers", "workers: 1000000\n", "workers"),
               ("seeds-count", "test:\n  seeds: {start: 100000, count: 1000000000}\n", "test.seeds.count"),
               ("seeds-start", "test:\n  seeds: {start: -1, count: 3}\n", "test.seeds.start"),
               ("seeds-list", "test:\n  seeds: [1, abc]\n", "test.seeds[1]"),
               ("octal", "workers: 010\n", "ambiguous"),
               ("duplicate", "workers: 2\nworkers: 3\n", "duplicate key 'workers'"),
               ("syntax", "workers: [2\n", "valid YAML"),
               ("alias-bomb", "".join(f"{k}: &{k} [{', '.join([f'*{p}'] * 10)}]\n" for p, k in zip("abcdef", "bcdefg"))
                .replace("*a", "x"), "aliases"),
               ("run-n-timesteps", ("agents:\n  runs:\n    ppo: {config: configs/train/ppo_v1.yaml, seeds: [0], "
                                    "overrides: {n_timesteps: 1.0e+30}}\n"), "n_timesteps")]


@pytest.mark.parametrize(("text", "needle"), [pytest.param(t, n, id=i) for i, t, n in BENCH_CASES])
def test_bad_benchmark_yaml_is_one_line_exit_2(text: str, needle: str, tmp_path: Path,
                                               capsys: pytest.CaptureFixture) -> None:
    root = Path(__file__).resolve().parents[1]
    base = (root / "configs" / "benchmark" / "v1_quick.yaml").read_text()
    key = text.split(":")[0]
    # the case's block replaces the same top-level block of the quick benchmark
    kept = [blk for blk in base.split("\n") if blk]
    out, skip = [], False
    for line in kept:
        top = line and not line.startswith((" ", "#"))
        if top:
            skip = line.split(":")[0] == key
        if not skip:
            out.append(line)
    (tmp_path / "b.yaml").write_text("\n".join(out) + "\n" + text)
    rc, err = run_agents(["benchmark", str(tmp_path / "b.yaml"), "--out-dir", str(tmp_path / "o")], capsys)
    one_line(rc, err, needle)
    assert not (tmp_path / "o").exists()


# the file's own top level: unknown keys named (with the allowed ones, agents.benchmark.config.TOP_KEYS) before any
# missing block is, the quick block a mapping of top-level blocks, the document a mapping
BENCH_KEY_CASES = [("unknown-key", "v1_quick", "bogus_key: 1\n", [], "unknown key(s) ['bogus_key']"),
                   ("unknown-before-missing", None, "bogus: 1\n", [], "unknown key(s) ['bogus']"),
                   ("quick-list", "v1", "quick: [1]\n", ["--quick"], "quick = [1] (a list): expected a mapping"),
                   ("quick-unknown", "v1", "quick: {bogus: 1}\n", ["--quick"], "quick: unknown key(s) ['bogus']"),
                   ("document-list", None, "- 1\n", [], "= [1] (a list): expected a mapping"),
                   ("block-list", None, "tuning: [1]\n", [], "tuning = [1] (a list)"),
                   ("block-missing", None, "workers: 2\n", [], "tuning missing"),
                   ("baselines-list", "v1_quick", "baselines: [pump_off]\n", [], "baselines = ['pump_off'] (a list)"),
                   ("validation-list", "v1_quick", "validation: [1]\n", [], "validation = [1] (a list)"),
                   ("workers-bool", "v1_quick", "workers: true\n", [], "workers = True (a boolean)"),
                   ("agents-unknown", "v1_quick", "agents: {runs: {}, bogus: 1}\n", [], "agents: unknown key(s) ['bogus']"),
                   ("quick-agents-unknown", "v1", "quick: {agents: {bogus: 1}}\n", ["--quick"],
                    "quick.agents: unknown key(s) ['bogus']"),
                   ("evaluate-only-unknown", "v1_quick", "evaluate_only: {agent: [ppo]}\n", [],
                    "evaluate_only: unknown key(s) ['agent']"),
                   ("evaluate-only-agents", "v1_quick", "evaluate_only: {agents: ppo}\n", [],
                    "evaluate_only: agents = 'ppo' (a string)")]


@pytest.mark.parametrize(("base", "text", "flags", "needle"),
                         [pytest.param(b, t, f, n, id=i) for i, b, t, f, n in BENCH_KEY_CASES])
def test_a_benchmark_yamls_top_level_is_named_before_any_work(base: str | None, text: str, flags: list[str],
                                                              needle: str, tmp_path: Path,
                                                              capsys: pytest.CaptureFixture,
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Before: an unknown top-level key was accepted silently (the run went on without it), one in a file with
    no tuning block was refused as 'tuning: expected a mapping with seeds', and quick: [1] was a traceback."""
    import yaml

    from agents.benchmark import run
    from agents.benchmark.config import TOP_KEYS

    def work(*_a: Any, **_k: Any) -> None:
        raise AssertionError("the benchmark started")
    monkeypatch.setattr(run, "tune_baselines", work)
    root = Path(__file__).resolve().parents[1]
    doc = yaml.safe_load(text)  # the case's blocks over the shipped config's (or alone)
    if base:
        doc = {**yaml.safe_load((root / "configs" / "benchmark" / f"{base}.yaml").read_text()), **doc}
    (tmp_path / "b.yaml").write_text(yaml.safe_dump(doc))
    rc, err = run_agents(["benchmark", str(tmp_path / "b.yaml"), *flags, "--out-dir", str(tmp_path / "o")], capsys)
    line = one_line(rc, err, needle)
    if needle.startswith("unknown"):  # the allowed top-level keys are listed
        assert all(k in line for k in TOP_KEYS)
    assert sorted(os.listdir(tmp_path)) == ["b.yaml"]


def test_every_shipped_benchmark_config_uses_only_the_declared_top_level_keys() -> None:
    from agents.benchmark.config import TOP_KEYS, load_benchmark_config

    root = Path(__file__).resolve().parents[1]
    for path in sorted((root / "configs" / "benchmark").glob("*.yaml")):
        text = path.read_text()
        if "designs:" in text:  # the model-based designs' pre-registrations: read by scripts/, not a benchmark
            continue
        for quick in (False, True):
            cfg = load_benchmark_config(path, quick=quick)
            assert set(cfg) - {"source"} <= set(TOP_KEYS), path


# a training YAML in rl-zoo3's layout (keyed by env id, configs/train/zoo_ppo.yml) or not a mapping at all
ZOO_CASES = [("list", {"srenv/SuckerRod-v0": [1, 2]}, "srenv/SuckerRod-v0 = [1, 2] (a list)", "a mapping of hyperparameters"),
             ("integer", {"srenv/SuckerRod-v1": 3}, "srenv/SuckerRod-v1 = 3 (an integer)", "a mapping of hyperparameters"),
             ("null", {"srenv/SuckerRod-v0": None}, "srenv/SuckerRod-v0 = None (null)", "a mapping of hyperparameters"),
             ("mapping", {"srenv/SuckerRod-v2": {"n_steps": 256}}, "srenv/SuckerRod-v2 = {'n_steps': 256} (a mapping)",
              "the flat layout"),
             ("document-list", [1, 2], "= [1, 2] (a list)", "a mapping of hyperparameters")]


@pytest.mark.parametrize("backend", ["sb3", "rllib"])
@pytest.mark.parametrize(("data", "found", "expected"), [pytest.param(d, f, e, id=i) for i, d, f, e in ZOO_CASES])
def test_a_zoo_layout_training_yaml_names_the_env_id_its_value_and_type(data: Any, found: str, expected: str,
                                                                       backend: str, tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture) -> None:
    """Before: 'train config: algo = None: expected one of ppo, ...' whatever stood under the env id (with
    backend: rllib, the env id as an unknown key, without its type)."""
    import yaml

    if backend == "rllib" and isinstance(data, dict):
        data = {"backend": "rllib", **data}
    (tmp_path / "zoo.yml").write_text(yaml.safe_dump(data))
    rc, err = run_agents(["train", str(tmp_path / "zoo.yml"), "--out", str(tmp_path / "o")], capsys)
    one_line(rc, err, str(tmp_path / "zoo.yml"), found, f"expected {expected}")
    if isinstance(data, dict):
        one_line(rc, err, "rl_zoo3.train", "flat layout")
    assert sorted(os.listdir(tmp_path)) == ["zoo.yml"]


def test_the_shipped_zoo_file_is_named_as_rl_zoo3s_layout(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    root = Path(__file__).resolve().parents[1]
    rc, err = run_agents(["train", str(root / "configs" / "train" / "zoo_ppo.yml"), "--out", str(tmp_path / "o")],
                         capsys)
    one_line(rc, err, "srenv/SuckerRod-v0 = {", "(a mapping): expected the flat layout", "rl_zoo3.train")
    assert not (tmp_path / "o").exists()


def _each_episode(rep: dict, key: str, value: Any) -> None:
    for p in rep["policies"].values():
        for e in p.get("episodes", []):
            if value is None:
                e.pop(key, None)
            else:
                e[key] = value


REPORT_CASES = [
    ("episodes-without-reward", lambda r: _each_episode(r, "reward", None), "a seed and a reward"),
    ("episodes-not-mappings", lambda r: r["policies"]["pump_off"].__setitem__("episodes", [1, 2]), "a seed and a reward"),
    ("reward-string", lambda r: _each_episode(r, "reward", "x"), "episodes[0].reward"),
    ("reward-nan", lambda r: _each_episode(r, "reward", float("nan")), "episodes[0].reward"),
    ("seed-negative", lambda r: _each_episode(r, "seed", -4), "episodes[0].seed"),
    ("policy-not-mapping", lambda r: r["policies"].__setitem__("pump_off", [1]), "expected a mapping"),
    ("params-out-of-range", lambda r: r["policies"]["pump_off"].__setitem__("params", {"threshold": 7}),
     "params.threshold"),
    ("params-not-mapping", lambda r: r["policies"]["pump_off"].__setitem__("params", "x"), "params"),
    ("env-kwargs-int-keys", lambda r: r.__setitem__("env_kwargs", {"1": 1, 2: 2}), "env_kwargs"),
]


@pytest.mark.parametrize(("mutate", "needle"), [pytest.param(m, n, id=i) for i, m, n in REPORT_CASES])
def test_replay_refuses_a_bad_report_before_any_episode(mutate: Any, needle: str, tmp_path: Path,
                                                        capsys: pytest.CaptureFixture) -> None:
    root = Path(__file__).resolve().parents[1]
    rep = json.loads((root / "docs" / "benchmark.json").read_text())
    mutate(rep)
    path = tmp_path / "rep.json"
    path.write_text(json.dumps(rep, allow_nan=True))
    if "env_kwargs" in needle:  # JSON keys are strings: the check is on the reader's side
        from agents.inputs import report_env_kwargs

        with pytest.raises(ConfigError, match="env_kwargs"):
            report_env_kwargs({"1": 1, 2: 2})
        return
    rc, err = run_agents(["replay", str(path), "--policy", "pump_off", "--episodes", "1"], capsys)
    one_line(rc, err, needle, "expected")


# ------------------------------------------------------------------------ checkpoint and normaliser files
def _npz(path: Path, **over: Any) -> None:
    arrays = {"mean": np.zeros(4), "var": np.ones(4), "clip_obs": 10.0, "epsilon": 1e-8, **over}
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})


NPZ_CASES = [("missing-var", {"var": None}, "missing var"), ("nan-mean", {"mean": np.array([np.nan, 0, 0, 0])}, "finite"),
             ("negative-var", {"var": -np.ones(4)}, "var >= 0"), ("shape", {"var": np.ones(3)}, "one shape"),
             ("huge", {"mean": np.zeros(10**5), "var": np.ones(10**5)}, "values"),
             ("clip-inf", {"clip_obs": np.inf}, "clip_obs"), ("eps-zero", {"epsilon": 0.0}, "epsilon"),
             ("eps-array", {"epsilon": np.ones(2)}, "scalar"), ("truncated", "truncated", "readable"),
             ("not-npz", "garbage", "readable")]


@pytest.mark.parametrize(("over", "needle"), [pytest.param(o, n, id=i) for i, o, n in NPZ_CASES])
def test_bad_obs_norm_npz_isone_line(over: Any, needle: str, tmp_path: Path) -> None:
    p = tmp_path / "m_obs_norm.npz"
    if over == "truncated":
        _npz(p)
        p.write_bytes(p.read_bytes()[:150])
    elif over == "garbage":
        p.write_bytes(os.urandom(300))
    else:
        _npz(p, **over)
    with pytest.raises(ConfigError) as ex:
        from agents.evaluation.normalizer import ObsNormalizer

        ObsNormalizer.load(str(p))
    assert needle in str(ex.value) and len(str(ex.value).splitlines()) == 1


MODEL_CASES = [("obs-shape-1e9", lambda: ag_inputs.shape([10**9], "model", "observation_space._shape[]", "obs"),
                "obs[0]"),
               ("obs-shape-product", lambda: ag_inputs.shape([100, 100], "model", "observation_space._shape[]", "obs"),
                "at most 4096"),
               ("obs-shape-negative", lambda: ag_inputs.shape([-3], "model", "observation_space._shape[]", "obs"),
                "obs[0]"),
               ("net-arch-huge", lambda: ag_inputs.net_arch([200000, 200000], "net_arch"), "net_arch[0]"),
               ("net-arch-dict", lambda: ag_inputs.net_arch({"pi": [64, 10**7]}, "net_arch"), "net_arch.pi[1]"),
               ("net-arch-deep", lambda: ag_inputs.net_arch([8] * 100, "net_arch"), "at most 16"),
               ("rllib-list", lambda: ag_inputs.policy_json([1, 2], "p.json"), "a JSON mapping"),
               ("checkpoint-list", lambda: ag_inputs.checkpoint_progress([1], "ckpt"), "num_timesteps"),
               ("checkpoint-negative", lambda: ag_inputs.checkpoint_progress({"num_timesteps": -1, "iterations": 1},
                                                                             "ckpt"), "ckpt: num_timesteps"),
               ("rllib-missing", lambda: ag_inputs.policy_json({"algo": "PPO"}, "p.json"), "missing"),
               ("rllib-hiddens", lambda: ag_inputs.policy_json(
                   {"algo": "PPO", "model_config": {"fcnet_hiddens": [10**6]}, "observation_shape": [4],
                    "action_shape": [2], "action_low": [-1, -1], "action_high": [1, 1]}, "p.json"), "fcnet_hiddens"),
               ("baseline-type", lambda: ag_inputs.baseline_params("pump_off", [1], "params"), "mapping"),
               ("baseline-value", lambda: ag_inputs.baseline_params("fillage_pi", {"kp": "x"}, "params"), "params.kp"),
               ("baseline-unknown", lambda: ag_inputs.baseline_params("pump_off", {"evil": 1}, "params"), "params.evil")]


@pytest.mark.parametrize(("call", "needle"), [pytest.param(c, n, id=i) for i, c, n in MODEL_CASES])
def test_model_metadata_is_bounded_before_any_allocation(call: Any, needle: str) -> None:
    with pytest.raises(ConfigError) as ex:
        call()
    assert needle in str(ex.value) and "expected" in str(ex.value)


# ------------------------------------------------------------------------------- env kwargs and actions
ENV_CASES = [("overrides-string", {"overrides": "task.interval_s=600"}, "overrides"),
             ("overrides-int-keys", {"overrides": {1: 2}}, "overrides"),
             ("overrides-list", {"overrides": ["a"]}, "overrides"),
             ("episode-steps", {"task__episode_hours": 8760, "task__interval_s": 10}, "task.episode_hours")]


@pytest.mark.parametrize("env_id", ["srenv/SuckerRod-v0", "srenv/SuckerRod-v1"])
@pytest.mark.parametrize(("kwargs", "needle"), [pytest.param(k, n, id=i) for i, k, n in ENV_CASES])
def test_bad_env_kwargs_are_named(env_id: str, kwargs: dict, needle: str) -> None:
    import gymnasium as gym

    import srenv  # noqa: F401

    with pytest.raises(ConfigError, match=needle):
        gym.make(env_id, **kwargs)


@pytest.mark.parametrize("value", CARD_POINTS.bad_values())
def test_card_points_is_declared_and_bounded(value: Any) -> None:
    import gymnasium as gym

    import srenv  # noqa: F401

    with pytest.raises(ConfigError, match="card_points"):
        gym.make("srenv/SuckerRod-v0", card_points=value)


def test_numpy_scalars_are_numbers_and_bad_actions_are_named() -> None:
    import gymnasium as gym

    import srenv  # noqa: F401

    e = gym.make("srenv/SuckerRod-v0", control__spm_max=np.float32(8.0), card_points=np.int64(16),
                 control__max_episode_steps=np.int64(2))
    assert e.unwrapped.base_cfg.control.max_episode_steps == 2
    assert e.unwrapped.base_cfg.control.spm_max == 8.0 and e.observation_space.shape == (40,)
    e.reset(seed=0)
    for bad in ("ab", {"a": 1}, None, [1, 2, 3], [[1], [2, 3]], object(), [np.nan, 0.0]):
        with pytest.raises(ValueError, match=r"^action = .*expected 2 finite numbers"):
            e.step(bad)


# ---------------------------------------------------------------- first-round classes that still failed
def test_a_number_with_a_leading_zero_is_refused_not_read_as_octal(tmp_path: Path) -> None:
    from srenv.config import CONFIG_DIR, load_config

    text = (CONFIG_DIR / f"{FIG3}.yaml").read_text()
    import re

    (tmp_path / "w.yaml").write_text(re.sub(r"(?m)^(\s+)spm: .*$", r"\1spm: 010", text, count=1))
    with pytest.raises(ConfigError, match="010 is ambiguous"):
        load_config(tmp_path / "w.yaml")
    with pytest.raises(ConfigError, match=r"surface.spm.*'010'"):
        load_config(FIG3, ["surface.spm=010"])
    assert load_config(FIG3, ["surface.spm=10"]).surface.spm == 10


@pytest.mark.parametrize(("config", "argv", "flag"), [
    ("conventional_fig4", ["--stroke-length-m", "2.0"], "--stroke-length-m"),
    (FIG7, ["--spm", "5"], "--spm"),
    (FIG7, ["--strokes", "2"], "--strokes"),
    (FIG3, ["--pull-velocity-m-s", "1"], "--pull-velocity-m-s"),
    ("measured", ["--spm", "5"], "--spm"),
])
def test_a_flag_the_surface_motion_ignores_is_refused(config: str, argv: list[str], flag: str, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    extra = []
    if config == "measured":
        write_card(tmp_path / "card.csv")
        config, extra = FIG3, ["--set", "surface.motion=measured", "--set", "surface.measured_card_csv=card.csv"]
    rc, err = run_srenv(["simulate", config, *extra, *argv, "--out", "o.csv"], capsys)
    one_line(rc, err, flag, "surface.motion", "ignored")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize(("set_", "field", "expected"), [
    ([], "surface.measured_card_csv", "stroke period of 1 to 600 s"),  # the card reader: no such stroke exists
    (["--set", "surface.measured_spm=0.001"], "surface.measured_spm", "200000 time steps"),  # the run's size
])
def test_a_measured_cards_own_period_bounds_the_run(set_: list[str], field: str, expected: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """A 20-row card whose stroke lasts 1e5 s (or a measured_spm of 1e-3) is 1e8 time steps a stroke."""
    monkeypatch.chdir(tmp_path)
    write_card(tmp_path / "card.csv", n=20, period_s=1e5 if not set_ else 10.0)
    rc, err = run_srenv(["simulate", FIG3, "--set", "surface.motion=measured", "--set",
                      "surface.measured_card_csv=card.csv", *set_, "--strokes", "1", "--out", "o.csv"], capsys)
    one_line(rc, err, field, expected)
    assert not (tmp_path / "o.csv").exists()


def test_fit_refuses_a_param_without_effect_and_its_json_is_strict(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_card(tmp_path / "card.csv")
    rc, err = run_srenv(["fit", "card.csv", "--config", FIG3, "--param", "economics.oil_price_usd_m3",
                      "--strokes", "1", "--out", "f.yaml"], capsys)
    one_line(rc, err, "--param", "economics.oil_price_usd_m3", "change the simulated card")
    assert not (tmp_path / "f.yaml").exists()


def test_agents_benchmark_refuses_a_symlinked_output_before_any_work(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture) -> None:
    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "o"
    out.mkdir()
    (tmp_path / "target.json").write_text("keep me")
    os.symlink(tmp_path / "target.json", out / "benchmark.json")
    rc, err = run_agents(["benchmark", str(root / "configs" / "benchmark" / "v1_quick.yaml"), "--quick", "--out-dir",
                       str(out)], capsys)
    one_line(rc, err, "--out-dir", "symbolic link")
    assert (tmp_path / "target.json").read_text() == "keep me" and sorted(os.listdir(out)) == ["benchmark.json"]


def test_agents_summary_line_is_strict_json(capsys: pytest.CaptureFixture) -> None:
    from agents.cli import _print_json

    _print_json({"a": [float("nan"), np.float32("inf"), 1, np.float64(2.5)], "b": {"c": (np.nan,)}})

    def refuse(token: str) -> None:
        raise ValueError(token)
    assert json.loads(capsys.readouterr().out, parse_constant=refuse) == {"a": [None, None, 1, 2.5], "b": {"c": [None]}}



def test_fit_refuses_the_cards_own_period_as_a_parameter(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_card(tmp_path / "card.csv")
    rc, err = run_srenv(["fit", "card.csv", "--config", FIG3, "--param", "surface.measured_spm", "--out", "f.yaml"],
                        capsys)
    one_line(rc, err, "--param", "surface.measured_spm", "measured, not fitted")
    assert sorted(os.listdir(tmp_path)) == ["card.csv"]


# ------------------------------------------------------------ card contents: the one card reader's checks
_T = np.arange(200) * 10.0 / 200
CARD_CASES = [("not-closed", {"pos": _T * 0.2}), ("zero-stroke", {"pos": np.full(200, 1.0)}),
              ("loads-1e300", {"load": np.full(200, 1e300)}), ("positions-1e300", {"pos": 1e300 * (1 - np.cos(_T))})]


@pytest.mark.parametrize("over", [pytest.param(o, id=i) for i, o in CARD_CASES])
def test_a_degenerate_card_is_refused_by_diagnose(over: dict, tmp_path: Path, capsys: pytest.CaptureFixture,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    t = _T
    x = over.get("pos", 1.2 * (1 - np.cos(2 * np.pi * t / 10.0)))
    f = over.get("load", 40e3 + 8e3 * np.sin(2 * np.pi * t / 10.0))
    np.savetxt(tmp_path / "card.csv", np.c_[t, x, f], delimiter=",",
               header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")
    rc, err = run_srenv(["diagnose", "card.csv", "--config", FIG3, "--out", "p.csv"], capsys)
    one_line(rc, err, "card.csv", "expected")
    assert sorted(os.listdir(tmp_path)) == ["card.csv"]


# ------------------------------------------------------------------------ every numeric well-config field
def _config_field_cases() -> list[Any]:
    from srenv.declarations import config_fields

    return [pytest.param(key, d, optional, id=key) for key, (d, optional) in config_fields().items()]


def _raw_with_section_of(key: str) -> dict:
    """The default well, or, for a field inside an optional section the default leaves out (``surface.beam_unit``),
    the first shipped well that gives that section: the field is then checked inside a valid section."""
    from srenv.config import read_raw, shipped_configs

    def has(raw: dict) -> bool:
        node: Any = raw
        for part in key.split(".")[:-1]:
            if isinstance(node, list):
                node = node[int(part)] if part.isdigit() and int(part) < len(node) else None
            else:
                node = node.get(part) if isinstance(node, dict) else None
            if node is None:
                return False
        return True

    raw = read_raw("default")
    if has(raw):
        return raw  # (a section the YAML leaves to its defaults is built from the override alone)
    return next((r for r in (read_raw(n) for n in shipped_configs()) if has(r)), raw)


@pytest.mark.parametrize(("key", "decl", "optional"), _config_field_cases())
def test_every_numeric_config_field_refuses_bad_values(key: str, decl: Any, optional: bool) -> None:
    """Generated from the fields' own declarations (config_sections.num, via declarations.config_fields): each
    bad value is one ConfigError naming the field (null too, unless the field is optional); a field added to
    a config section is covered by construction."""
    from srenv.config import apply_overrides, config_from_dict

    raw = _raw_with_section_of(key)
    dotted = key.replace(".0.", "[0].")
    for value in decl.bad_values():
        if value is None and optional:
            continue
        with pytest.raises(ConfigError) as ex:
            config_from_dict(apply_overrides(raw, {key: value}))
        assert ex.value.field == dotted, (key, value, str(ex.value))
        assert "\n" not in str(ex.value) and "expected" in str(ex.value)
