"""The quick start's main job in its fast mode: the shipped agent and the tuned pump-off on one test well."""

import json

from agents.benchmark.shipped_quickstart import quickstart_shipped
from agents.evaluation.shipped import shipped_report


def test_quickstart_fast_mode_agrees_with_the_shipped_report(tmp_path, capsys):
    res = quickstart_shipped(tmp_path, episodes=1, workers=1)
    out = capsys.readouterr().out.strip().splitlines()
    rep = json.loads(shipped_report().read_text())
    # the baseline replays the report's record exactly; the agent within torch's cross-host round-off
    assert res["record_max_rel_diff"]["pump_off"] <= 1e-9
    assert res["record_max_rel_diff"][res["agent"]] <= 0.02
    assert res["agrees_with_report"]
    assert res["lead_recorded_same_episodes"] == rep["policies"][res["agent"]]["episodes"][0]["reward"] \
        - rep["policies"]["pump_off"]["episodes"][0]["reward"]
    # the verdict, the report's own verdict, then only where the files are
    assert out[-3].startswith("This run (1 test wells): reward = USD per hour of well time")
    assert out[-2].startswith("The shipped report") and "significant (95 % CI above zero)" in out[-2]
    assert out[-1].startswith("Files: ") and not any(line.lstrip().startswith("{") for line in out[-3:])
    assert (tmp_path / "episode.png").stat().st_size > 10_000
    assert json.loads((tmp_path / "quickstart.json").read_text())["seeds"] == rep["test"]["seeds"][:1]
