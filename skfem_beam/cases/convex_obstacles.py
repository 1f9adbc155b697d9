"""Convex obstacles g = ±(0.005 + 0.03 (x − L/2)²) along a 10 m pipe, forced by f = sin 10t.

    python -m skfem_beam.cases.convex_obstacles [--J 40] [--element hermite|bspline] ...

The second paper's Table 2 scene.
"""
from __future__ import annotations

from .. import cli
from ..problem import Obstacles, check_positive
from . import _longitudinal
from ._beam import run_beam_case


def obstacles(L: float, g0: float = 0.005, curvature: float = 0.03) -> Obstacles:
    g = lambda x: g0 + curvature * (x - L / 2) ** 2  # noqa: E731
    return Obstacles(g1=lambda x: -g(x), g2=g)


def main(argv=None) -> int:
    args = cli.parse(_longitudinal.parser("skfem_beam.cases.convex_obstacles", __doc__), argv)
    check_positive("L", args.L)
    pb = _longitudinal.problem(args, obstacles(args.L))
    gL = 0.005 + 0.03 * (args.L / 2) ** 2
    config = {"f": "sin(10 t)", "u0": "0", "v0": "0", "g": "±(0.005 + 0.03 (x − L/2)²)"}
    return run_beam_case("convex_obstacles", pb, args, config, stops=(-gL, gL))


if __name__ == "__main__":
    cli.main_guard(main)
