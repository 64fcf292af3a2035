"""Dynamometer cards: surface (polished rod) and downhole (pump) cards, oilfield style.

Position upward from the bottom of the stroke, load = true axial tension in kN.
"""

from __future__ import annotations

import numpy as np


def card_figure(trace: dict, title: str = "", last_stroke_s: float | None = None):
    """A matplotlib Figure with the surface card and the pump card (last stroke if given)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    t = trace["t_s"]
    sel = t >= t[-1] - last_stroke_s - 1e-9 if last_stroke_s else np.ones_like(t, dtype=bool)
    fig = Figure(figsize=(9, 3.8), dpi=100)
    ax1, ax2 = fig.subplots(1, 2)
    x = trace["polished_rod_position_m"][sel]
    ax1.plot(x - x.min(), trace["polished_rod_load_n"][sel] / 1e3, lw=1.0)
    ax1.set(xlabel="polished-rod position (m)", ylabel="polished-rod load (kN)", title="surface card")
    xp = trace["pump_position_m"][sel]
    ax2.plot(xp - xp.min(), trace["pump_load_n"][sel] / 1e3, lw=1.0, color="tab:red")
    ax2.set(xlabel="plunger position (m)", ylabel="pump load (kN)", title="pump card")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def card_rgb(trace: dict, title: str = "", last_stroke_s: float | None = None) -> np.ndarray:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = card_figure(trace, title, last_stroke_s)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def save_cards(trace: dict, path: str, title: str = "", last_stroke_s: float | None = None) -> None:
    card_figure(trace, title, last_stroke_s).savefig(path)


class CardWindow:
    """Mixin for an env rendering its cards in a matplotlib window (``render_mode="human"``): the window closes
    with the env and never travels with a pickled or copied env (SubprocVecEnv, deepcopy)."""

    _fig = None

    def close(self) -> None:
        if self._fig is not None:
            import matplotlib.pyplot as plt

            plt.close(self._fig)
            self._fig = None

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_fig"] = None  # a window does not travel
        return state
