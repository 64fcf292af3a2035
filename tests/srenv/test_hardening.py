"""Hostile or careless input, class by class (issue 13, docs/reliability.md §5).

Every bad input: exit status 2, one line on stderr naming the field, the value and what is expected (the
bound), no traceback, no output or temporary file left behind. The cases that could exhaust the machine
run the real CLI in a subprocess under an address-space limit and a timeout. Model files are data: a
pickle payload inside one never runs without --trust-model. A local sweep opens no listener beyond
loopback and leaves no process behind.
"""

from __future__ import annotations

import base64
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from srenv.config import CONFIG_DIR, MAX_YAML_BYTES
from srenv.errors import VALUE_REPR_CHARS, NumericFailure, short_repr
from srenv.tools.cli import main
from srenv.tools.finite import check_finite

ROOT = Path(__file__).resolve().parents[2]
FIG3 = "paper_fig3_vertical"
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
MEMORY_LIMIT_BYTES = 3 * 2**30


def _limited() -> None:  # preexec_fn of the subprocess cases: bounded address space
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))


def _leftovers(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir() if p.is_file() and (p.suffix in (".csv", ".png") or ".tmp" in p.name))


def _assert_refused(rc: int, err: str, d: Path, *needles: str) -> None:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == 2, err[-2000:]
    assert len(lines) == 1 and "Traceback" not in err, err[-2000:]
    assert len(lines[0]) < 600, lines[0][:200]
    for n in needles:
        assert n in lines[0], (n, lines[0])
    assert _leftovers(d) == []


# ------------------------------------------------------------------------------ inputs of `simulate`
def _bomb(depth: int) -> str:
    a = ['x0: &x0 ["lol"' + ',"lol"' * 8 + "]"] + [
        f"x{i}: &x{i} [" + ", ".join([f"*x{i - 1}"] * 9) + "]" for i in range(1, depth + 1)]
    return ("name: bomb\nrod:\n  tapers:\n    - {diameter_mm: 22.0, length_m: 624.0}\nlol:\n"
            + "\n".join("  " + s for s in a) + "\n")


def _files(d: Path) -> None:
    fig3 = (CONFIG_DIR / f"{FIG3}.yaml").read_text()
    # the same key twice in one mapping: `spm: 6` then `spm: 30` (PyYAML alone would run at 30)
    (d / "dup.yaml").write_text(re.sub(r"(?m)^(\s+)spm: .*$", r"\1spm: 6\n\1spm: 30", fig3, count=1))
    (d / "dup_top.yaml").write_text("name: x\nname: y\n" + fig3)
    (d / "bomb.yaml").write_text(_bomb(7))
    (d / "deep.yaml").write_text("a: " + "[" * 200 + "]" * 200 + "\n")
    (d / "big.yaml").write_text("# " + "x" * (MAX_YAML_BYTES + 10) + "\n" + fig3)
    (d / "dir.yaml").mkdir()
    (d / "binary.yaml").write_bytes(b"\xff\xfe\x00name: x\n")


BIGINT = "1" + "0" * 400
# (id, argv after `simulate`, substrings of the one line, run in a limited subprocess?)
SIMULATE_CASES = [
    ("missing-path", ["/no/such/dir/paper_fig3_vertical.yaml"], ["config", "no such file"], False),
    ("missing-yaml-in-cwd", ["nowhere.yaml"], ["config", "no such file"], False),
    ("unknown-name", ["paper_fig99"], ["config", "shipped name"], False),
    ("directory-path", ["dir.yaml"], ["config", "directory"], False),
    ("not-utf8", ["binary.yaml"], ["config", "UTF-8"], False),
    ("duplicate-key", ["dup.yaml"], ["config", "duplicate key 'spm'", "line"], False),
    ("duplicate-top-key", ["dup_top.yaml"], ["duplicate key 'name'"], False),
    ("yaml-alias-bomb", ["bomb.yaml"], ["config", "aliases"], True),
    ("yaml-deep-nesting", ["deep.yaml"], ["config", "nesting"], True),
    ("yaml-too-large", ["big.yaml"], ["config", f"at most {MAX_YAML_BYTES} bytes"], False),
    ("tiny-element", [FIG3, "--set", "simulation.element_length_m=1e-300"],
     ["simulation.element_length_m", "1e-300", "[1, 10000]"], True),
    ("huge-dt", [FIG3, "--set", "simulation.time_step_s=1"], ["simulation.time_step_s", "[1e-05, 0.05]"], False),
    ("dt-10", [FIG3, "--set", "simulation.time_step_s=10"], ["simulation.time_step_s"], False),
    ("tiny-dt", [FIG3, "--set", "simulation.time_step_s=1e-9"], ["simulation.time_step_s", "1e-09"], True),
    ("dt-too-many-steps-per-stroke", [FIG3, "--set", "simulation.time_step_s=1e-5"],
     ["simulation.time_step_s", "200000 steps per stroke"], True),
    ("huge-load", [FIG3, "--set", "pump.upstroke_load_n=1e308"], ["pump.upstroke_load_n", "1e+07"], False),
    ("bigint-spm", [FIG3, "--set", f"surface.spm={BIGINT}"], ["surface.spm", "integer of about 401 digits"],
     True),
    ("spm-1e308", [FIG3, "--set", "surface.spm=1e308"], ["surface.spm", "[0.1, 60]"], False),
    ("spm-90-one-stroke", [FIG3, "--spm", "90"], ["--spm", "[0.1, 60]"], False),
    ("max-corrections-1e38", [FIG3, "--set", "simulation.max_corrections=1e38"],
     ["simulation.max_corrections", "at most 1000"], False),
    ("youngs-1e308", [FIG3, "--set", "rod.tapers.0.youngs_modulus_pa=1e308"],
     ["rod.tapers[0].youngs_modulus_pa", "1e+12"], False),
    ("tiny-taper", [FIG3, "--set", "rod.tapers.0.length_m=1e-9"], ["rod.tapers[0].length_m", "[1, 10000]"],
     False),
    ("too-many-nodes", [FIG3, "--set", "rod.tapers.0.length_m=9000", "--set", "simulation.element_length_m=1",
                        "--set", "survey.stations=[]"], ["simulation.element_length_m", "2000 nodes"], True),
    ("consistent-mass-dense", [FIG3, "--set", "simulation.element_length_m=1", "--set",
                               "rod.mass_matrix=consistent"], ["element_length_m", "500 nodes"], True),
    ("always-qp-dense", [FIG3, "--set", "simulation.element_length_m=1", "--always-qp"],
     ["element_length_m", "500 nodes", "always_qp"], True),
    ("strokes-huge", [FIG3, "--strokes", "99999999999"], ["--strokes", "at most 100000"], True),
    ("strokes-too-many-samples", [FIG3, "--strokes", "1000"], ["--strokes", "1000000 recorded time steps"],
     True),
    ("duration-huge", [FIG3, "--duration-s", "1e300"], ["--duration-s", "at most"], False),
    ("plot-suffix", [FIG3, "--plot", "out.xyz"], ["--plot", "out.xyz", ".png"], False),
    ("out-suffix", [FIG3, "--out", "out.txt"], ["--out", ".csv"], False),
    ("out-is-directory", [FIG3, "--out", "dir.csv"], ["--out", "directory"], False),
    ("out-parent-missing", [FIG3, "--out", "no/such/out.csv"], ["--out", "existing directory"], False),
    ("out-unwritable", [FIG3, "--out", "/proc/out.csv"], ["--out", "writable"], False),
]


@pytest.fixture()
def workdir(tmp_path: Path) -> Path:
    _files(tmp_path)
    (tmp_path / "dir.csv").mkdir()
    return tmp_path


def _argv(args: list[str]) -> list[str]:
    extra = [] if "--out" in args else ["--out", "out.csv"]
    strokes = [] if any(a in args for a in ("--strokes", "--duration-s")) else ["--strokes", "1"]
    return ["simulate", *args, *strokes, *extra]


@pytest.mark.parametrize(("args", "needles", "subproc"), [pytest.param(a, n, s, id=i)
                                                          for i, a, n, s in SIMULATE_CASES])
def test_bad_simulate_input_is_one_line_exit_2(args: list[str], needles: list[str], subproc: bool,
                                               workdir: Path, capsys: pytest.CaptureFixture,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    if subproc:
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", *_argv(args)], check=False, cwd=workdir, env=ENV,
                           capture_output=True, text=True, timeout=60, preexec_fn=_limited)
        assert time.perf_counter() - t0 < 60
        _assert_refused(p.returncode, p.stderr, workdir, *needles)
        return
    monkeypatch.chdir(workdir)
    with pytest.raises(SystemExit) as ex:  # argparse-level refusals exit from inside main
        raise SystemExit(main(_argv(args)))
    _assert_refused(ex.value.code, capsys.readouterr().err, workdir, *needles)


FIG7 = "paper_fig7_pullout"
SWEEP = ["--param", "surface.pull_velocity_m_s", "--serial"]
SWEEP_CASES = [  # (id, config, further arguments, substrings of the one line)
    ("duration-too-many-steps", FIG7, ["--values", "0.5,3", "--duration-s", "1e5"],
     ["--duration-s", "1000000 time steps"]),
    ("duration-huge", FIG7, ["--values", "0.5,3", "--duration-s", "1e300"], ["--duration-s", "at most"]),
    ("too-many-cases", FIG7, ["--values", ",".join(str(0.01 * (i + 1)) for i in range(101)), "--grid",
                              "pump.reference_velocity_m_s=" + ",".join(str(0.1 * (i + 1)) for i in range(100))],
     ["--values", "at most 10000 cases"]),
    ("plot-suffix", FIG7, ["--values", "0.5,3", "--plot", "x.jpg"], ["--plot", ".png"]),
    ("out-directory", FIG7, ["--values", "0.5,3", "--out", "dir.csv"], ["--out", "directory"]),
    ("missing-config-path", "/no/such/paper_fig7_pullout.yaml", ["--values", "0.5,3"], ["config", "no such file"]),
]


@pytest.mark.parametrize(("config", "args", "needles"), [pytest.param(c, a, n, id=i) for i, c, a, n in SWEEP_CASES])
def test_bad_sweep_input_is_one_line_exit_2(config: str, args: list[str], needles: list[str], workdir: Path,
                                            capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(workdir)
    argv = ["sweep", config, *SWEEP, *args, *([] if "--out" in args else ["--out", "out.csv"]),
            *([] if "--duration-s" in args else ["--duration-s", "5"])]
    with pytest.raises(SystemExit) as ex:
        raise SystemExit(main(argv))
    _assert_refused(ex.value.code, capsys.readouterr().err, workdir, *needles)


def test_error_values_are_truncated() -> None:
    nested: list = ["lol"] * 9
    for _ in range(7):
        nested = [nested] * 9  # 9^8 leaves if printed in full
    t0 = time.perf_counter()
    for value in (nested, "x" * 10**6, 10**400, -(10**5000)):
        assert len(short_repr(value)) <= VALUE_REPR_CHARS
    assert time.perf_counter() - t0 < 1.0
    assert short_repr(0.02) == "0.02" and short_repr("abc") == "'abc'"


def test_valid_configs_still_load_and_bounds_are_in_the_doc() -> None:
    from srenv.config import config_doc, load_config, shipped_configs

    for name in shipped_configs():
        load_config(name)
    load_config(CONFIG_DIR / f"{FIG3}.yaml")  # a Path is a path
    assert "[1e-05, 0.05]" in config_doc() and "[0.1, 60]" in config_doc()


# ------------------------------------------------------------------------------ outputs
def test_outputs_are_0644_and_json_is_strict(tmp_path: Path, capsys: pytest.CaptureFixture,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    old = os.umask(0o022)
    try:
        assert main(["simulate", FIG3, "--strokes", "1", "--out", "out.csv", "--plot", "out.png"]) == 0
    finally:
        os.umask(old)
    line = capsys.readouterr().out.strip().splitlines()[-1]

    def refuse(token: str) -> None:
        raise ValueError(token)
    json.loads(line, parse_constant=refuse)  # NaN / Infinity would raise
    for name in ("out.csv", "out.png"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "out.png"]


def test_non_finite_results_are_a_numeric_failure() -> None:
    trace = {"t_s": np.arange(3.0), "polished_rod_load_n": np.array([1.0, np.nan, 2.0])}
    with pytest.raises(NumericFailure, match="polished_rod_load_n"):
        check_finite(trace, {})
    with pytest.raises(NumericFailure, match="pprl_n"):
        check_finite({"t_s": np.arange(3.0)}, {"pprl_n": float("inf")})
    check_finite({"t_s": np.arange(3.0)}, {"pprl_n": 1.0, "goodman_pct": [1.0, 2.0]})


def test_sigterm_during_the_write_leaves_no_temporary_file(tmp_path: Path) -> None:
    """400 strokes = 800 000 CSV rows: seconds of writing, during which the temporary file exists."""
    p = subprocess.Popen([sys.executable, "-m", "srenv.tools.cli", "simulate", FIG3, "--strokes", "400", "--out",
                          "big.csv"], cwd=tmp_path, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    try:
        deadline = time.time() + 100
        while time.time() < deadline and p.poll() is None and not any(".tmp" in f.name for f in tmp_path.iterdir()):
            time.sleep(0.05)
        assert p.poll() is None, "the run ended before its temporary file was seen"
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130 and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------ env
def test_env_refuses_an_spm_range_beyond_the_bound_and_steps_at_any_legal_spm() -> None:
    import gymnasium as gym

    import srenv  # noqa: F401
    from srenv.analysis.stroke_summary import summarize
    from srenv.config import load_config
    from srenv.errors import ConfigError
    from srenv.simulation.simulator import Simulator

    with pytest.raises(ConfigError, match=r"control.spm_max.*\[0.1, 60\]"):
        gym.make("srenv/SuckerRod-v0", control__spm_max=100)
    # a stroke (1 s at 60 SPM) shorter than the natural period (2.6 s of a 3 km string): the slip window
    # is clipped to the stroke instead of raising
    sim = Simulator(load_config(FIG3, ["rod.tapers.0.length_m=3000", "survey.stations=[]"]))
    assert 1.0 / sim.f1_hz > 1.0
    m = summarize(sim, sim.run_strokes(1, spm=60.0))
    assert np.isfinite(m["slip_amplitude_m"]) and np.isfinite(m["stick_slip_index"])
    e = gym.make("srenv/SuckerRod-v0", control__spm_max=60)
    e.reset(seed=0)
    obs, reward, *_ = e.step(np.array([1.0, 1.0], dtype=np.float32))
    assert np.all(np.isfinite(obs)) and np.isfinite(reward)


# ------------------------------------------------------------------------------ sweep: Ray and leftovers
def _descendants(pid: int) -> set[int]:
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d.name))
    out, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out


def _running(pid: int) -> bool:
    """Alive and not a zombie (an exited process whose entry init has not reaped yet holds nothing)."""
    try:
        return "\nState:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False


def _listeners() -> list[tuple[str, int]]:
    """(local address, pid) of every TCP listener, from `ss -ltnpH`."""
    out = subprocess.run(["ss", "-ltnpH"], check=False, capture_output=True, text=True, timeout=10).stdout
    found = []
    for line in out.splitlines():
        cols = line.split()
        if len(cols) >= 4:
            for pid in re.findall(r"pid=(\d+)", line):
                found.append((cols[3], int(pid)))
    return found


@pytest.mark.skipif(shutil.which("ss") is None, reason="needs ss (iproute2) to list listeners")
def test_local_sweep_listens_on_nothing_beyond_loopback_and_leaves_no_process(tmp_path: Path) -> None:
    p = subprocess.Popen([sys.executable, "-m", "srenv.tools.cli", "sweep", "paper_fig7_pullout", "--param",
                          "surface.pull_velocity_m_s", "--values", "0.5,3", "--duration-s", "5", "--workers",
                          "2", "--out", str(tmp_path / "sweep.csv")], env=ENV, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    seen: set[int] = set()
    exposed: list[tuple[str, int]] = []
    try:
        while p.poll() is None:
            tree = {p.pid} | _descendants(p.pid)
            seen |= tree
            exposed += [(a, pid) for a, pid in _listeners() if pid in tree
                        and not a.startswith(("127.", "[::1]:", "localhost:"))]
            time.sleep(0.2)
        out, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, err[-2000:]
    assert json.loads(out.strip().splitlines()[-1])["backend"] == "processes"
    assert len(seen) > 2, "the worker processes were never seen"
    assert exposed == []
    time.sleep(0.5)
    alive = [pid for pid in seen if _running(pid)]
    assert alive == []


# ------------------------------------------------------------------------------ model files are data
SHIPPED = ROOT / "models" / "ppo_default.zip"


class _Payload:
    """Unpickling this creates a file: the harmless stand-in for arbitrary code."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __reduce__(self):
        return (open, (self.path, "w"))


def _evil_model(src: Path, dst: Path, marker: Path, where: str) -> None:
    import cloudpickle
    import torch

    items = {}
    with zipfile.ZipFile(src) as z:
        items = {k: z.read(k) for k in z.namelist()}
    if where == "data":
        data = json.loads(items["data"])
        data["lr_schedule"] = {":type:": "<class 'function'>",
                               ":serialized:": base64.b64encode(cloudpickle.dumps(_Payload(str(marker)))).decode()}
        items["data"] = json.dumps(data).encode()
    else:  # policy.pth: a torch file whose pickle holds the payload
        import io

        buf = io.BytesIO()
        torch.save({"x": _Payload(str(marker))}, buf)
        items["policy.pth"] = buf.getvalue()
    with zipfile.ZipFile(dst, "w") as out:
        for k, b in items.items():
            out.writestr(k, b)


def _evaluate(policy: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "agents", "evaluate", "--policy", str(policy), "--episodes", "1",
                           "--seed", "0", "--env-kwarg", "control__max_episode_steps=2", *extra], check=False, cwd=ROOT,
                          env=ENV, capture_output=True, text=True, timeout=300)


@pytest.mark.skipif(not SHIPPED.is_file(), reason="no shipped model")
def test_a_pickle_payload_in_a_model_file_never_runs_without_trust(tmp_path: Path) -> None:
    marker = tmp_path / "PWNED"
    # data payload, JSON statistics beside it: the model loads as data and evaluates; the payload is skipped
    _evil_model(SHIPPED, tmp_path / "evil.zip", marker, "data")
    shutil.copy(SHIPPED.with_name("ppo_default_vecnormalize.json"), tmp_path / "evil_vecnormalize.json")
    p = _evaluate(tmp_path / "evil.zip")
    assert p.returncode == 0, p.stderr[-2000:]
    assert not marker.exists()
    # only pickled statistics beside it: refused in one line, saying why
    (tmp_path / "evil_vecnormalize.json").unlink()
    shutil.copy(SHIPPED.with_name("ppo_default_vecnormalize.pkl"), tmp_path / "evil_vecnormalize.pkl")
    p = _evaluate(tmp_path / "evil.zip")
    _assert_refused(p.returncode, p.stderr, tmp_path, "pickle", "--trust-model")
    assert not marker.exists()
    # payload in the weights file: torch.load(weights_only=True) refuses it
    _evil_model(SHIPPED, tmp_path / "evil2.zip", marker, "policy.pth")
    shutil.copy(SHIPPED.with_name("ppo_default_vecnormalize.json"), tmp_path / "evil2_vecnormalize.json")
    p = _evaluate(tmp_path / "evil2.zip")
    _assert_refused(p.returncode, p.stderr, tmp_path, "policy weights do not load")
    assert not marker.exists()
    # the payload is live: the trusted (SB3 + pickle) route does run it
    p = _evaluate(tmp_path / "evil.zip", "--trust-model")
    assert marker.exists()


def _agents(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str]:
    from agents.cli import main as agents_main

    try:
        rc = agents_main(argv)
    except SystemExit as ex:
        rc = ex.code
    return rc, capsys.readouterr().err


def _smoke_yaml(extra: str) -> str:
    return ("algo: ppo\nenv_kwargs: {config: default}\nn_envs: 1\nvec_env: dummy\nn_timesteps: 64\n"
            "n_steps: 32\nbatch_size: 32\n" + extra)


TRAIN_CASES = [
    ("bad-syntax", "algo: [ppo\n", ["train config", "valid YAML", "line"]),
    ("duplicate-verbose", _smoke_yaml("verbose: 0\nverbose: 1\n"), ["duplicate key 'verbose'"]),
    ("duplicate-device", _smoke_yaml("device: cpu\ndevice: cuda\n"), ["duplicate key 'device'"]),
    ("env-id-module-import", _smoke_yaml("env_id: 'evilmod:Env-v0'\n"), ["env_id", "evilmod:Env-v0", "srenv/"]),
    ("env-id-foreign", _smoke_yaml("env_id: CartPole-v1\n"), ["env_id", "CartPole-v1"]),
    ("seed-string", _smoke_yaml("seed: abc\n"), ["seed", "integer seed"]),
    ("verbose-bad", _smoke_yaml("verbose: 7\n"), ["verbose", "0, 1 or 2"]),
    ("device-bad", _smoke_yaml("device: tpu\n"), ["device", "cpu, auto"]),
    ("tensorboard-log", _smoke_yaml("tensorboard_log: /tmp/x\n"), ["tensorboard_log", "harness"]),
]


@pytest.mark.parametrize(("text", "needles"), [pytest.param(t, n, id=i) for i, t, n in TRAIN_CASES])
def test_bad_train_config_is_one_line_exit_2(text: str, needles: list[str], tmp_path: Path,
                                             capsys: pytest.CaptureFixture) -> None:
    cfg = tmp_path / "train.yaml"
    cfg.write_text(text)
    (tmp_path / "evilmod.py").write_text(f"open({str(tmp_path / 'PWNED')!r}, 'w')\n")
    rc, err = _agents(["train", str(cfg), "--out", str(tmp_path / "run")], capsys)
    _assert_refused(rc, err, tmp_path, *needles)
    assert not (tmp_path / "PWNED").exists() and not (tmp_path / "run").exists()


@pytest.mark.parametrize("kind", ["not-a-zip", "truncated", "empty", "directory"])
def test_bad_model_file_is_one_line_exit_2(kind: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    path = tmp_path / "model.zip"
    if kind == "not-a-zip":
        path.write_bytes(os.urandom(2000))
    elif kind == "truncated" and SHIPPED.is_file():
        path.write_bytes(SHIPPED.read_bytes()[: SHIPPED.stat().st_size // 2])
    elif kind == "empty" or kind == "truncated":
        path.write_bytes(b"")
    else:
        path.mkdir()
    rc, err = _agents(["evaluate", "--policy", str(path), "--episodes", "1"], capsys)
    _assert_refused(rc, err, tmp_path, str(path))


def test_resume_survives_a_truncated_history_and_keeps_the_better_best(tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture) -> None:
    from agents.training.sb3.callbacks import BEST_RECORD, _recorded_best, _restore_eval_history

    class Cb:
        def __init__(self) -> None:
            self.evaluations_timesteps: list = []
            self.evaluations_results: list = []
            self.evaluations_length: list = []
            self.best_mean_reward = -np.inf

    npz = tmp_path / "evaluations.npz"
    np.savez(npz, timesteps=np.array([64, 128]), results=np.array([[1.0], [3.0]]), ep_lengths=np.ones((2, 1)))
    cb = Cb()
    _restore_eval_history(cb, npz, 128)
    assert cb.best_mean_reward == 3.0
    npz.write_bytes(npz.read_bytes()[:100])  # a kill during the save
    cb = Cb()
    _restore_eval_history(cb, npz, 128)
    assert cb.best_mean_reward == -np.inf and "skipping evaluation history" in capsys.readouterr().err
    (tmp_path / BEST_RECORD).write_text(json.dumps({"best_mean_reward": 7.5}))
    assert _recorded_best(tmp_path) == 7.5
    (tmp_path / BEST_RECORD).write_text("{trunc")
    assert _recorded_best(tmp_path) == -np.inf


def test_a_resumed_run_does_not_replace_a_better_best_model(tmp_path: Path) -> None:
    from agents.training.config import parse_train_config
    from agents.training.sb3.callbacks import BEST_RECORD
    from agents.training.sb3.train import train

    best = tmp_path / "best"
    best.mkdir()
    (best / "best_model.zip").write_bytes(b"the better model")
    (best / BEST_RECORD).write_text(json.dumps({"best_mean_reward": 1e9}))
    cfg = parse_train_config({"algo": "ppo", "env_kwargs": {"config": "default", "control__max_episode_steps": 4},
                              "n_envs": 1, "vec_env": "dummy", "n_timesteps": 64, "checkpoint_freq": 64,
                              "eval_freq": 32, "n_eval_episodes": 1, "n_steps": 32, "batch_size": 32,
                              "n_epochs": 1, "normalize": True})
    summary = train(cfg, tmp_path, resume=True)
    assert summary["num_timesteps"] >= 64
    assert (best / "best_model.zip").read_bytes() == b"the better model"
    assert (tmp_path / "model_vecnormalize.json").is_file()  # evaluation's non-pickle statistics


def test_verbose_and_device_given_once_override_the_harness_defaults() -> None:
    from agents.training.config import parse_train_config

    cfg = parse_train_config({"algo": "ppo", "verbose": 1, "device": "cpu"})
    assert cfg.algo_kwargs == {"verbose": 1, "device": "cpu"}
