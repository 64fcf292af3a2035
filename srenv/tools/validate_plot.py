"""The figure of ``srenv validate --plot``: measured and predicted surface cards, and the diagnosed pump card
against the record's reference pump card (loads in kN, positions in m from each card's bottom)."""

from __future__ import annotations


def save_validation_plot(rec, result, pump_card, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.5), dpi=100)
    a, b = fig.subplots(1, 2)
    tr = result.trace
    x = tr["polished_rod_position_m"]
    a.plot(rec.position_m, rec.load_n / 1e3, lw=1.2, label="measured")
    a.plot(x - x.min(), tr["polished_rod_load_n"] / 1e3, lw=1.0, label="predicted (srenv)")
    a.set(xlabel="polished-rod position (m)", ylabel="load (kN)", title="surface card")
    xp = pump_card.pump_position_m
    b.plot(xp - xp.min(), pump_card.pump_load_n / 1e3, lw=1.0, color="tab:red", label="srenv diagnosis (true)")
    if rec.pump_load_n is not None:
        xr = rec.pump_position_m
        b.plot(xr - xr.min(), rec.pump_load_n / 1e3, lw=1.0, color="k", label="record's pump card (effective)")
    b.set(xlabel="plunger position (m)", ylabel="load (kN)", title="pump card")
    for ax in (a, b):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(str(rec.source)[-60:])
    fig.tight_layout()
    fig.savefig(path)
