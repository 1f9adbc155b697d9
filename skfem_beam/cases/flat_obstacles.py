"""Flat obstacles ±0.01 m along the second half of a 10 m pipe, forced by f = sin 10t.

    python -m skfem_beam.cases.flat_obstacles [--J 40] [--element hermite|bspline] ...

The second paper's Table 3 scene: g1 = −0.01, g2 = 0.01 on [L/2, L], no obstacle on
(0, L/2); the mesh must have a node at L/2 (even J on a uniform mesh).
"""
from __future__ import annotations

from .. import cli, scenes
from . import pipe_parser
from ._beam import run_beam_case


def main(argv=None) -> int:
    p = pipe_parser("skfem_beam.cases.flat_obstacles", __doc__, J=40, dt=1e-3, T=1.0,
                    L=scenes.PIPE10_L)
    p.add_argument("--gap", type=float, default=0.01, help="obstacles at ±gap on [L/2, L] (m)")
    args = cli.parse(p, argv)
    pb = scenes.flat_obstacles(J=args.J, element=args.element, L=args.L, k2=args.k2,
                               gap=args.gap, nodes=cli.mesh_nodes(args))
    config = {"f": "sin(10 t)", "u0": "0", "v0": "0", "g": "±gap on [L/2, L]"}
    return run_beam_case("flat_obstacles", pb, cli.spec(args, config), stops=(-args.gap, args.gap))


if __name__ == "__main__":
    cli.main_guard(main)
