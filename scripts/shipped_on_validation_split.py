"""The shipped v2 ensemble beside alarm_pump_off on the v2 validation split's episodes of f24's gate (seeds
21200..21215, wells validation-000..015, which no tuning or training drew): a measurement, nothing chosen on it.

    PYTHONPATH=. python scripts/shipped_on_validation_split.py > docs/archive/shipped_on_validation_split.json
"""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help, and no other flag
    import oracle_distill_more as m
    from guard_pilot import play_validation

    from agents.policies.ensemble import ensemble_spec

    cfg, _name, _run, _tuned, res = m.setup()
    g = json.loads(Path("docs/archive/oracle_distill_capped.json").read_text())["gate"]
    seeds = g["seeds"]
    assert g["scenario"] == "validation"
    specs = {"alarm_pump_off": g["specs"]["alarm_pump_off"],
             "shipped_ensemble": ensemble_spec(m.students(m.SHIPPED, "oracle_distilled", m.SHIPPED_SEEDS, res))}
    gcfg = {**cfg, "validation": {"seeds": seeds, "scenario": "validation"}}
    eps = play_validation(gcfg, specs, Path("runs/shipped_validation"), 2)
    summ = m.summarise(eps, ("alarm_pump_off",))
    same = [round(e["reward"] / 144, 3) for e in eps["alarm_pump_off"]] == g["per_episode_usd_h"]["alarm_pump_off"]
    print(json.dumps({"command": "PYTHONPATH=. python scripts/shipped_on_validation_split.py", "seeds": seeds,
                      "scenario": "validation", "summary": summ, "alarm_equals_f24_gate": same}, indent=1))


if __name__ == "__main__":
    main()
