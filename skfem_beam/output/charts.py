"""Charts a person looks at first (matplotlib, headless), drawn from data in memory.

Every chart of every command is made the same way: :func:`figure` opens it, the caller
draws, and on leaving the block it is laid out, saved and closed.
"""
from __future__ import annotations

from contextlib import contextmanager

# no matplotlib.use(): without a display matplotlib falls back to Agg by itself, and
# forcing it here would switch off inline figures in the notebooks that import us
import matplotlib.pyplot as plt
import numpy as np


@contextmanager
def figure(path, figsize=(9, 4), dpi=110, **subplots):
    """``with figure(path) as (fig, ax): ...``: draw, then it is laid out, saved, closed."""
    fig, ax = plt.subplots(figsize=figsize, dpi=dpi, **subplots)
    try:
        yield fig, ax
        fig.tight_layout()
        fig.savefig(path)
    finally:
        plt.close(fig)


def _frame(ax, xlabel, ylabel, title="", legend=True, fontsize=None):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=fontsize)
    if legend:
        ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)


def trajectory_chart(path, t, series: dict, stops=(), title="", ylabel="displacement (m)"):
    """Lines ``series`` (label -> values) against t, with horizontal obstacle lines."""
    with figure(path) as (fig, ax):
        for label, y in series.items():
            ax.plot(t, y, lw=0.9, label=label)
        for g in stops:
            if np.isfinite(g):
                ax.axhline(g, color="k", lw=1.2, ls="--")
        _frame(ax, "t (s)", ylabel, title, legend=len(series) > 1)


def energy_chart(path, t, energy, title="discrete energy ½E_β"):
    trajectory_chart(path, t, {"energy": energy}, title=title, ylabel="energy (m³/s²)")


def compare_chart(path, t, computed: dict, exact: dict, title: str, ylabel: str):
    """Computed lines solid, exact ones (label -> values or None) dashed and darker, on top."""
    with figure(path) as (fig, ax):
        pairs = zip(computed.items(), list(exact.items()) + [(None, None)] * len(computed))
        for (label, y), (elabel, ye) in pairs:
            ax.plot(t, y, lw=1.0, label=label)
            if ye is not None:
                ax.plot(t, ye, lw=1.1, ls=(0, (4, 3)), color="k", alpha=0.8, zorder=3,
                        label=elabel)
        _frame(ax, "t (s)", ylabel, title, fontsize=9)


def shape_chart(path, result, count=14, title=""):
    """The beam u(x, t_k) at ``count`` saved frames with the obstacles (papers' Figs 1–3)."""
    system = result.system
    sampler = system.space.sampler(np.linspace(0.0, 1.0, 9))
    with figure(path) as (fig, ax):
        idx = np.unique(np.linspace(0, len(result.frames_t) - 1, count).astype(int))
        cmap = plt.get_cmap("viridis")
        for i, k in enumerate(idx):
            ax.plot(sampler.x, sampler.E0 @ result.frames_u[k], lw=0.9,
                    color=cmap(i / max(1, len(idx) - 1)),
                    label=f"t={result.frames_t[k]:.3g} s" if i in (0, len(idx) - 1) else None)
        if system.sample_x is not None and system.sample_x.size:
            for g in (system.sample_lo, system.sample_hi):
                gx = np.where(np.isfinite(g), g, np.nan)
                ax.plot(system.sample_x, gx, "k", lw=1.5)
        _frame(ax, "x (m)", "u (m)", title)


def penetration_chart(path, rows: list[dict], title=""):
    """Maximum penetration between nodes against J (log–log), one line per scene/element/side."""
    with figure(path, figsize=(7, 4.5)) as (fig, ax):
        keys = dict.fromkeys((r["scene"], r["element"]) for r in rows)
        for scene, element in keys:
            sel = [r for r in rows if r["scene"] == scene and r["element"] == element]
            J = [r["J"] for r in sel]
            for side, ls in (("below_g1", "-"), ("above_g2", "--")):
                ax.loglog(J, [r[side] for r in sel], ls, marker="o", ms=4,
                          label=f"{scene} {element}: max "
                                f"({'g1−u' if side == 'below_g1' else 'u−g2'})⁺")
            paper = [r.get(f"paper_{side}") for r in sel]
            if all(p is not None for p in paper):
                ax.loglog(J, [r["paper_below_g1"] for r in sel], ":", color="gray", lw=0.8)
        ax.set_xlabel("J (elements)")
        ax.set_ylabel("penetration between nodes (m)")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6.5)
