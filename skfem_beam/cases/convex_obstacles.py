"""Convex obstacles g = ±(0.005 + 0.03 (x − L/2)²) along a 10 m pipe, forced by f = sin 10t.

    python -m skfem_beam.cases.convex_obstacles [--J 40] [--element hermite|bspline] ...

The second paper's Table 2 scene.
"""
from __future__ import annotations

from .. import cli, scenes
from . import pipe_parser
from ._beam import run_beam_case


def main(argv=None) -> int:
    args = cli.parse(pipe_parser("skfem_beam.cases.convex_obstacles", __doc__, J=40, dt=1e-3,
                                 T=1.0, L=scenes.PIPE10_L), argv)
    pb = scenes.convex_obstacles(J=args.J, element=args.element, L=args.L, k2=args.k2,
                                 nodes=cli.mesh_nodes(args))
    lo, hi = pb.obstacles.bounds([pb.beam.L])      # the gap at the tip, for the chart
    config = {"f": "sin(10 t)", "u0": "0", "v0": "0", "g": "±(0.005 + 0.03 (x − L/2)²)"}
    return run_beam_case("convex_obstacles", pb, cli.spec(args, config), stops=(lo[0], hi[0]))


if __name__ == "__main__":
    cli.main_guard(main)
