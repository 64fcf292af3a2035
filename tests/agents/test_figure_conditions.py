"""The episode figure shades the spans of the well's true condition (v2 names one per interval), so a reader sees
what the agent did when a condition appeared, beside the best baseline."""

import numpy as np

from agents.benchmark.figure import _condition_spans


def test_each_run_of_a_condition_is_shaded_and_labelled_once():
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    conds = ["full"] * 3 + ["fluid_pound"] * 2 + ["full"] + ["fluid_pound"] + ["tagging_down"] * 3 + [""]
    hours = np.arange(1, len(conds) + 1) * 0.5
    _condition_spans(ax, hours, conds, 0.5)
    spans = [p for p in ax.patches]
    assert len(spans) == 3  # two pound runs, one tagging run; full and "" (v1: no condition) are not shaded
    xs = sorted((round(p.get_x(), 6), round(p.get_x() + p.get_width(), 6)) for p in spans)
    assert xs[0] == (1.5, 2.5) and xs[-1] == (3.5, 5.0)
    labels = [p.get_label() for p in spans if p.get_label() and not p.get_label().startswith("_")]
    assert sorted(labels) == ["fluid pound", "tagging down"]


def test_a_v1_trace_without_conditions_draws_nothing():
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    _condition_spans(ax, np.arange(1, 4) * 1.0, ["", "", ""], 1.0)
    assert not ax.patches
