"""The quick start's main job in its fast mode: the shipped agent of each env version and its tuned baselines on
one test well, the verdicts (with the constraint costs), and nothing but file locations after them."""

import json

from agents.benchmark.shipped_quickstart import cost_note, quickstart_shipped
from agents.evaluation.shipped import shipped_report


def test_quickstart_v1_agrees_with_the_shipped_report(tmp_path, capsys):
    res = quickstart_shipped(tmp_path, episodes=1, workers=1, version="v1")
    out = capsys.readouterr().out.strip().splitlines()
    rep = json.loads(shipped_report("v1").read_text())
    # the baseline replays the report's record exactly; the agent within torch's cross-host round-off
    assert res["record_max_rel_diff"]["pump_off"] <= 1e-9
    assert res["record_max_rel_diff"][res["agent"]] <= 0.02
    assert res["agrees_with_report"]
    assert res["lead_recorded_same_episodes"] == rep["policies"][res["agent"]]["episodes"][0]["reward"] \
        - rep["policies"]["pump_off"]["episodes"][0]["reward"]
    # the verdict, the report's own verdict, then only where the files are
    assert out[-3].startswith("This run (1 test wells): reward = USD per hour of well time")
    assert out[-2].startswith("The shipped report") and "significant (95 % CI above zero)" in out[-2]
    assert "Constraint cost per episode: ppo_residual_distilled_ensemble 2.28 vs pump_off 2.26" in out[-2]
    assert out[-1].startswith("Files: ") and not any(line.lstrip().startswith("{") for line in out[-3:])
    assert (tmp_path / "episode.png").stat().st_size > 10_000
    assert json.loads((tmp_path / "quickstart.json").read_text())["seeds"] == rep["test"]["seeds"][:1]


def test_quickstart_v2_plays_the_shipped_v2_agent_and_says_the_fresh_split_cost_loss(tmp_path, capsys):
    res = quickstart_shipped(tmp_path, episodes=1, workers=1)  # v2 is the default
    out = capsys.readouterr().out.strip().splitlines()
    rep = json.loads(shipped_report("v2").read_text())
    assert res["agent"] == "oracle_distilled_ensemble" and rep["env_id"] == "srenv/SuckerRod-v2"
    for base in ("fillage_pi", "alarm_pump_off"):  # played now, the field controllers replay their record exactly
        assert res["record_max_rel_diff"][base] <= 1e-9, base
    assert res["record_max_rel_diff"][res["agent"]] <= 0.02 and res["agrees_with_report"]
    table = "\n".join(out[:-5])
    assert "| installed | report record |" in table and "| pump_off | report record |" in table
    # the test look played no oracle: the causal oracle plays the same well now, the top of the normalised score
    assert "| causal_oracle | ran now | " in table and " | 1.00 | " in table.split("causal_oracle")[1].split("\n")[0]
    assert res["summary"]["causal_oracle"]["normalised_score"] == 1.0
    assert 0.0 < res["summary"][res["agent"]]["normalised_score"] < 1.5
    assert "(0 installed, 1 causal_oracle)" in out[-4]
    assert out[-4].startswith("This run (1 test wells): ") and "Constraint cost per episode" in out[-4]
    assert out[-3].startswith("The shipped report (100 test episodes")
    assert "+10.91 USD/h" in out[-3] and "vs fillage_pi 10.10 (LOWER" in out[-3]
    # the headline on fresh wells, its cost condition failed: said, not hidden
    assert out[-2].startswith("Fresh wells (40 drawn at run time, seed 20261203")
    assert "+9.33 USD/h" in out[-2] and "vs alarm_pump_off 4.59 (HIGHER" in out[-2]
    assert out[-1].startswith("Files: ") and not any(line.lstrip().startswith("{") for line in out[-4:])


def test_cost_note_compares_the_best_agent_with_the_best_tuned_baseline():
    def s(kind, reward, cost):
        return {"kind": kind, "mean_reward": reward, "mean_cost": cost}

    rep = {"summary": {"a": s("agent", 5, 3.0), "b": s("agent", 1, 0.1), "x": s("baseline", 4, 2.0),
                       "y": s("baseline", 2, 9.0), "causal_oracle": s("baseline", 9, 0.0)}}
    assert cost_note(rep) == "Constraint cost per episode: a 3.00 vs x 2.00 (HIGHER, +50.0 %)."
    rep["summary"]["x"]["mean_cost"] = 3.0
    assert cost_note(rep).endswith("(the same).")
    assert cost_note({"summary": {"x": s("baseline", 1, 1.0)}}) == ""
