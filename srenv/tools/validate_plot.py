"""The figure of ``srenv validate --plot``: measured and predicted surface cards, and the diagnosed pump card
against the record's reference pump card (loads in kN, positions in m from each card's bottom)."""

from __future__ import annotations

from ..analysis.diagnose import load_in_convention


def pump_card_lines(rec, pump_card, convention: str) -> list[tuple]:
    """The pump card panel's lines (positions from each card's bottom, N): srenv's diagnosis in ``convention``
    and the record's own card (effective loads, as vendors give them), so the panel shows what is compared."""
    fp = load_in_convention(pump_card.pump_load_n, convention, pump_card.rod_end_pressure_pa, pump_card.rod_end_area_m2)
    xp = pump_card.pump_position_m
    lines = [(xp - xp.min(), fp, f"srenv diagnosis ({convention})", {"color": "tab:red"})]
    if rec.pump_load_n is not None:
        xr = rec.pump_position_m
        lines.append((xr - xr.min(), rec.pump_load_n, "record's pump card (its own, effective)", {"color": "k"}))
    return lines


def save_validation_plot(rec, result, pump_card, path: str, convention: str = "effective") -> None:
    """Both pump cards in ``convention`` (the one the figures compare: srenv's true loads + p A at the rod end
    for ``effective``); a measured card placed on its unit's motion is labelled so."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.5), dpi=100)
    a, b = fig.subplots(1, 2)
    tr = result.trace
    x = tr["polished_rod_position_m"]
    a.plot(rec.position_m, rec.load_n / 1e3, lw=1.2,
           label="measured (on the unit's motion)" if getattr(rec, "motion_from_unit", False) else "measured")
    a.plot(x - x.min(), tr["polished_rod_load_n"] / 1e3, lw=1.0, label="predicted (srenv)")
    a.set(xlabel="polished-rod position (m)", ylabel="load (kN)", title="surface card")
    for xs, fs, label, style in pump_card_lines(rec, pump_card, convention):
        b.plot(xs, fs / 1e3, lw=1.0, label=label, **style)
    b.set(xlabel="plunger position (m)", ylabel="load (kN)", title="pump card")
    for ax in (a, b):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(str(rec.source)[-60:])
    fig.tight_layout()
    fig.savefig(path)
