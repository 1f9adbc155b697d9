"""Charts a person looks at first (matplotlib, headless), drawn from data in memory.

Every chart of every command is made the same way: :func:`figure` opens it, the caller
draws, and on leaving the block it is laid out, saved and closed.
"""
from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np


def pyplot():
    """matplotlib.pyplot, imported at the first chart (0.3 s: a run that draws in the chart
    process, see :mod:`.chart_process`, never imports it).  No matplotlib.use(): without a
    display matplotlib falls back to Agg by itself, and forcing it would switch off inline
    figures in the notebooks that import us."""
    import matplotlib.pyplot as plt
    return plt


@contextmanager
def figure(path, figsize=(9, 4), dpi=110, **subplots):
    """``with figure(path) as (fig, ax): ...``: draw, then it is laid out, saved, closed."""
    plt = pyplot()
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
    if legend and ax.get_legend_handles_labels()[0]:   # none: matplotlib warns on stderr
        ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)


def envelope(t, y, columns: int = 1000):
    """(t, y) reduced to what ``columns`` pixel columns can show: in each of ``columns``
    runs of consecutive samples (equally many: the rows are equally spaced in t) the
    first minimum and the first maximum, in time order, and the first and last sample.

    At most 2·columns + 4 points, drawing the same picture: every column's extremes are
    kept, so impacts (the stop values, force peaks) are never lost.  No copy of y is made
    unless it holds NaN (a gap, kept as a gap).
    """
    t, y = np.asarray(t), np.asarray(y)
    n = y.size
    if n <= 2 * columns + 4:
        return t, y
    chunk = -(-n // columns)
    lo_src = hi_src = y
    if np.isnan(y.min()):            # min propagates NaN: argmin/argmax would stop at it
        lo_src, hi_src = np.where(np.isnan(y), np.inf, y), np.where(np.isnan(y), -np.inf, y)
    full = n // chunk * chunk
    starts = np.arange(0, full, chunk)
    picks = [starts + lo_src[:full].reshape(-1, chunk).argmin(axis=1),
             starts + hi_src[:full].reshape(-1, chunk).argmax(axis=1), [0, n - 1]]
    if full < n:                     # the last, shorter run
        picks.append([full + lo_src[full:].argmin(), full + hi_src[full:].argmax()])
    idx = np.unique(np.concatenate(picks))
    return t[idx], y[idx]


def _columns(fig) -> int:
    """The figure's width in pixels: no axes is wider, so no column is lost."""
    return max(100, int(fig.get_figwidth() * fig.dpi))


def plot_reduced(ax, t, y, **style):
    """``ax.plot(t, y)`` of the :func:`envelope` of y at the figure's pixel width."""
    return ax.plot(*envelope(t, y, _columns(ax.figure)), **style)


def _stop_lines(ax, stops, names=("g1", "g2")):
    """Horizontal lines at the finite ``stops``, one legend entry each."""
    for name, g, ls in zip(names, stops, ("--", "-.")):
        if g is not None and np.isfinite(g):
            ax.axhline(g, color="k", lw=1.2, ls=ls, label=f"obstacle {name} = {g:g} m")


def trajectory_chart(path, t, series: dict, stops=(), title="", ylabel="displacement (m)"):
    """Lines ``series`` (label -> values) against t, with horizontal obstacle lines
    (``stops``: g1, g2); long series are drawn reduced (:func:`envelope`)."""
    with figure(path) as (fig, ax):
        for label, y in series.items():
            plot_reduced(ax, t, y, lw=0.9, label=label)
        _stop_lines(ax, stops)
        _frame(ax, "t (s)", ylabel, title, fontsize=9)


def energy_chart(path, t, energy, title="discrete energy ½E_β", work=None, joules=False,
                 support=True):
    """½E_β against t; with ``work`` (the cumulative "damping", "input", "contact" work,
    in the units of energy) also the terms of its balance that are not all zero
    (½E_β − ½E_β[0] + damping = input + contact).  ``joules``:
    the values are in J (× ρS), else per unit mass per length (m³/s²); ``support``: the
    loads' work includes a moving support's (a beam's; a plate has none)."""
    series = {"½E_β" + ("" if joules else " (per unit mass per length)"): energy}
    if work is not None and any(np.any(w) for w in work.values()):
        labels = {"input": "work of the loads" + (" (support motion included)" if support
                                                    else ""),
                  "damping": "work lost in damping", "contact": "work of the contact forces",
                  "friction": "work of friction"}
        series.update({labels[k]: w for k, w in work.items() if np.any(w)})
    trajectory_chart(path, t, series, title=title,
                     ylabel="energy (J)" if joules else "energy (m³/s²)")


def compare_chart(path, t, computed: dict, exact: dict, title: str, ylabel: str):
    """Computed lines solid, exact ones (label -> values or None) dashed and darker, on top."""
    with figure(path) as (fig, ax):
        pairs = zip(computed.items(), list(exact.items()) + [(None, None)] * len(computed))
        for (label, y), (elabel, ye) in pairs:
            plot_reduced(ax, t, y, lw=1.0, label=label)
            if ye is not None:
                plot_reduced(ax, t, ye, lw=1.1, ls=(0, (4, 3)), color="k", alpha=0.8,
                             zorder=3, label=elabel)
        _frame(ax, "t (s)", ylabel, title, fontsize=9)


def _obstacle(ax, x, g, name, marker, color="k", label=True, elastic=False):
    """g(x) as a line where it spans an interval, as markers where it is a point stop;
    one legend entry (NaN: no obstacle; ``label`` False: none).  ``elastic``: the
    obstacles are springs (the penalty law), which the beam may press into: hollow
    markers, a dotted line."""
    finite = np.isfinite(g)
    if not finite.any():
        return
    # a run of one finite sample between NaNs is a point stop: a line would not show it
    alone = finite & ~np.r_[False, finite[:-1]] & ~np.r_[finite[1:], False]
    side = "lower" if name.startswith("g1") else "upper"
    text = f"obstacle {name} ({side}{', elastic' if elastic else ''})" if label else None
    if alone.any():
        ax.plot(x[alone], g[alone], ls="none", marker=marker, ms=11, color=color,
                mfc="none" if elastic else color,
                label=f"{text} (point stop)" if text else None)
        text = None
    if (finite & ~alone).any():
        ax.plot(x, np.where(alone, np.nan, g), color=color, lw=1.6,
                ls=":" if elastic else "--" if name.startswith("g1") else "-.", label=text)


@dataclass
class Shapes:
    """What beam_shapes.png draws, as plain arrays (computed in the command, drawn in the
    chart process): the physical displacement ũ at the points ``x`` at times ``t`` (one
    row of ``u`` each), the obstacles fixed to the ground (NaN: none) and, when the
    support carries some, those at rest (``carried``) and the support's φ at each time."""
    x: np.ndarray
    t: np.ndarray
    u: np.ndarray
    fixed: tuple
    carried: tuple | None
    phi: np.ndarray | None
    ylim: tuple
    elastic: bool = False       # the obstacles are springs (the penalty law)


def shapes(result, count=14, elastic=False) -> Shapes:
    """ũ(x, t_k) = u + h(x)φ(t_k) at ``count`` saved frames of ``result`` (finite ones,
    spread over the run), with the obstacles g1, g2: what ParaView shows, support motion
    included, for any lifting; ``elastic``: the obstacles are springs."""
    from .fields import sample_line
    line = sample_line(result.system)
    good = np.flatnonzero(np.isfinite(result.frames_u).all(axis=1))
    idx = good[np.unique(np.linspace(0, good.size - 1, min(count, good.size)).astype(int))]
    t = result.frames_t[idx]
    u = np.array([line.fields(result.frames_t[k], result.frames_u[k], result.frames_v[k],
                              result.frames_force[k])["displacement"] for k in idx])
    carried = phi = None
    fixed = (line.g1, line.g2)
    if line.carried is not None:
        carried = tuple(np.where(np.isfinite(g), g, np.nan) for g in line.carried)
        fixed = tuple(np.where(np.isfinite(g), g, np.nan) for g in line.fixed)
        phi = np.array([float(line.motion.phi(tk)) for tk in t])
    # the beam's range and the narrowest gap: obstacles far from the beam (the convex
    # ones reach ±0.75 m at the ends) would squash the curves to a line
    span = [u.min(), u.max()]
    for g, pick in ((line.g1, max), (line.g2, min)):
        if np.isfinite(g).any():
            span = [min(span[0], pick(np.nanmin(g), np.nanmax(g))),
                    max(span[1], pick(np.nanmin(g), np.nanmax(g)))]
    pad = 0.08 * (span[1] - span[0]) or 1e-3
    return Shapes(line.x, t, u, fixed, carried, phi, (span[0] - pad, span[1] + pad), elastic)


def shape_chart(path, shapes: Shapes, title=""):
    """The :class:`Shapes` of a run (papers' Figs 1–3), a colour per time.  Obstacles
    carried by a moving support are drawn at every time in that time's colour, fixed ones
    once."""
    with figure(path, figsize=(9, 4.4)) as (fig, ax):
        plt = pyplot()
        cmap = plt.get_cmap("viridis")
        t = shapes.t
        norm = plt.Normalize(t.min(), max(t.max(), t.min() + 1e-300))
        for k, (tk, ut) in enumerate(zip(t, shapes.u)):
            ax.plot(shapes.x, ut, lw=1.0, color=cmap(norm(tk)),
                    label=f"ũ(x, t) at {t.size} times" if k == 0 else None)
            if shapes.carried is not None:
                for g, name, marker in zip(shapes.carried, ("g1", "g2"), ("^", "v")):
                    _obstacle(ax, shapes.x, g + shapes.phi[k], f"{name} carried", marker,
                              cmap(norm(tk)), label=k == t.size - 1, elastic=shapes.elastic)
        _obstacle(ax, shapes.x, shapes.fixed[0], "g1", "^", elastic=shapes.elastic)
        _obstacle(ax, shapes.x, shapes.fixed[1], "g2", "v", elastic=shapes.elastic)
        ax.set_ylim(*shapes.ylim)
        bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, pad=0.01)
        bar.set_label("t (s)")
        _frame(ax, "x (m)", "ũ (m)", title, fontsize=9)


def _orbit(ax, v, w, outline, title: str, centre=(0.0, 0.0)) -> None:
    """w against v (mm) on ``ax``, with the hole's wall (``outline``, (k, 2), m): the
    orbit chart's drawing, which the wear chart draws beside its sectors."""
    ax.plot(np.asarray(v) * 1e3, np.asarray(w) * 1e3, lw=0.6, color="C0", label="orbit")
    if len(outline):
        o = np.asarray(outline) * 1e3
        ax.plot(o[:, 0], o[:, 1], color="k", lw=1.2, label="hole wall")
    ax.plot([centre[0] * 1e3], [centre[1] * 1e3], "k+")
    ax.set_aspect("equal", adjustable="datalim")
    _frame(ax, "v (mm)", "w (mm)", title, fontsize=9)


def orbit_chart(path, v, w, outline, title: str, centre=(0.0, 0.0)) -> None:
    """w against v at a support's node, with its hole's wall (``outline``, (k, 2))."""
    with figure(path, figsize=(5.5, 5.5)) as (fig, ax):
        _orbit(ax, v, w, outline, title, centre)


def _sectors(ax, wear: dict) -> None:
    """The worn depth (mm) per sector as bars round a polar ``ax``, or the volume (mm³)
    when there is no depth (no [wear] land); the angle from +v towards +w, as the orbit
    is drawn, so a bar points at the wall the orbit hits."""
    sectors = wear["sectors"]
    depth = all("depth" in k for k in sectors)
    start = np.array([k["from_rad"] for k in sectors])
    width = np.array([k["to_rad"] for k in sectors]) - start
    value = np.array([k["depth"] * 1e3 if depth else k["volume"] * 1e9 for k in sectors])
    ax.bar(start, value, width=width, align="edge", color="C3", alpha=0.7,
           edgecolor="k", lw=0.5, label="per 30° sector")
    if depth:       # the same volume worn evenly round the tube, for scale
        ax.plot(np.linspace(-np.pi, np.pi, 121), np.full(121, wear["depth_uniform"] * 1e3),
                "k--", lw=0.8, label="if worn evenly")
        ax.legend(loc="lower left", bbox_to_anchor=(-0.1, -0.12), fontsize=7)
    angles = np.arange(0, 360, 30)
    ax.set_thetagrids(angles, ["+v" if a == 0 else "+w" if a == 90 else f"{a}°"
                               for a in angles], fontsize=7)
    ax.tick_params(axis="y", labelsize=7)
    ax.set_title("worn depth (mm)" if depth else
                 "worn volume (mm³): no [wear] land, so no depth", fontsize=9)


def wear_chart(path, wear: dict, v, w, outline, title: str, centre=(0.0, 0.0)) -> None:
    """A support's wear round its hole (``wear``: its entry of summary.json's supports)
    beside the orbit of the tube's centre in the hole (as :func:`orbit_chart`)."""
    with figure(path, figsize=(10, 5), ncols=2) as (fig, (left, right)):
        left.remove()       # subplots makes its axes alike: the left one becomes polar
        _sectors(fig.add_subplot(1, 2, 1, projection="polar"), wear)
        _orbit(right, v, w, outline, "orbit of the tube's centre", centre)
        fig.suptitle(title, fontsize=9)


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


# ---------------------------------------------------------------- a sweep's bifurcation chart

# periodic values, by period; no red (the stops) and no black (the irregular values)
PERIOD_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink",
                 "tab:olive", "tab:cyan")


def bifurcation_chart(path, settings: dict, results: list[dict]) -> None:
    """The Poincaré section of a sweep's runs (:mod:`skfem_beam.sweep`) against the swept
    value, coloured by period, over their impacts per period and contact-time fraction."""
    param = settings["param"]
    label = {"omega": "support frequency ω (rad/s)", "amplitude": "support amplitude A (m)",
             "gap": "gap (m)", "k2": "k² (m⁴/s²)", "L": "L (m)"}.get(param, param)
    with figure(path, figsize=(9, 6.5), dpi=120, nrows=2, sharex=True,
                gridspec_kw={"height_ratios": [3, 1]}) as (fig, (ax, ax2)):
        periods = _sections(ax, results)
        _first_frequency(ax, ax2, param, results)
        _sweep_stops(ax, settings, results)
        bad = [r["value"] for r in results if r["status"] != "success"]
        if bad:
            ax.plot(bad, [0.0] * len(bad), "x", color="tab:red", label="run failed / unstable")
        if bad or any(periods) or ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper right", fontsize=8)
        ax.set_title(_sweep_title(settings), fontsize=9)
        ax.set_ylabel("tip displacement ũ(L, kP) (m)")
        ax.grid(alpha=0.3)
        _contact_statistics(ax2, results, label)


def _sections(ax, results: list[dict]) -> list[int]:
    """Periodic orbits in colour, one per period (1T, 2T, ...), the rest in black; the
    periods drawn."""
    periods = sorted({r.get("period") or 0 for r in results})
    for i, p in enumerate(periods):
        rs = [r for r in results if (r.get("period") or 0) == p]
        x = np.concatenate([[r["value"]] * len(r["tip_displacement"]) for r in rs] or [[]])
        y = np.concatenate([r["tip_displacement"] for r in rs] or [[]])
        color = "k" if p == 0 else PERIOD_COLORS[(i - (0 in periods)) % len(PERIOD_COLORS)]
        ax.plot(x, y, ",", color=color, alpha=0.8)
        ax.plot(x, y, ".", ms=2 if p == 0 else 3, color=color, alpha=0.5 if p == 0 else 1,
                label=f"period {p}T ({len(rs)} value{'s' * (len(rs) > 1)})" if p else None)
    return periods


def _first_frequency(ax, ax2, param: str, results: list[dict]) -> None:
    """The beam's first natural frequency, when ω is swept and every run has the same: a
    line where it lies within the swept values, else a note (the axis would stretch)."""
    f1 = {(r.get("damping") or {}).get("f1") for r in results} - {None}
    values = [r["value"] for r in results]
    if param == "omega" and len(f1) == 1 and values:
        w1 = 2 * math.pi * f1.pop()
        lo, hi = min(values), max(values)
        if not lo <= w1 <= hi:
            ax.text(0.99, 0.02, f"ω₁ = {w1:.3g} rad/s, outside the swept values",
                    transform=ax.transAxes, ha="right", va="bottom", fontsize=8,
                    color="0.3")
            return
        for a in (ax, ax2):
            a.axvline(w1, color="0.4", lw=0.8, ls=":")
        right = w1 > lo + 0.7 * (hi - lo)     # the label on the side with room
        ax.annotate(f"ω₁ = {w1:.3g}", (w1, 1.0), xycoords=("data", "axes fraction"),
                    xytext=(-2 if right else 2, -10), textcoords="offset points",
                    fontsize=8, color="0.3", ha="right" if right else "left")


def _sweep_stops(ax, settings: dict, results: list[dict]) -> None:
    """The stops at ±gap, fixed or moving with the swept value."""
    gap = settings["fixed"].get("gap")
    if gap is not None:
        for g in (-gap, gap):
            ax.axhline(g, color="tab:red", lw=0.8, ls="--",
                       label=f"stops ±{gap:g} m" if g > 0 else None)
    elif settings["param"] == "gap" and results:   # the stops move with the swept value
        xs = np.array([r["value"] for r in results])
        ax.plot(xs, xs, "--", color="tab:red", lw=0.8, label="stops ±gap")
        ax.plot(xs, -xs, "--", color="tab:red", lw=0.8)


def _sweep_title(settings: dict) -> str:
    fixed = ", ".join(f"{k}={v:g}" for k, v in settings["fixed"].items())
    zeta = settings["zeta"]
    fixed += f"; ζ={zeta:g} at f1, f2 (Rayleigh)" if zeta else "; no damping"
    return (f"{settings['scene']}: Poincaré section of the tip, once per forcing period\n"
            f"({fixed}; {settings['periods']} periods after {settings['transient']:g} s, "
            f"J={settings['J']}, β={settings['beta']:g}, Δt≈{settings['dt_target']:g} s)")


def _contact_statistics(ax2, results: list[dict], label: str) -> None:
    """Impacts per period and the contact-time fraction of the runs that succeeded."""
    ok = [r for r in results if r["status"] == "success"]
    ax2.plot([r["value"] for r in ok], [r["impacts_per_period"] for r in ok], ".-", ms=3,
             lw=0.6, color="tab:blue")
    ax2.set_ylabel("impacts / period", color="tab:blue")
    ax3 = ax2.twinx()
    ax3.plot([r["value"] for r in ok], [r["contact_fraction"] for r in ok], ".-", ms=3,
             lw=0.6, color="tab:orange")
    ax3.set_ylabel("contact-time fraction", color="tab:orange")
    ax2.set_xlabel(label)
    ax2.grid(alpha=0.3)


def deflection_chart(path, points, cells, w, title="", held=None) -> None:
    """w over the plate (mm, colour) at one frame, with the mesh's cells drawn; ``held``:
    (x, y, in contact) of the obstacles' vertices, drawn hollow, those in contact red."""
    from matplotlib.collections import PolyCollection
    tall = np.ptp(points[:, 1]) > 1.5 * np.ptp(points[:, 0])
    with figure(path, figsize=(5, 6.5) if tall else (7, 5)) as (fig, ax):
        polys = points[cells][:, :, :2]
        coll = PolyCollection(polys, array=1e3 * w[cells].mean(axis=1), cmap="viridis",
                              edgecolors="0.6", linewidths=0.3)
        ax.add_collection(coll)
        ax.set_xlim(points[:, 0].min(), points[:, 0].max())
        ax.set_ylim(points[:, 1].min(), points[:, 1].max())
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(title, fontsize=9)
        fig.colorbar(coll, ax=ax, label="w (mm), cell mean")
        if held is not None and len(held[0]):
            x, y, touching = (np.asarray(v) for v in held)
            ax.plot(x, y, "o", ms=3, mfc="none", mec="0.15", mew=0.6,
                    label="obstacles' vertices")
            if touching.any():
                ax.plot(x[touching], y[touching], "o", ms=3.5, color="tab:red",
                        label="in contact")
            ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
