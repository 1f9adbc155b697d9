"""The first paper's scene: a steel pipe clamped to a vibrating support, stops at the tip.

    python -m skfem_beam.cases.point_stops [--J 19] [--dt 5e-5] [--T 2] [--beta 0.5] ...
"""
from __future__ import annotations

from .. import cli, scenes
from . import pipe_parser
from ._beam import run_beam_case


def main(argv=None) -> int:
    p = pipe_parser("skfem_beam.cases.point_stops", __doc__, J=19, dt=5e-5, T=2.0, L=1.501)
    p.add_argument("--gap", type=float, default=0.1, help="stops at ±gap (m)")
    p.add_argument("--amplitude", type=float, default=0.2, help="support φ = A sin(ωt): A (m)")
    p.add_argument("--omega", type=float, default=10.0, help="support φ = A sin(ωt): ω (rad/s)")
    args = cli.parse(p, argv)
    pb = scenes.point_stops(J=args.J, element=args.element, L=args.L, k2=args.k2, gap=args.gap,
                            amplitude=args.amplitude, omega=args.omega,
                            nodes=cli.mesh_nodes(args))
    config = {"u0": "0", "v0": "-amplitude*omega*h(x) (L2 projection)"}
    return run_beam_case("point_stops", pb, cli.spec(args, config), stops=(-args.gap, args.gap))


if __name__ == "__main__":
    cli.main_guard(main)
