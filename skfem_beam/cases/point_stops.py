"""The first paper's scene: a steel pipe clamped to a vibrating support, stops at the tip.

    python -m skfem_beam.cases.point_stops [--J 19] [--dt 5e-5] [--T 2] [--beta 0.5] ...
"""
from __future__ import annotations

from .. import cli
from ..problem import Beam, BeamProblem, InitialState, Obstacles, Support, lifting
from ._beam import run_beam_case

# E = 2e11 Pa, ρ = 8000 kg/m³, outer diameter 1 cm, wall 0.5 mm (the paper's pipe)
PIPE_RHO_S = 8000.0 * 3.141592653589793 / 4 * (0.01**2 - 0.009**2)   # ≈ 0.1194 kg/m


def problem(L=1.501, k2=282.84, gap=0.1, amplitude=0.2, omega=10.0, J=19,
            element="hermite", rho_S=PIPE_RHO_S, nodes=None) -> BeamProblem:
    """u0 = 0, v0 = −2h(x): the beam is at rest in the fixed frame (ũ = ũ_t = 0) at t = 0."""
    from ..problem import check_positive
    gap = check_positive("gap", gap)
    beam = Beam(L, k2, rho_S)
    return BeamProblem(
        beam=beam, obstacles=Obstacles.point_stops(beam.L, -gap, gap),
        support=Support(amplitude, omega),
        initial=InitialState(v0=lambda x: -amplitude * omega * lifting(x, beam.L)),
        J=J, element=element, nodes=nodes)


def main(argv=None) -> int:
    p = cli.parser("skfem_beam.cases.point_stops", __doc__.splitlines()[0],
                   J=19, dt=5e-5, T=2.0)
    p.add_argument("--L", type=float, default=1.501, help="beam length (m)")
    p.add_argument("--k2", type=float, default=282.84, help="k² = EI/(ρS) (m⁴/s²)")
    p.add_argument("--gap", type=float, default=0.1, help="stops at ±gap (m)")
    p.add_argument("--amplitude", type=float, default=0.2, help="support φ = A sin(ωt): A (m)")
    p.add_argument("--omega", type=float, default=10.0, help="support φ = A sin(ωt): ω (rad/s)")
    args = cli.parse(p, argv)
    pb = problem(args.L, args.k2, args.gap, args.amplitude, args.omega, args.J, args.element,
                 nodes=cli.mesh_nodes(args))
    config = {"u0": "0", "v0": "-amplitude*omega*h(x) (L2 projection)"}
    return run_beam_case("point_stops", pb, args, config, stops=(-args.gap, args.gap))


if __name__ == "__main__":
    cli.main_guard(main)
