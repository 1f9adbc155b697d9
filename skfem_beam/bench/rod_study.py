"""The periodic rod against its exact solution: convergence at a fixed Courant number and
the energy drift over four periods.

    python -m skfem_beam.bench.rod_study [--N 20,40,80,160] [--courant 0.4,0.04] [--T 12]
        [--mass consistent,lumped,average] [--beta 0.25,0.5]

For each (mass, β, Courant number Δt/h, N): the L²(0, T) error of u(0, ·), the
L²(0, T; L²(0, L)) and max-in-time L²(0, L) errors of u (Gauss points inside every
element), the largest nodal penetration max(−u(0, tₙ)), the relative energy drift
(E(T) − E(0))/E(0) of the scheme's ½E_β, and the rates log₂(e_h/e_{h/2}).  The scene is
:func:`skfem_beam.scenes.periodic_rod` (L = c = 1, u0 = ½ − x/2, exact energy 1/8).

    python -m skfem_beam.bench.rod_study --classes [--N 80] [--out docs]

Every class and option at one N (default 80), Δt/h = 0.04 and 0.4, T = 12, one row of
:data:`SETTINGS` each (a new option is one more row): the errors, penetration, drift and
time loop of :func:`skfem_beam.bench.work_precision.rung` (and max|Δ²u(0)|, the
contact node's step-to-step oscillation), printed as a table and written
to ``rod_study.csv`` in --out, then the best setting at each Courant number against the
issue's targets (:func:`verdict`).  About 20 s once the kernels are compiled.
"""
from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np

from .. import scenes
from ..bar import l2_time, run_bar
from ..methods import MOREAU_JEAN
from ..reference import exact_of
from .work_precision import COURANTS, rung

KEYS = ("l2_u0", "l2_u", "linf_l2_u")


def space_errors(run, exact, points: int = 5, chunk: int = 2000) -> np.ndarray:
    """‖u_h(tₙ) − u(tₙ)‖_{L²(0, L)} at every kept state (Gauss–Legendre in each element)."""
    result = run.result
    space = result.system.space
    xi, w = np.polynomial.legendre.leggauss(points)
    smp = space.sampler(0.5 * (xi + 1.0))
    weights = np.tile(0.5 * w, space.J) * np.repeat(space.h, points)
    t = result.frames_t
    keep = t <= run.t[-1] + 1e-9 * result.dt
    out = []
    for k in range(0, int(keep.sum()), chunk):
        U = result.frames_u[k:k + chunk]
        tk = t[k:k + chunk]
        e = (smp.E0 @ U.T).T - exact.u(smp.x[None, :], tk[:, None])
        out.append(np.sqrt((e * e) @ weights))
    return np.concatenate(out) if out else np.zeros(0)


def rod_row(N: int, courant: float, T: float = 12.0, beta: float = 0.25,
            mass: str = "average") -> dict:
    """One run of the periodic rod with Δt = courant·h/c, against :class:`RodExact`."""
    bar = scenes.periodic_rod(N, mass=mass)
    dt = courant * bar.h / bar.c
    run = run_bar(bar, dt, T, beta=beta, all_states_limit=10**8)
    exact = exact_of(bar, T)
    eu = space_errors(run, exact)
    E = run.energy
    return {"N": N, "courant": courant, "dt": dt, "beta": beta, "mass": mass,
            "l2_u0": l2_time(run.u0 - exact.u(0.0, run.t), dt), "l2_u": l2_time(eu, dt),
            "linf_l2_u": float(eu.max()), "penetration": run.penetration,
            "energy_drift": float((E[-1] - E[0]) / E[0]),
            "energy_max_change": float(np.abs(E - E[0]).max() / E[0]),
            "wall_time_s": run.wall_time_s}


def study(Ns=(20, 40, 80, 160), courant: float = 0.4, T: float = 12.0, beta: float = 0.25,
          mass: str = "average") -> list[dict]:
    """One row per N at a fixed Courant number; rates against the previous row."""
    rows = []
    for N in Ns:
        row = rod_row(N, courant, T, beta, mass)
        if rows:
            for key in KEYS:
                row[f"rate_{key}"] = math.log2(rows[-1][key] / row[key])
        rows.append(row)
    return rows


def table(rows: list[dict]) -> str:
    lines = [f"{'mass':>10} {'β':>5} {'Δt/h':>5} {'N':>4} {'L2 u(0)':>9} {'rate':>5} "
             f"{'L2L2 u':>9} {'rate':>5} {'maxL2 u':>9} {'rate':>5} {'penetr.':>8} "
             f"{'ΔE/E(T)':>9}"]
    for r in rows:
        rate = lambda k: f"{r[f'rate_{k}']:5.2f}" if f"rate_{k}" in r else "    -"  # noqa: E731
        lines.append(f"{r['mass']:>10} {r['beta']:5.2f} {r['courant']:5.2f} {r['N']:4d} "
                     f"{r['l2_u0']:9.2e} {rate('l2_u0')} {r['l2_u']:9.2e} {rate('l2_u')} "
                     f"{r['linf_l2_u']:9.2e} {rate('linf_l2_u')} {r['penetration']:8.1e} "
                     f"{r['energy_drift']:9.2e}")
    return "\n".join(lines)


# (label, class, mass, how to run), as work_precision.METHODS: every class and option
SETTINGS = [
    *[(f"position, {mass}, β={b}, e={e:g}", "position", mass, dict(beta=beta, restitution=e))
      for mass in ("average", "consistent", "lumped")
      for b, beta in (("1/4", 0.25), ("1/2", 0.5)) for e in (0.0, 0.5, 1.0)],
    *[(f"Moreau–Jean, average, θ={th}, e={e:g}", MOREAU_JEAN, "average",
       dict(theta=theta, restitution=e))
      for th, theta in (("1/2", 0.5), ("1", 1.0)) for e in (0.0, 1.0)],
    ("penalty k=1e3, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e3)),
    ("penalty k=1e5, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e5)),
    # massless rows "beta" (β-weighted K row) or "quasi-static" (equilibrium at t_{n+1})
    *[(f"modified mass, β={b}" + (", quasi-static" if rows == "quasi-static" else ""),
       "modified mass", "redistributed", dict(beta=beta, massless=rows))
      for b, beta, rows in (("1/2", 0.5, "beta"), ("1/4", 0.25, "beta"),
                            ("1/4", 0.25, "quasi-static"), ("1/2", 0.5, "quasi-static"))],
]
# the targets: no penetration (round-off), |drift| ≤ 0.5 % over T = 12
PENETRATION_TOL, DRIFT_TOL = 1e-12, 0.005
COLUMNS = (("penetr.", "penetration", "8.1e"), ("drift %", "energy_drift", "+8.3f"),
           ("L∞L² u", "linf_l2_u", "9.2e"), ("L²H¹ u", "l2_h1_u", "9.2e"),
           ("L²L² u_t", "l2_l2_ut", "9.2e"), ("L² σ(0)", "l2_stress", "9.2e"),
           ("L² u(0)", "error", "9.2e"), ("max|Δ²u0|", "max_d2_u0", "9.2e"),
           ("loop s", "wall_time_s", "7.4f"))


def class_rows(N: int = 80, settings=SETTINGS, courants=COURANTS):
    """One row of :func:`work_precision.rung` per setting and Courant number."""
    for setting in settings:
        for courant in courants:
            yield rung("rod", setting, N, courant)


def class_line(r: dict) -> str:
    cells = [f"{100 * r[key] if key == 'energy_drift' else r[key]:{fmt}}"
             for _, key, fmt in COLUMNS]
    return f"{r['method']:34s} {r['courant']:5g} " + " ".join(cells)


def class_header() -> str:
    return f"{'setting':34s} {'Δt/h':>5} " + " ".join(
        f"{name:>{int(fmt.split('.')[0].lstrip('+'))}}" for name, _, fmt in COLUMNS)


def meets(r: dict) -> bool:
    """Both targets: no penetration and |drift| ≤ 0.5 %."""
    return r["penetration"] <= PENETRATION_TOL and abs(r["energy_drift"]) <= DRIFT_TOL


def verdict(rows: list[dict], courant: float) -> dict:
    """At one Courant number, the row with the smallest u(0) error: of all rows ("any"),
    of those that do not penetrate ("exact"), of those that meet both targets
    ("targets"; None when no row does)."""
    sel = [r for r in rows if r["courant"] == courant and r["status"] == "success"]
    best = lambda rs: min(rs, key=lambda r: r["error"]) if rs else None  # noqa: E731
    return {"courant": courant, "any": best(sel),
            "exact": best([r for r in sel if r["penetration"] <= PENETRATION_TOL]),
            "targets": best([r for r in sel if meets(r)])}


def verdict_text(v: dict) -> str:
    lines = [f"Δt/h = {v['courant']:g}:"]
    for key, what in (("any", "smallest u(0) error"),
                      ("exact", "smallest u(0) error without penetration"),
                      ("targets", "smallest u(0) error, no penetration, |drift| ≤ 0.5 %")):
        r = v[key]
        lines.append(f"  {what}: " + ("none" if r is None else
                                     f"{r['method']} ({r['error']:.3g}, drift "
                                     f"{100 * r['energy_drift']:+.2f} %, penetration "
                                     f"{r['penetration']:.1e})"))
    return "\n".join(lines)


def classes(N: int, out: Path) -> list[dict]:
    """The study of every class: print it, write ``out``/rod_study.csv, say the verdict."""
    print(class_header(), flush=True)
    rows = []
    for row in class_rows(N):
        rows.append(row)
        print(class_line(row), flush=True)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "rod_study.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for courant in COURANTS:
        print(verdict_text(verdict(rows, courant)))
    print(f"written {out}/rod_study.csv")
    return rows


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="skfem_beam.bench.rod_study", description=__doc__)
    p.add_argument("--classes", action="store_true",
                   help="every class and option at one N (the first of --N; default 80)")
    p.add_argument("--out", default="docs", help="folder for rod_study.csv (--classes)")
    p.add_argument("--N", default=None, help="default 20,40,80,160 (80 with --classes)")
    p.add_argument("--courant", default="0.4,0.04")
    p.add_argument("--T", type=float, default=12.0)
    p.add_argument("--mass", default="consistent,lumped,average")
    p.add_argument("--beta", default="0.25,0.5")
    args = p.parse_args(argv)
    if args.classes:
        classes(int(args.N.split(",")[0]) if args.N else 80, Path(args.out))
        return
    Ns = [int(n) for n in (args.N or "20,40,80,160").split(",")]
    rows = []
    for mass in args.mass.split(","):
        for beta in (float(b) for b in args.beta.split(",")):
            for courant in (float(c) for c in args.courant.split(",")):
                rows += study(Ns, courant, args.T, beta, mass)
    print(table(rows))


if __name__ == "__main__":
    main()
