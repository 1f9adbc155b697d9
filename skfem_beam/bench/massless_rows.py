"""The modified mass's massless rows on the periodic rod: β-weighted against quasi-static.

    python -m skfem_beam.bench.massless_rows [--N 80] [--T 12]

For Δt/h = 0.04 and 0.4: the L²(0, T) error of u(0, ·), the largest nodal penetration,
the energy drift against the exact 1/8, the largest second difference of u(0, tₙ) (the
massless node's step-to-step oscillation) and the time loop, beside the position scheme's
default (average mass, β = 1/4).  The table is in docs/design.md §7.
"""
from __future__ import annotations

import argparse

import numpy as np

from .. import scenes
from ..bar import l2_time, run_bar
from ..reference import exact_of

SETTINGS = (("position, average, β=1/4", "average", 0.25, "beta"),
            ("modified mass, β=1/2", "redistributed", 0.5, "beta"),
            ("modified mass, β=1/4", "redistributed", 0.25, "beta"),
            ("modified mass, β=1/4, quasi-static", "redistributed", 0.25, "quasi-static"),
            ("modified mass, β=1/2, quasi-static", "redistributed", 0.5, "quasi-static"))


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, default=80)
    p.add_argument("--T", type=float, default=12.0)
    a = p.parse_args(argv)
    print("Δt/h  setting                               u(0) L²   penetration  drift     "
          "max|Δ²u(0)|  loop (s)")
    for courant in (0.04, 0.4):
        for name, mass, beta, massless in SETTINGS:
            bar = scenes.periodic_rod(a.N, mass=mass)
            dt = courant * bar.h / bar.c
            r = run_bar(bar, dt, a.T, beta=beta, all_states_limit=10**8, massless=massless)
            err = l2_time(r.u0 - exact_of(bar, a.T).u(0.0, r.t), dt)
            print(f"{courant:<5g} {name:<37s} {err:.3e}  {r.penetration:.1e}      "
                  f"{(r.energy[-1] - 0.125) / 0.125:+.3%}  {np.abs(np.diff(r.u0, 2)).max():.2e}"
                  f"     {r.result.wall_time_s:.3f}")


if __name__ == "__main__":
    main()
