"""Coulomb friction in round holes, both schemes against Δt (issue 40): Moreau–Jean
(velocity level, θ = ½) and the β-scheme's position-level law ``round-hole-friction``
on the shipped friction scene.

    python -m skfem_beam.bench.friction_study [--dts 4e-4,2e-4,...] [--T 4.7]
        [--t0 0.5] [--blocks 6] [--out docs]

Each run is the scene file as a user runs it (``scenefile.load`` with
``--set contact.law=LAW``, the scene's own method, mesh, loads and [wear]) at one Δt.
Vibro-impact is chaotic, so trajectories are not compared: every statistic is a time
average over the window [t0, T] after the start's transient (the load, a sum of 64
sines 0.238 Hz apart, repeats every 4.2 s: the default window is one of its periods;
at T = 8.9 Moreau–Jean's friction Gauss–Seidel fails at Δt ≤ 2.5e-5 after 5.8 s, and a
failed run's window ends with its last whole block, status says so).
Per run and per support (a hole's node):

- ``penetration_m``: max over the whole run of |y_p − c| − r at the hole's node, from
  the saved series (every step), and ``penetration_pct`` of the clearance r;
- ``friction_W``, ``normal_W``, ``impact_W``: the support's work rates over the window
  (``output.supports``: friction −ΔW_f/Δt, normal ∫|F_n||v_t|, the scheme's contact
  work), in W; ``wear_m3_s`` = K × normal_W (the scene's [wear] coefficient K);
- ``*_se``: the standard error of the window's mean from ``--blocks`` equal blocks
  (batch means: how much of a difference is the chaos);
- ``impacts_per_s``, ``contact_fraction``: events starting in the window, the union
  of their contact intervals clipped to it, over its length;
- ``wall_s``: the time loop of the whole run.

Writes friction_study.csv and friction_study.png into --out and prints the table and
the verdict (:func:`verdict`): each scheme's error at the scene's Δt against its own
finest Δt and against the common limit (the mean of both schemes' finest values), and
the order p of |s(Δt) − s(Δt/2)| ∝ Δt^p fitted on the ladder.
"""
from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import SolverError
from ..methods import MOREAU_JEAN
from ..output.supports import support_rows, union_length
from ..parser import Parser, made_folder
from ..scenefile import example, load
from ..scenefile.build import wear
from ..semidiscrete import beam_system

SCENE = "tube_round_holes_friction"
LAWS = (MOREAU_JEAN, "round-hole-friction")
LABEL = {MOREAU_JEAN: "Moreau–Jean (θ = ½)", "round-hole-friction": "position level (β = ½)"}
FACTORS = (4, 2, 1, 0.5, 0.25, 0.125)       # × the scene's Δt
STATS = ("friction_W", "normal_W", "wear_m3_s")
COLUMNS = ("law", "dt", "T", "t0", "x", "penetration_m", "penetration_pct", "friction_W",
           "friction_W_se", "normal_W", "normal_W_se", "impact_W", "wear_m3_s",
           "wear_m3_s_se", "impacts_per_s", "contact_fraction", "wall_s", "t_end", "status")


def build(law: str, dt: float, T: float, path=None):
    """The scene file (``path``, default the shipped friction scene) with
    contact.law = ``law``, time.dt = ``dt``, time.T = ``T``: its run (not yet advanced),
    problem and Wear, as ``python -m skfem_beam run FILE --set ...`` builds them."""
    scene = load(path or example(SCENE), [f"contact.law={law}", f"time.dt={dt!r}",
                                          f"time.T={T!r}"])
    system = beam_system(scene.problem)
    stepping = replace(scene.stepping, frames=2)
    return scene.method.build(system, stepping), scene.problem, wear(scene)


def penetration(run, hole) -> float:
    """max over the saved states of |y_p − c| − r at the node of ``hole`` (a HoleAt)."""
    name = f"hole_{hole.x:g}_displacement_"
    names = list(run.system.observe)
    v = np.asarray(run.obs[:, names.index(name + "v")]) - hole.hole.centre[0]
    w = np.asarray(run.obs[:, names.index(name + "w")]) - hole.hole.centre[1]
    return float(np.max(np.hypot(v, w)) - hole.hole.radius)


def advance_in_blocks(run, t0: float, blocks: int) -> tuple[list, str]:
    """Step ``run`` to t0 and then to T in ``blocks`` equal blocks; returns the
    per-row work (Run.record's row_work) at t0 and at each block's end, with their times,
    and the status: "success", or why the run stopped (a solver's failure: the window
    then ends with the last whole block, and the row says so)."""
    n0 = int(round(t0 / run.dt))
    run.advance(n0)
    marks = [(n0 * run.dt, run.record.row_work)]
    ends = np.linspace(n0, run.n_steps, blocks + 1).round().astype(int)[1:]
    for n1 in ends:
        try:
            run.advance(int(n1))
        except SolverError as e:
            return marks, f"window cut at t = {marks[-1][0]:g} s: {e}"
        if run.status != "running" and run.status != "success":
            return marks, f"window cut at t = {marks[-1][0]:g} s: {run.message}"
        marks.append((run.n * run.dt, run.record.row_work))
    return marks, run.status


def rates(marks, rows, column: int, scale: float) -> tuple[float, float]:
    """The work rate of ``rows``' ``column`` (0 contact, 1 normal |F_n||v_t|, 2 friction)
    over the window and its batch-means standard error (scale: ρS, to W)."""
    t = np.array([m[0] for m in marks])
    w = np.array([scale * m[1][rows, column].sum() for m in marks])
    per_block = np.diff(w) / np.diff(t)
    mean = (w[-1] - w[0]) / (t[-1] - t[0])
    se = float(per_block.std(ddof=1) / math.sqrt(per_block.size)) if per_block.size > 1 \
        else math.nan
    return float(mean), se


def events_in_window(run, x: float, t0: float, T: float) -> tuple[float, float]:
    """(impacts per second, contact fraction) of the support at x over [t0, T]."""
    ev = run.impact_events()
    at = (np.asarray(ev["x"]) == x) & (np.asarray(ev["t_start"]) >= t0)
    start = np.maximum(np.asarray(ev["t_start"]), t0)
    end = np.minimum(np.asarray(ev["t_end"]), T)
    inside = (np.asarray(ev["x"]) == x) & (end > start)
    return float(at.sum() / (T - t0)), union_length(start[inside], end[inside]) / (T - t0)


def study_run(law: str, dt: float, T: float, t0: float, blocks: int = 8,
              path=None) -> list[dict]:
    """One run of the scene with ``law`` at ``dt``: a row per support (module docstring)."""
    run, problem, archard = build(law, dt, T, path)
    marks, status = advance_in_blocks(run, t0, blocks)
    t_end = marks[-1][0]
    scale = problem.beam.rho_S
    out = []
    for hole in problem.holes:
        rows = support_rows(run, hole.x)
        friction, friction_se = rates(marks, rows, 2, -scale)
        normal, normal_se = rates(marks, rows, 1, scale)
        impacts, fraction = events_in_window(run, hole.x, t0, t_end)
        pen = penetration(run, hole)
        out.append({"law": law, "dt": dt, "T": T, "t0": t0, "x": hole.x,
                    "penetration_m": pen, "penetration_pct": 100 * pen / hole.hole.radius,
                    "friction_W": friction, "friction_W_se": friction_se,
                    "normal_W": normal, "normal_W_se": normal_se,
                    "impact_W": -rates(marks, rows, 0, scale)[0],
                    "wear_m3_s": archard.coefficient * normal,
                    "wear_m3_s_se": archard.coefficient * normal_se,
                    "impacts_per_s": impacts, "contact_fraction": fraction,
                    "wall_s": run.wall, "t_end": t_end, "status": status})
    return out


def study(dts, T: float, t0: float, blocks: int = 8, laws=LAWS, path=None) -> list[dict]:
    """Every law at every Δt of ``dts``: the rows of :func:`study_run`."""
    rows = []
    for law in laws:
        for dt in dts:
            rows += study_run(law, dt, T, t0, blocks, path)
            r = rows[-1]
            print(f"  {law:20s} dt={dt:.4g}  friction {r['friction_W']:.4g} W  "
                  f"wall {r['wall_s']:.1f} s  {r['status']}", flush=True)
    return rows


def per_run(rows: list[dict], law: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(Δt, the statistic averaged over the supports) of ``law``, Δt decreasing."""
    dts = sorted({r["dt"] for r in rows if r["law"] == law}, reverse=True)
    values = [np.mean([r[name] for r in rows if r["law"] == law and r["dt"] == dt])
              for dt in dts]
    return np.array(dts), np.array(values)


def order(dts: np.ndarray, values: np.ndarray) -> float:
    """p of |s(Δt) − s(Δt/2)| ∝ Δt^p, least squares on the ladder's successive
    differences (NaN with fewer than two of them, or a zero difference)."""
    diff = np.abs(np.diff(values))
    if diff.size < 2 or np.any(diff == 0):
        return math.nan
    return float(np.polyfit(np.log(dts[:-1]), np.log(diff), 1)[0])


def errors_at(rows: list[dict], dt: float, name: str) -> dict:
    """Per law: its value at ``dt`` and its standard error, its finest-Δt value, the
    relative error against that and against the common limit (the mean of both laws'
    finest values), the order; ``noise``: 2 × the two laws' standard errors at ``dt``
    combined, relative to the common limit (a difference of errors below it is chaos)."""
    finest = {law: per_run(rows, law, name)[1][-1] for law in LAWS}
    common = float(np.mean(list(finest.values())))
    out = {"common_limit": common}
    se2 = 0.0
    for law in LAWS:
        dts, values = per_run(rows, law, name)
        k = int(np.argmin(np.abs(dts - dt)))
        se = float(per_run(rows, law, name + "_se")[1][k])
        se2 += se * se
        out[law] = {"value": float(values[k]), "se": se, "finest": float(values[-1]),
                    "error_own": abs(values[k] - values[-1]) / abs(values[-1]),
                    "error_common": abs(values[k] - common) / abs(common),
                    "order": order(dts, values)}
    out["noise"] = 2 * math.sqrt(se2) / abs(common)
    return out


def verdict(rows: list[dict], dt: float) -> tuple[bool, str]:
    """Is the position-level law's error at the scene's Δt (against the common limit) no
    worse than Moreau–Jean's, in friction work rate and wear rate, or worse by less than
    the statistics' noise?  (yes/no, the text)"""
    lines, ok = [], True
    for name in ("friction_W", "wear_m3_s"):
        e = errors_at(rows, dt, name)
        mj, pl = e[MOREAU_JEAN], e["round-hole-friction"]
        excess = pl["error_common"] - mj["error_common"]
        ok &= excess <= e["noise"]
        lines.append(
            f"{name} at Δt = {dt:g}: position level {pl['value']:.4g} ± {pl['se']:.2g} "
            f"(error {100 * pl['error_own']:.1f} % vs its finest Δt, "
            f"{100 * pl['error_common']:.1f} % vs the common limit {e['common_limit']:.4g}; "
            f"order {pl['order']:.2f}), Moreau–Jean {mj['value']:.4g} ± {mj['se']:.2g} "
            f"({100 * mj['error_own']:.1f} %, {100 * mj['error_common']:.1f} %; order "
            f"{mj['order']:.2f}); the finest values {pl['finest']:.4g} and "
            f"{mj['finest']:.4g} differ by "
            f"{100 * abs(pl['finest'] - mj['finest']) / e['common_limit']:.1f} %; noise "
            f"(2 standard errors) {100 * e['noise']:.1f} %")
    dts, pen = per_run(rows, MOREAU_JEAN, "penetration_m")
    lines.append(f"penetration: Moreau–Jean {pen[0]:.3g} … {pen[-1]:.3g} m, order "
                 f"{np.polyfit(np.log(dts), np.log(pen), 1)[0]:.2f}; position level at most "
                 f"{max(r['penetration_m'] for r in rows if r['law'] != 'moreau-jean'):.2g} m")
    cut = [f"{r['law']} Δt={r['dt']:g}" for r in rows if r["status"] != "success"]
    if cut:
        lines.append("windows cut short (status column): " + ", ".join(sorted(set(cut))))
    lines.append("verdict: the position-level law's error at the scene's Δt is "
                 + ("no worse than Moreau–Jean's (or worse by less than the noise)" if ok
                    else "WORSE than Moreau–Jean's by more than the noise")
                 + " in friction work rate and wear rate")
    return ok, "\n".join(lines)


def table(rows: list[dict]) -> str:
    """The study's rows as a Markdown table (the support at the first hole; the
    shipped scene's two supports are symmetric about mid-span and agree to round-off)."""
    first = min(r["x"] for r in rows)
    head = ("law", "Δt (s)", "penetration (m)", "% of r", "friction W", "normal W",
            "wear m³/s", "impacts/s", "contact", "wall s")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in (r for r in rows if r["x"] == first):
        lines.append(
            f"| {r['law']} | {r['dt']:.4g} | {r['penetration_m']:.2g} | "
            f"{r['penetration_pct']:.2g} | {r['friction_W']:.4f} ± {r['friction_W_se']:.4f} | "
            f"{r['normal_W']:.4f} ± {r['normal_W_se']:.4f} | {r['wear_m3_s']:.3g} | "
            f"{r['impacts_per_s']:.1f} | {r['contact_fraction']:.3f} | {r['wall_s']:.1f} |")
    return "\n".join(lines)


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, COLUMNS)
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{r[k]:.9g}" if isinstance(r[k], float) else r[k])
                             for k in COLUMNS})


def chart(rows: list[dict], dt_scene: float, path: Path) -> None:
    """Three panels against Δt, both laws on each: penetration (% of r, log-log),
    friction work rate and wear rate (log Δt, with ± the batch-means standard error)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    panels = (("penetration_pct", "max penetration at the nodes (% of r)", 1.0),
              ("friction_W", "friction work rate per support (W)", 1.0),
              ("wear_m3_s", "wear volume rate per support (mm³/year)", 1e9 * 365.25 * 86400))
    for ax, (name, title, unit) in zip(axes, panels):
        for law, mark in zip(LAWS, ("o-", "s-")):
            dts, values = per_run(rows, law, name)
            if name == "penetration_pct":
                ax.loglog(dts, np.maximum(values, 1e-16), mark, label=LABEL[law])
                continue
            se = per_run(rows, law, name + "_se")[1]
            ax.errorbar(dts, values * unit, yerr=se * unit, fmt=mark, capsize=3,
                        label=LABEL[law])
            ax.set_xscale("log")
        ax.axvline(dt_scene, color="0.6", ls=":", lw=1)
        ax.set_xticks(dts, [f"{d:g}" for d in dts], fontsize=7)
        ax.minorticks_off()
        ax.set_xlabel("Δt (s)  (dotted: the scene's)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{SCENE}.toml: Coulomb friction (μ = 0.3), statistics over "
                 f"[{rows[0]['t0']:g}, {rows[0]['T']:g}] s", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    p = Parser(prog="python -m skfem_beam.bench.friction_study",
               description=__doc__.split("\n\n")[0])
    p.add_argument("--dts", default=None, help="comma-separated Δt (s); default: the "
                   "scene's Δt × 4, 2, 1, 1/2, 1/4, 1/8")
    p.add_argument("--T", type=float, default=4.7, help="end time (s)")
    p.add_argument("--t0", type=float, default=0.5, help="start of the window (s)")
    p.add_argument("--blocks", type=int, default=6, help="blocks for the standard error")
    p.add_argument("--out", type=made_folder, default="docs",
                   help="folder for the CSV and the chart")
    args = p.parse_args(argv)
    dt_scene = load(example(SCENE)).stepping.dt
    dts = [float(d) for d in args.dts.split(",")] if args.dts else \
        [dt_scene * f for f in FACTORS]
    rows = study(dts, args.T, args.t0, args.blocks)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "friction_study.csv")
    chart(rows, dt_scene, out / "friction_study.png")
    print(table(rows))
    print(verdict(rows, dt_scene)[1])
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
