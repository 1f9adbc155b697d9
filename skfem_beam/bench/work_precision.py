"""Every class of contact time-stepping on one chart: error against the wall time of the
time loop, on the two benchmarks with exact solutions, at two Courant numbers.

    python -m skfem_beam.bench.work_precision [--scene rod|bar|all] [--out docs] [--quick]

Classes (Doyen, Ern & Piperno's four): position-level exact enforcement (our scheme,
restitution e = 0, two settings of mass and β), penalty (one-sided springs of two
stiffnesses, β = 1/4, average mass), velocity level (Moreau–Jean, θ = 1/2, e = 0, average
mass) and modified mass (mass redistributed away from the contact node: β = 1/2, and
β = 1/4 with the massless row in equilibrium at t_{n+1}, ``massless="quasi-static"``).

Benchmarks: the periodic rod (``scenes.periodic_rod``, T = 12 = four periods) and the
impacting bar (``scenes.impacting_bar``, rigid obstacle, T = 3), each at Δt/h = 0.04 and
0.4 on a ladder of N (h and Δt refined together).  Errors against the exact solution:
L²(0, T) of u(0, ·) (the chart's error), of the contact stress, L∞(L²) and L²(L²) of u,
L²(H¹) of u and L²(L²) of u_t (Gauss points in every element, on about 1500 frames; u_t is
each scheme's own velocity: backward differences for the position and penalty schemes,
v for Moreau–Jean), the largest penetration, and the energy drift (E(T) − E)/E against
the exact energy E (1/8 and 1/2): ½E_β for the β-schemes, ½vᵀMv + ½uᵀKu for
Moreau–Jean.  The wall time is the time loop alone (Result.wall_time_s).  Writes
work_precision.csv and work_precision.png into --out (about 1 min once the kernels are
compiled).
"""
from __future__ import annotations

import argparse
import csv
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import scenes
from ..bar import bar_system, l2_time
from ..reference import exact_of
from .. import methods
from ..methods import MOREAU_JEAN
from ..scheme import solve

COURANTS = (0.04, 0.4)
BENCHMARKS = {"rod": (scenes.periodic_rod, 12.0, 0.125),
              "bar": (lambda N, mass: scenes.impacting_bar(N=N, mass=mass), 3.0, 0.5)}
# (label, class, mass, how to run): every class of the chart
METHODS = [
    ("position, average, β=1/4", "position", "average", dict(beta=0.25)),
    ("position, consistent, β=1/2", "position", "consistent", dict(beta=0.5)),
    ("penalty k=1e3, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e3)),
    ("penalty k=1e5, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e5)),
    ("Moreau–Jean θ=1/2 e=0, average", MOREAU_JEAN, "average", dict(theta=0.5)),
    ("modified mass (redistributed), β=1/2", "modified mass", "redistributed", dict(beta=0.5)),
    ("modified mass (redistributed), β=1/4, quasi-static", "modified mass", "redistributed",
     dict(beta=0.25, massless="quasi-static")),
]
STYLE = {"position": "-", "penalty": "--", MOREAU_JEAN: "-.", "modified mass": ":"}


def run_method(system, dt, T, kw, frames):
    """One run of a setting: ``kw`` holds beta, or theta (Moreau–Jean), and optionally
    stiffness (penalty), restitution e (e = 0: the papers' scheme, bit for bit) and
    massless ("beta" or "quasi-static": how a redistributed mass's massless rows step,
    see Stepping)."""
    e = kw.get("restitution", 0.0)
    if "theta" in kw:
        method = methods.MoreauJean(kw["theta"], e)
    elif "stiffness" in kw:     # per unit of the equation, as the studies give it
        method = methods.Penalty(kw["stiffness"], equation_units=True)
    else:
        method = methods.PositionLevel("auto", e, kw.get("massless", "beta"))
    return solve(system, dt, T, kw.get("beta", 0.5), frames=frames, progress=False,
                 method=method)


def field_errors(result, exact, points: int = 4) -> dict:
    """L∞(L²) and L²(L²) of u, L²(H¹) of u and L²(L²) of u_t on the result's frames."""
    space = result.system.space
    xi, w = np.polynomial.legendre.leggauss(points)
    smp = space.sampler(0.5 * (xi + 1.0))
    weights = np.tile(0.5 * w, space.J) * np.repeat(space.h, points)
    t = result.frames_t
    dtf = t[1] - t[0]
    U, V = result.frames_u, result.frames_v
    X = smp.x[None, :]
    eu = (smp.E0 @ U.T).T - exact.u(X, t[:, None])
    ev = (smp.E0 @ V.T).T - exact.velocity(X, t[:, None])
    # P1 slopes per element at its Gauss points (the nodal values of every node)
    nodal = (space.C @ U.T).T
    slope = np.repeat(np.diff(nodal, axis=1) / space.h, points, axis=1)
    ex_strain = exact.strain(X, t[:, None] + 1e-12)
    l2 = lambda e: np.sqrt((e * e) @ weights)                       # noqa: E731
    return {"linf_l2_u": float(l2(eu).max()), "l2_l2_u": l2_time(l2(eu), dtf),
            "l2_h1_u": l2_time(np.sqrt(l2(eu) ** 2 + l2(slope - ex_strain) ** 2), dtf),
            "l2_l2_ut": l2_time(l2(ev), dtf)}


def rung(scene: str, method: tuple, N: int, courant: float) -> dict:
    label, klass, mass, kw = method
    make, T, E = BENCHMARKS[scene]
    bar = make(N, mass=mass)
    system = bar_system(bar)
    dt = courant * bar.h / bar.c
    steps = int(np.ceil(T / dt - 1e-9))
    r = run_method(system, dt, T, kw, frames=min(steps, 1500))
    exact = exact_of(replace(bar, mass="average"), T)
    t = r.t
    force = r.contact_force[1:, 0]            # the force of the step tₙ → tₙ₊₁, at tₙ
    return {"scene": scene, "class": klass, "method": label, "courant": courant, "N": N,
            "dt": dt, "error": l2_time(r.observed["u0"] - exact.u(0.0, t), dt),
            "l2_stress": l2_time(force - exact.contact_force(t[:-1]), dt),
            **field_errors(r, exact), "penetration": r.max_penetration,
            # the contact node's step-to-step oscillation (a massless node at β = 1/4)
            "max_d2_u0": float(np.abs(np.diff(r.observed["u0"], 2)).max()),
            "energy_drift": float((r.energy[-1] - E) / E), "wall_time_s": r.wall_time_s,
            "status": r.status}


def rows_of(scene: str, quick: bool):
    Ns = (10, 20, 40, 80) if quick else (20, 40, 80, 160, 320)
    for method in METHODS:
        for courant in COURANTS:
            for N in Ns:
                yield rung(scene, method, N, courant)


def chart(path: Path, rows: list[dict]):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    benches = [s for s in BENCHMARKS if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(len(benches), 3, figsize=(17, 4.6 * len(benches)), dpi=100,
                             squeeze=False)
    for row_axes, scene in zip(axes, benches):
        sel = [r for r in rows if r["scene"] == scene]
        for ax, courant in zip(row_axes, COURANTS):
            for i, (label, klass, _, _) in enumerate(METHODS):
                pts = [r for r in sel if r["method"] == label and r["courant"] == courant]
                ax.loglog([max(r["wall_time_s"], 1e-5) for r in pts],
                          [r["error"] for r in pts], STYLE[klass], marker="o", ms=3.5,
                          lw=1.2, label=label, color=f"C{i}")
            ax.set_xlabel("wall time of the time loop (s)")
            ax.set_ylabel("L²(0,T) error of u(0,·)")
            ax.set_title(f"{scene}: Δt/h = {courant:g}", fontsize=10)
            ax.grid(alpha=0.3, which="both")
        row_axes[0].legend(fontsize=7, loc="best")
        ax = row_axes[2]
        for i, (label, klass, _, _) in enumerate(METHODS):   # one colour per setting
            for courant, marker in zip(COURANTS, "os"):
                pts = [r for r in sel if r["method"] == label and r["courant"] == courant]
                ax.semilogx([r["N"] for r in pts], [100 * r["energy_drift"] for r in pts],
                            STYLE[klass], marker=marker, ms=3.5, lw=1.0, color=f"C{i}",
                            label=f"{label}, Δt/h={courant:g}")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_yscale("symlog", linthresh=1.0)   # linear within ±1 %: the stiff penalty's
        ax.set_xlabel("N (elements)")             # +850 % would flatten the others'
        Ns = sorted({r["N"] for r in sel})
        ax.set_xticks(Ns, [str(n) for n in Ns], minor=False)
        ax.set_xticks([], minor=True)
        ax.set_ylabel("energy drift (E(T) − E)/E (%)")
        ax.set_title(f"{scene}: energy drift at T (○ Δt/h = 0.04, □ 0.4)", fontsize=10)
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="skfem_beam.bench.work_precision",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="all", choices=["all", *BENCHMARKS])
    ap.add_argument("--out", default="docs")
    ap.add_argument("--quick", action="store_true", help="coarser ladders (N = 10 to 80)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in (BENCHMARKS if args.scene == "all" else [args.scene]):
        for row in rows_of(scene, args.quick):
            rows.append(row)
            print(f"{scene:4s} {row['method']:51s} Δt/h={row['courant']:<5g} N={row['N']:4d} "
                  f"u(0) {row['error']:8.2e} stress {row['l2_stress']:8.2e} "
                  f"pen {row['penetration']:8.1e} drift {100 * row['energy_drift']:+7.3f} % "
                  f"loop {row['wall_time_s']:7.4f} s", flush=True)
    with open(out / "work_precision.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    chart(out / "work_precision.png", rows)
    print(f"written {out}/work_precision.csv and work_precision.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
