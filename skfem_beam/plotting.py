"""Charts a person looks at first (matplotlib, headless)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def trajectory_chart(path, t, series: dict, stops=(), title="", ylabel="displacement (m)"):
    """Lines ``series`` (label -> values) against t, with horizontal obstacle lines."""
    fig, ax = plt.subplots(figsize=(9, 4), dpi=110)
    for label, y in series.items():
        ax.plot(t, y, lw=0.9, label=label)
    for g in stops:
        if np.isfinite(g):
            ax.axhline(g, color="k", lw=1.2, ls="--")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if len(series) > 1:
        ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def energy_chart(path, t, energy, title="discrete energy ½E_β"):
    trajectory_chart(path, t, {"energy": energy}, title=title, ylabel="energy (m³/s²)")
