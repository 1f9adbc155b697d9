"""Flat obstacles ±0.01 m along the second half of a 10 m pipe, forced by f = sin 10t.

    python -m skfem_beam.cases.flat_obstacles [--J 40] [--element hermite|bspline] ...

The second paper's Table 3 scene: g1 = −0.01, g2 = 0.01 on [L/2, L], no obstacle on
(0, L/2); the mesh must have a node at L/2 (even J on a uniform mesh).
"""
from __future__ import annotations

import numpy as np

from .. import cli
from ..problem import Obstacles, check_positive
from . import _longitudinal
from ._beam import run_beam_case


def obstacles(L: float, gap: float = 0.01) -> Obstacles:
    gap = check_positive("gap", gap)
    return Obstacles(g1=lambda x: np.where(x >= L / 2, -gap, -np.inf),
                     g2=lambda x: np.where(x >= L / 2, gap, np.inf), breakpoints=(L / 2,))


def main(argv=None) -> int:
    p = _longitudinal.parser("skfem_beam.cases.flat_obstacles", __doc__)
    p.add_argument("--gap", type=float, default=0.01, help="obstacles at ±gap on [L/2, L] (m)")
    args = cli.parse(p, argv)
    check_positive("L", args.L)
    pb = _longitudinal.problem(args, obstacles(args.L, args.gap))
    config = {"f": "sin(10 t)", "u0": "0", "v0": "0", "g": "±gap on [L/2, L]"}
    return run_beam_case("flat_obstacles", pb, args, config, stops=(-args.gap, args.gap))


if __name__ == "__main__":
    cli.main_guard(main)
