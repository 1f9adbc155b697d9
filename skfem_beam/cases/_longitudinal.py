"""Flags and problem shared by the second paper's scenes (L = 10 m pipe, f = sin 10t)."""
from __future__ import annotations

import numpy as np

from .. import cli
from ..problem import Beam, BeamProblem, InitialState, Load, Obstacles


def parser(prog: str, doc: str, T: float = 1.0):
    p = cli.parser(prog, doc.strip().splitlines()[0], J=40, dt=1e-3, T=T)
    p.add_argument("--L", type=float, default=10.0, help="beam length (m)")
    p.add_argument("--k2", type=float, default=282.84, help="k² = EI/(ρS) (m⁴/s²)")
    return p


def problem(args, obstacles: Obstacles, load=None, initial=None) -> BeamProblem:
    from .point_stops import PIPE_RHO_S
    return BeamProblem(Beam(args.L, args.k2, PIPE_RHO_S), obstacles,
                       load=load if load is not None else Load.uniform(lambda t: np.sin(10 * t)),
                       initial=initial or InitialState(), J=args.J, element=args.element,
                       nodes=cli.mesh_nodes(args))
