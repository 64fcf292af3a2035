"""A report names its models by content (agents/evaluation/model_pins.py, issue 24): an agent record's ``sha256``
pins each member's zip and obs_norm; ``replay`` and ``benchmark --evaluate-only --report`` refuse, in one line and
before any episode, a member whose file differs; a record without pins (an older report) is trusted by name; new
reports (the benchmark's records, an evaluate-only report) write the pins of the files they played."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from agents.benchmark.assemble import _ensemble_record, guarded_record
from agents.cli import main
from agents.evaluation.manifest import MANIFEST, MODELS_HOME, SHIPPED_REPORTS, sha256
from agents.evaluation.model_pins import PINS, member_pins, obs_norm_path
from agents.evaluation.replay import ReplayError, load_report, policy_specs

REPO = Path(__file__).resolve().parents[2]
V2 = REPO / "docs/v2/benchmark.json"
AGENT = "oracle_distilled_ensemble"  # the shipped v2 agent
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled.yaml"  # its evaluate_only.agents: [AGENT]
A43_CONFIG = REPO / "configs/benchmark/v2_oracle_distilled_described_guarded.yaml"  # the a43 design's
A43 = [REPO / f"docs/archive/benchmark_v2_oracle_distilled_described_guarded_{s}.json" for s in ("test", "fresh")]
# d42's fits, as registered in configs/benchmark/v2_oracle_distilled_described_guarded.yaml's history
D42_SHA = {"models/oracle_distilled_v2_seed0.zip": "359b418671b20164fa823b09f38cc8594eef06b5a4fede689480546106f25463",
           "models/oracle_distilled_v2_seed1.zip": "32d4036bc512231ba8aceeda9b0ed0480856f243be2cb0c2adf03ceaede3d623",
           "models/oracle_distilled_v2_seed2.zip": "8a445f9731bcffd75a98ae8c8dcb73bc8ffbabd3ab0f7892c617688fe760f0ea",
           **{f"models/oracle_distilled_v2_seed{k}_obs_norm.npz":
              "84f9002d42c6a116eb168e0a1f3d2b053778e9df8abf1d5924173698a6cfb2b1" for k in range(3)}}
SHIPPED = sorted({*SHIPPED_REPORTS.values(), "docs/v2/fresh.json"})  # the shipped reports and v2's fresh split


def _copy(tmp: Path, rep: dict) -> Path:
    """``rep`` as TMP/benchmark.json with the shipped v2 students in TMP/models (looked in before models/)."""
    (tmp / "models").mkdir(parents=True, exist_ok=True)
    for f in MODELS_HOME.glob("oracle_distilled_v2_seed*"):
        shutil.copyfile(f, tmp / "models" / f.name)
    (tmp / "benchmark.json").write_text(json.dumps(rep))
    return tmp / "benchmark.json"


def _other_bytes(path: Path) -> None:
    path.write_bytes(path.read_bytes() + b"\0")


SEED0, NORM0 = "models/oracle_distilled_v2_seed0.zip", "models/oracle_distilled_v2_seed0_obs_norm.npz"
# each way a pinned member is not what the report played: (change to the copy, the files or the record; needles)
WRONG = {
    "zip-differs": (lambda d, p: _other_bytes(d / SEED0), [f'sha256["{SEED0}"]', "the report recorded", "found"]),
    "obs-norm-differs": (lambda d, p: _other_bytes(d / NORM0), [f'sha256["{NORM0}"]', "with sha256"]),
    "obs-norm-missing": (lambda d, p: (d / NORM0).unlink(), [f'sha256["{NORM0}"]', "no such file"]),
    "obs-norm-not-played": (lambda d, p: p.update({NORM0: None}), [f'sha256["{NORM0}"]', "played without it"]),
    "no-entry": (lambda d, p: p.pop(SEED0), ["no entry for " + SEED0]),
    "bad-digest": (lambda d, p: p.update({SEED0: "beef"}), ["64 lowercase hex digits"]),
}


def _wrong(tmp: Path, case: str) -> Path:
    rep = json.loads(V2.read_text())
    path = _copy(tmp, rep)
    change, _ = WRONG[case]
    change(tmp, rep["policies"][AGENT][PINS])
    path.write_text(json.dumps(rep))
    return path


COMMANDS = {"replay": lambda rep, out: ["replay", str(rep), "--policy", AGENT, "--episodes", "1"],
            "evaluate-only": lambda rep, out: ["benchmark", str(CONFIG), "--evaluate-only", "--fresh-seed", "1",
                                               "--episodes", "1", "--report", str(rep), "--out-dir", str(out)]}


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("case", sorted(WRONG))
def test_a_member_that_is_not_the_played_file_is_refused_in_one_line(tmp_path, capsys, command, case) -> None:
    rep = _wrong(tmp_path / "rep", case)
    code = main(COMMANDS[command](rep, tmp_path / "out"))
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1, err  # before any episode: nothing printed, nothing written
    assert f"policies.{AGENT}.{PINS}" in lines[0] and all(n in lines[0] for n in WRONG[case][1]), lines[0]
    assert not (tmp_path / "out" / "benchmark.json").exists()


def test_the_mismatch_line_names_both_digests_and_where_the_file_is_expected(tmp_path) -> None:
    rep = _wrong(tmp_path, "zip-differs")
    with pytest.raises(ReplayError) as exc:
        policy_specs(load_report(rep), AGENT, tmp_path)
    msg = str(exc.value)
    assert sha256(MODELS_HOME / Path(SEED0).name) in msg and sha256(tmp_path / SEED0) in msg
    assert f"put it at {tmp_path / SEED0}" in msg


@pytest.mark.parametrize("path", A43, ids=["test-look", "fresh-look"])
def test_the_a43_reports_refuse_the_shipped_students_of_the_same_name(tmp_path, capsys, path) -> None:
    """The trap closed: the looks played d42's fits, which share the shipped students' file names; replaying or
    re-evaluating those reports from a checkout found models/'s students and played another policy without a word."""
    name = "oracle_distilled_guarded"
    assert json.loads(path.read_text())["policies"][name][PINS] == D42_SHA
    for args in (["replay", str(path), "--policy", name, "--episodes", "1"],
                 ["benchmark", str(A43_CONFIG), "--evaluate-only", "--fresh-seed", "1", "--episodes", "1",
                  "--report", str(path), "--out-dir", str(tmp_path / "out")]):
        code = main(args)
        out, err = capsys.readouterr()
        assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
        assert f'policies.{name}.{PINS}["{SEED0}"]' in err, err
        assert D42_SHA[SEED0] in err and sha256(MODELS_HOME / Path(SEED0).name) in err, err


@pytest.mark.parametrize("rel", SHIPPED)
def test_the_shipped_reports_pin_the_files_in_models(rel: str) -> None:
    """Each shipped report's agents pin exactly the files models/MANIFEST.json lists, and they rebuild from models/."""
    manifest = json.loads((MODELS_HOME / MANIFEST).read_text())["files"]
    rep = load_report(REPO / rel)
    agents = [n for n, p in rep["policies"].items() if p["kind"] == "agent"]
    assert agents
    for n in agents:
        pins, models = rep["policies"][n][PINS], rep["policies"][n]["models"]
        assert set(pins) == {*models, *(obs_norm_path(m).as_posix() for m in models)}, n
        assert all(d == manifest[Path(ref).name]["sha256"] for ref, d in pins.items()), n
        assert policy_specs(rep, n, (REPO / rel).parent)  # the files in models/ pass the check


def test_an_older_record_without_pins_is_trusted_by_name(tmp_path) -> None:
    rep = json.loads(V2.read_text())
    pinned = policy_specs(rep, AGENT, V2.parent)
    del rep["policies"][AGENT][PINS]
    path = _copy(tmp_path, rep)
    _other_bytes(tmp_path / SEED0)  # another file of that name: read as before, unchecked
    old = policy_specs(load_report(path), AGENT, tmp_path)
    assert [m["path"] for m in old[0]["members"]] == [str((tmp_path / m).resolve()) for m in
                                                      rep["policies"][AGENT]["models"]]
    assert old[0]["residual"] == pinned[0]["residual"] and len(old) == len(pinned) == 1


def _members(tmp: Path, norms: bool = True) -> list[dict]:
    out = []
    for k in range(2):
        z = tmp / f"x_seed{k}.zip"
        z.write_bytes(bytes([k]) * 10)
        if norms:
            obs_norm_path(z).write_bytes(bytes([k + 7]) * 10)
        out.append({"kind": "agent", "path": str(z), "obs_norm": str(obs_norm_path(z)) if norms else None})
    return out


def test_new_records_pin_every_member_file(tmp_path) -> None:
    members = _members(tmp_path)
    runs = {"r": {"config": "configs/train/ppo_residual_v2.yaml", "seeds": [0, 1]}}
    rec = _ensemble_record({"kind": "ensemble", "members": members, "of": "r"}, runs, [])
    assert rec["models"] == ["models/x_seed0.zip", "models/x_seed1.zip"]
    assert rec[PINS] == {"models/x_seed0.zip": sha256(tmp_path / "x_seed0.zip"),
                         "models/x_seed0_obs_norm.npz": sha256(tmp_path / "x_seed0_obs_norm.npz"),
                         "models/x_seed1.zip": sha256(tmp_path / "x_seed1.zip"),
                         "models/x_seed1_obs_norm.npz": sha256(tmp_path / "x_seed1_obs_norm.npz")}
    spec = {"inner": {"kind": "ensemble", "members": members}, "of": "r",
            "fallback": {"name": "pump_off", "params": {}}, "guard": {}}
    assert guarded_record(spec, runs, [])[PINS] == rec[PINS]
    (tmp_path / "plain").mkdir()
    plain = _members(tmp_path / "plain", norms=False)
    assert member_pins(["models/a.zip", "models/b.zip"], plain) == {
        "models/a.zip": sha256(Path(plain[0]["path"])), "models/a_obs_norm.npz": None,
        "models/b.zip": sha256(Path(plain[1]["path"])), "models/b_obs_norm.npz": None}
    with pytest.raises(ValueError, match="2 model names for 1 members"):
        member_pins(["models/a.zip", "models/b.zip"], plain[:1])


@pytest.fixture(scope="module")
def fresh_out(tmp_path_factory):
    """A short evaluate-only run (15-minute episodes, one fresh well) on a pinned copy of the shipped v2 report."""
    from agents.benchmark.fresh import evaluate_fresh

    tmp = tmp_path_factory.mktemp("pins")
    rep = _copy(tmp / "rep", json.loads(V2.read_text()))
    cfg = tmp / "fresh.yaml"
    cfg.write_text("env_id: srenv/SuckerRod-v2\nenv_kwargs: {observation: field, episode_hours: 0.25}\n"
                   "workers: 1\ntuning: {scenario: train, seeds: [0]}\ntest: {seeds: [100000]}\n"
                   f"evaluate_only: {{agents: [{AGENT}], references: {{}}}}\n")
    evaluate_fresh(str(cfg), 11, 1, tmp / "out", report=rep)  # a right digest plays
    return tmp / "out" / "benchmark.json"


def test_an_evaluate_only_report_pins_what_it_played_and_replay_reproduces_it(fresh_out, capsys, tmp_path) -> None:
    rep = json.loads(fresh_out.read_text())
    manifest = json.loads((MODELS_HOME / MANIFEST).read_text())["files"]
    pins = rep["policies"][AGENT][PINS]
    assert pins and all(d == manifest[Path(ref).name]["sha256"] for ref, d in pins.items())
    code = main(["replay", str(fresh_out), "--policy", AGENT, "--policy", "pump_off", "--episodes", "1"])
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and res["reproduced"], res  # pinned files found in models/: they play, the same returns
    del rep["policies"][AGENT][PINS]  # the same report as an older one: it plays as before
    (tmp_path / "old.json").write_text(json.dumps(rep))
    code = main(["replay", str(tmp_path / "old.json"), "--policy", AGENT, "--episodes", "1"])
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and res["reproduced"], res
