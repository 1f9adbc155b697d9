"""Speed against accuracy: error against wall time for every method, on a ladder of
resolutions (h and Δt refined together).

    python -m skfem_beam.bench.work_precision [--scene bar|point_stops|convex|all]
                                              [--out docs] [--quick]

- bar: error of u(L,·) (L² in time) against the exact solution (rigid obstacle).
- convex: L² in time of the tip displacement against a converged reference computed
  here (J and Δt finer than the ladder); the scene is not chaotic over T = 1 (a 1e-12
  perturbation stays ~1e-12), so the whole run is compared.
- point_stops: vibro-impact is chaotic, so the tip is compared only on a horizon that
  ends at the reference's second impact.
The wall time is the time loop alone (Result.wall_time_s).  Writes work_precision.csv
and work_precision.png (log–log, one line per method) into --out.
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from .. import scenes
from ..bar import errors, run_bar
from ..scheme import solve
from ..reference import BarExact
from ..semidiscrete import beam_system


def l2(e, dt):
    return float(np.sqrt(dt * np.sum(np.asarray(e) ** 2)))


def on_grid(t_ref, y_ref, t):
    return np.interp(t, t_ref, y_ref)


# ----------------------------------------------------------------------------- bar
def bar_ladder(quick: bool):
    Ns = [25, 50, 100, 200] if quick else [25, 50, 100, 200, 400]
    methods = [("contact β=1/4", dict(beta=0.25)), ("contact β=1/2", dict(beta=0.5))]
    methods += [(f"penalty k={k:g} β=1/4", dict(beta=0.25, method="penalty", k=k))
                for k in ((1e3, 1e5) if quick else (1e3, 1e4, 1e5))]
    if not quick:
        methods.insert(1, ("contact β=1/4 osqp", dict(beta=0.25, solver="osqp")))
    T = 3.0
    for label, kw in methods:
        for N in Ns:
            dt = 0.1 / N            # Courant number c·Δt/h = 0.1, as the paper's Δt = 1e-3 at N = 100
            bar = scenes.impacting_bar(N=N, k=kw.get("k", 100.0))
            run = run_bar(bar, dt, T, beta=kw["beta"], method=kw.get("method", "contact"),
                          solver=kw.get("solver", "auto"))
            exact = BarExact.of(scenes.impacting_bar(N=N), T)   # the rigid obstacle's exact solution
            e = errors(run, exact)
            yield {"scene": "bar", "method": label, "J": N, "dt": dt, "error": e["l2_uL"],
                   "error_u0": e["l2_u0"], "wall_time_s": run.result.wall_time_s,
                   "violation": float(max(0.0, -np.min(run.u0)))}


# ---------------------------------------------------------------------------- beams
def beam_rung(scene, label, kw, problem, dt, T, t_ref, y_ref) -> dict:
    """One run of a beam method; its tip error (L² in time) against the reference.
    ``violation`` is the largest penetration between nodes (for a penalty spring, its
    compression)."""
    stiff = kw.get("stiffness")
    r = solve(beam_system(problem), dt, T, kw["beta"], solver=kw.get("solver", "auto"),
              stiffness=stiff / scenes.PIPE_RHO_S if stiff else None, frames=2, progress=False)
    tip = r.observed["tip_displacement"]
    return {"scene": scene, "method": label, "J": problem.J, "dt": dt,
            "error": l2(tip - on_grid(t_ref, y_ref, r.t), dt), "wall_time_s": r.wall_time_s,
            "violation": r.max_penetration}


# -------------------------------------------------------------------------- convex
def convex_ladder(quick: bool):
    T = 1.0
    rungs = [(10, 4e-3), (20, 2e-3), (40, 1e-3), (80, 5e-4)]
    Jref, dtref = (160, 1.25e-4) if quick else (320, 6.25e-5)
    ref = solve(beam_system(scenes.convex_obstacles(J=Jref)), dtref, T, 0.5, frames=2, progress=False)
    t_ref, y_ref = ref.t, ref.observed["tip_displacement"]
    methods = [("contact β=1/2 hermite active-set", dict(beta=0.5)),
               ("contact β=1/2 bspline active-set", dict(beta=0.5, element="bspline")),
               ("contact β=1/4 hermite active-set", dict(beta=0.25))]
    if not quick:
        methods += [("contact β=1/4 bspline active-set", dict(beta=0.25, element="bspline")),
                    ("contact β=1/2 hermite daqp", dict(beta=0.5, solver="daqp")),
                    ("contact β=1/2 hermite osqp", dict(beta=0.5, solver="osqp"))]
    methods += [(f"penalty {k:g} N/m β=1/4", dict(beta=0.25, stiffness=k))
                for k in ((1e4, 1e6) if quick else (1e4, 1e5, 1e6))]
    for label, kw in methods:
        for J, dt in rungs:
            pb = scenes.convex_obstacles(J=J, element=kw.get("element", "hermite"))
            yield beam_rung("convex", label, kw, pb, dt, T, t_ref, y_ref)


# --------------------------------------------------------------------- point stops
def second_impact(t, force):
    """Time of the second rising edge of contact (chatter counts: it is an impact)."""
    on = np.abs(force) > 0
    rises = np.flatnonzero(on[1:] & ~on[:-1]) + 1
    return t[rises[1]] if rises.size > 1 else t[-1]


def point_stops_ladder(quick: bool):
    rungs = [(5, 2e-4), (10, 1e-4), (20, 5e-5), (40, 2.5e-5)]
    T = 0.3
    ref_pb = scenes.point_stops(J=80)
    ref = solve(beam_system(ref_pb), 2.5e-6 if not quick else 5e-6, T, 0.5, frames=2,
                progress=False)
    horizon = second_impact(ref.t, ref.contact_force[:, 0])
    t_ref, y_ref = ref.t, ref.observed["tip_displacement"]
    methods = [("contact β=1/2 hermite", dict(beta=0.5)),
               ("contact β=1/4 hermite", dict(beta=0.25)),
               ("contact β=1/2 bspline", dict(beta=0.5, element="bspline"))]
    if not quick:
        methods += [("contact β=1/4 bspline", dict(beta=0.25, element="bspline")),
                    ("contact β=1/2 hermite osqp", dict(beta=0.5, solver="osqp"))]
    methods += [(f"penalty {k:g} N/m β=1/4", dict(beta=0.25, stiffness=k))
                for k in ((1e6, 1e8) if quick else (1e6, 1e7, 1e8))]
    for label, kw in methods:
        for J, dt in rungs:
            pb = scenes.point_stops(J=J, element=kw.get("element", "hermite"))
            yield {**beam_rung("point_stops", label, kw, pb, dt, horizon, t_ref, y_ref),
                   "horizon_s": float(horizon)}


LADDERS = {"bar": bar_ladder, "convex": convex_ladder, "point_stops": point_stops_ladder}
TITLES = {"bar": "impacting bar (rigid): L² error of u(L,·) vs exact",
          "convex": "convex obstacles, T = 1: L² error of the tip vs converged reference",
          "point_stops": "pipe between stops: L² tip error up to the second impact"}


def chart(path: Path, rows: list[dict]):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = [s for s in LADDERS if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.2 * len(scenes), 4.8), dpi=110,
                             squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        sel = [r for r in rows if r["scene"] == scene]
        for method in dict.fromkeys(r["method"] for r in sel):
            pts = [r for r in sel if r["method"] == method]
            style = "--" if method.startswith("penalty") else "-"
            ax.loglog([max(r["wall_time_s"], 1e-5) for r in pts], [r["error"] for r in pts],
                      style, marker="o", ms=3.5, lw=1.1, label=method)
        ax.set_xlabel("wall time of the time loop (s)")
        ax.set_ylabel("error")
        ax.set_title(TITLES[scene], fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6.5, loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="skfem_beam.bench.work_precision",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="all", choices=["all", *LADDERS])
    ap.add_argument("--out", default="docs")
    ap.add_argument("--quick", action="store_true", help="fewer methods, cheaper references")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scenes = list(LADDERS) if args.scene == "all" else [args.scene]
    rows = []
    for scene in scenes:
        for row in LADDERS[scene](args.quick):
            rows.append(row)
            print(f"{row['scene']:12s} {row['method']:36s} J={row['J']:4d} dt={row['dt']:8.2e} "
                  f"error={row['error']:9.3e} loop={row['wall_time_s']:8.4f} s "
                  f"violation={row['violation']:.1e}", flush=True)
    keys = sorted({k for r in rows for k in r}, key=lambda k: list(rows[0]).index(k)
                  if k in rows[0] else 99)
    with open(out / "work_precision.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    chart(out / "work_precision.png", rows)
    print(f"written {out}/work_precision.csv and work_precision.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
