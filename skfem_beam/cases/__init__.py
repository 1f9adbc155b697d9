"""One module per scene; each is a thin command line mapping its flags onto
:mod:`skfem_beam.scenes`."""
from __future__ import annotations

from .. import cli, scenes


def pipe_parser(prog: str, doc: str, *, J: int, dt: float, T: float, L: float) -> cli.Parser:
    """The flags every beam case takes, plus the pipe's length --L and stiffness --k2."""
    p = cli.parser(prog, doc.strip().splitlines()[0], J=J, dt=dt, T=T)
    p.add_argument("--L", type=float, default=L, help="beam length (m)")
    p.add_argument("--k2", type=float, default=scenes.PIPE_K2, help="k² = EI/(ρS) (m⁴/s²)")
    return p
