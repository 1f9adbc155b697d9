"""The periodic rod against its exact solution: convergence at a fixed Courant number and
the energy drift over four periods.

    python -m skfem_beam.bench.rod_study [--N 20,40,80,160] [--courant 0.4,0.04] [--T 12]
        [--mass consistent,lumped,average] [--beta 0.25,0.5]

For each (mass, β, Courant number Δt/h, N): the L²(0, T) error of u(0, ·), the
L²(0, T; L²(0, L)) and max-in-time L²(0, L) errors of u (Gauss points inside every
element), the largest nodal penetration max(−u(0, tₙ)), the relative energy drift
(E(T) − E(0))/E(0) of the scheme's ½E_β, and the rates log₂(e_h/e_{h/2}).  The scene is
:func:`skfem_beam.scenes.periodic_rod` (L = c = 1, u0 = ½ − x/2, exact energy 1/8).
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from .. import scenes
from ..bar import l2_time, run_bar
from ..reference import exact_of

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


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="skfem_beam.bench.rod_study", description=__doc__)
    p.add_argument("--N", default="20,40,80,160")
    p.add_argument("--courant", default="0.4,0.04")
    p.add_argument("--T", type=float, default=12.0)
    p.add_argument("--mass", default="consistent,lumped,average")
    p.add_argument("--beta", default="0.25,0.5")
    args = p.parse_args(argv)
    Ns = [int(n) for n in args.N.split(",")]
    rows = []
    for mass in args.mass.split(","):
        for beta in (float(b) for b in args.beta.split(",")):
            for courant in (float(c) for c in args.courant.split(",")):
                rows += study(Ns, courant, args.T, beta, mass)
    print(table(rows))


if __name__ == "__main__":
    main()
