"""Convergence of the impacting bar against its exact solution (Δt ∝ h).

    python -m skfem_beam.bench.bar_convergence [--N 25,50,100,200,400] [--courant 0.1]
        [--mass average] [--beta 0.25] [--T 3] [--obstacle rigid,elastic] [--k 100]

For each mesh: the L²-in-time errors of u(0,·), u(L,·) and of the reaction R (see
:func:`skfem_beam.bar.errors`), the rates log₂(e_{h}/e_{h/2}), the penetration, the
energy lost over the first contact and the time-loop wall time.  Example 1 of Do,
Raupp & Feijoo: a = ρ = L = 1, b = 0, f = 0, v0 = −1.
"""
from __future__ import annotations

import math

from .. import scenes
from ..bar import energy_report, errors, run_bar
from ..parser import Parser, counts
from ..reference import BarExact

KEYS = ("l2_u0", "l2_uL", "l2_force")


def study(obstacle: str = "rigid", Ns=(25, 50, 100, 200, 400), courant: float = 0.1,
          T: float = 3.0, beta: float = 0.25, method: str = "contact",
          **bar_kw) -> list[dict]:
    """One row per mesh N, with Δt = courant·h/c; rates against the previous row.
    ``bar_kw``: the bar's other data (:class:`~skfem_beam.bar.Bar`: mass "average", the
    elastic obstacle's k = 100 unless given)."""
    rows = []
    for N in Ns:
        bar = scenes.impacting_bar(obstacle=obstacle, N=N, **bar_kw)
        dt = courant * bar.h / bar.c
        run = run_bar(bar, dt, T, beta=beta, method=method)
        row = {"N": N, "dt": dt, **errors(run, BarExact.of(bar, T)),
               "penetration": run.penetration,
               "energy_loss_relative": energy_report(run).get("energy_loss_relative"),
               "wall_time_s": run.wall_time_s}
        if rows:
            for key in KEYS:
                row[f"rate_{key}"] = math.log2(rows[-1][key] / row[key])
        rows.append(row)
    return rows


def table(rows: list[dict], title: str = "") -> str:
    head = (f"{'N':>5} {'dt':>9} {'L2 u(0)':>10} {'rate':>5} {'L2 u(L)':>10} {'rate':>5} "
            f"{'L2 R':>10} {'rate':>5} {'penetr.':>9} {'E lost/E':>9} {'wall s':>7}")
    lines = [title, head] if title else [head]
    for r in rows:
        rate = lambda k: f"{r[f'rate_{k}']:5.2f}" if f"rate_{k}" in r else "    -"  # noqa: E731
        loss = r["energy_loss_relative"]
        lines.append(f"{r['N']:5d} {r['dt']:9.3g} {r['l2_u0']:10.3e} {rate('l2_u0')} "
                     f"{r['l2_uL']:10.3e} {rate('l2_uL')} {r['l2_force']:10.3e} "
                     f"{rate('l2_force')} {r['penetration']:9.2e} "
                     f"{loss if loss is None else format(loss, '9.2e')} "
                     f"{r['wall_time_s']:7.3f}")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = Parser(prog="skfem_beam.bench.bar_convergence",
                                description=__doc__.splitlines()[0])
    p.add_argument("--N", type=counts, default="25,50,100,200,400",
                   help="meshes, comma separated")
    p.add_argument("--courant", type=float, default=0.1, help="c·Δt/h")
    p.add_argument("--T", type=float, default=3.0)
    p.add_argument("--beta", type=float, default=0.25)
    p.add_argument("--mass", default="average")
    p.add_argument("--obstacle", default="rigid,elastic")
    p.add_argument("--k", type=float, default=100.0)
    a = p.parse_args(argv)
    Ns = a.N
    for obstacle in a.obstacle.split(","):
        rows = study(obstacle, Ns, a.courant, a.T, a.beta, mass=a.mass, k=a.k)
        extra = f", k={a.k:g}" if obstacle == "elastic" else ""
        print(table(rows, f"\n{obstacle} obstacle{extra}: mass={a.mass}, β={a.beta:g}, "
                          f"c·Δt/h={a.courant:g}, T={a.T:g}"))
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
