"""The papers' scenes as plain functions returning problem objects.

    scenes.point_stops()        first paper: pipe on a vibrating support, stops at the tip
    scenes.flat_obstacles()     second paper, Table 3: flat obstacles ±0.01 m on [L/2, L]
    scenes.convex_obstacles()   second paper, Table 2: g = ±(0.005 + 0.03 (x − L/2)²)
    scenes.energy_decay()       second paper, Figs 4–7: f = 0, energy drops only at impacts
    scenes.impacting_bar()      third paper, Example 1 (and 2 with f=−1)
    scenes.periodic_rod()       clamped rod released onto a rigid obstacle: 3-periodic, exact

The case modules, the benchmarks, the notebooks and the tests all build their scenes
here; the command line only maps its flags onto these keyword arguments.
"""
from __future__ import annotations

import math

import numpy as np

from .bar import Bar
from .problem import (Beam, BeamProblem, Damping, InitialState, Load, Obstacles, Support,
                      check_positive, lifting)

# the first paper's pipe: E = 2e11 Pa, ρ = 8000 kg/m³, outer diameter 1 cm, wall 0.5 mm
PIPE_K2 = 282.84                                          # EI/(ρS), m⁴/s²
PIPE_RHO_S = 8000.0 * math.pi / 4 * (0.01**2 - 0.009**2)  # ≈ 0.1194 kg/m
PIPE10_L = 10.0                                           # the second paper's length (m)


# the mesh keywords point_stops forwards to BeamProblem, and their defaults
POINT_STOPS_MESH = {"J": 19, "element": "hermite", "nodes": None}


def point_stops(*, L=1.501, k2=PIPE_K2, gap=0.1, amplitude=0.2, omega=10.0,
                rho_S=PIPE_RHO_S, damping=None, **mesh) -> BeamProblem:
    """Clamped to a support moving as A sin ωt, stops ±gap at the tip.  u0 = 0,
    v0 = −Aω h(x): the beam is at rest in the fixed frame (ũ = ũ_t = 0) at t = 0.
    ``damping``: a :class:`~skfem_beam.problem.Damping` (the papers' pipe has none).
    ``mesh``: J, element, nodes as :class:`~skfem_beam.problem.BeamProblem` takes them
    (defaults :data:`POINT_STOPS_MESH`)."""
    unknown = sorted(set(mesh) - set(POINT_STOPS_MESH))
    if unknown:
        raise TypeError(f"point_stops() got an unexpected keyword argument {unknown[0]!r} "
                        f"(its mesh keywords: {', '.join(POINT_STOPS_MESH)})")
    gap = check_positive("gap", gap)
    beam = Beam(L, k2, rho_S)
    return BeamProblem(
        beam=beam, obstacles=Obstacles.point_stops(beam.L, -gap, gap),
        support=Support(amplitude, omega),
        initial=InitialState(v0=lambda x: -amplitude * omega * lifting(x, beam.L)),
        **{**POINT_STOPS_MESH, **mesh},
        damping=Damping() if damping is None else damping)


def flat_profile(L: float, gap: float = 0.01) -> Obstacles:
    """g1 = −gap, g2 = gap on [L/2, L], no obstacle on (0, L/2)."""
    gap = check_positive("gap", gap)
    return Obstacles(g1=lambda x: np.where(x >= L / 2, -gap, -np.inf),
                     g2=lambda x: np.where(x >= L / 2, gap, np.inf), breakpoints=(L / 2,))


def convex_profile(L: float, g0: float = 0.005, curvature: float = 0.03) -> Obstacles:
    """g = ±(g0 + curvature (x − L/2)²)."""
    g = lambda x: g0 + curvature * (x - L / 2) ** 2  # noqa: E731
    return Obstacles(g1=lambda x: -g(x), g2=g)


def _pipe10(obstacles_of, *, J, element, L, k2, nodes, load=None, initial=None):
    """The second paper's 10 m pipe forced by f = sin 10t (or ``load``)."""
    beam = Beam(L, k2, PIPE_RHO_S)
    return BeamProblem(beam, obstacles_of(beam.L),
                       load=load if load is not None else Load.uniform(lambda t: np.sin(10 * t)),
                       initial=initial or InitialState(), J=J, element=element, nodes=nodes)


def flat_obstacles(*, J=40, element="hermite", L=PIPE10_L, k2=PIPE_K2, gap=0.01,
                   nodes=None) -> BeamProblem:
    """Needs a node at L/2 (even J on a uniform mesh)."""
    return _pipe10(lambda L: flat_profile(L, gap), J=J, element=element, L=L, k2=k2,
                   nodes=nodes)


def convex_obstacles(*, J=40, element="hermite", L=PIPE10_L, k2=PIPE_K2, g0=0.005,
                     curvature=0.03, nodes=None) -> BeamProblem:
    return _pipe10(lambda L: convex_profile(L, g0, curvature), J=J, element=element, L=L,
                   k2=k2, nodes=nodes)


def energy_decay(*, J=40, element="hermite", L=PIPE10_L, k2=PIPE_K2, nodes=None) -> BeamProblem:
    """f = 0, u0 = 0.005 x², v0 = −x, g = ±(0.2 + 0.3 (x − L/2)²)."""
    return _pipe10(lambda L: convex_profile(L, 0.2, 0.3), J=J, element=element, L=L, k2=k2,
                   nodes=nodes, load=Load(),
                   initial=InitialState(u0=lambda x: 0.005 * x**2, du0=lambda x: 0.01 * x,
                                        v0=lambda x: -x))


def impacting_bar(**kw) -> Bar:
    """Example 1 of Do, Raupp & Feijoo (rigid obstacle; ``obstacle="elastic"`` for the
    spring k = 100; ``f=-1`` for Example 2); keywords as :class:`~skfem_beam.bar.Bar`."""
    return Bar(**kw)


def periodic_rod(N=80, *, gap=0.5, L=1.0, a=1.0, rho=1.0, mass="average", obstacle_at="left",
                 A=None) -> Bar:
    """Clamped at the far end, rigid obstacle at the other, released at rest from the line
    u0 = gap·(1 − distance to the obstacle/L) (½ − x/2 by default).  Its exact solution
    (:class:`~skfem_beam.reference.RodExact`) has period 3L/c and energy ½·a·gap²/L·A
    (1/8 for the defaults, A = 1)."""
    u0 = [(0.0, gap), (L, 0.0)] if obstacle_at in ("left", 0) else [(0.0, 0.0), (L, -gap)]
    return Bar(a=a, rho=rho, L=L, v0=0.0, u0=u0, obstacle="rigid", N=N, mass=mass,
               far_end="clamped", obstacle_at=obstacle_at, A=A)
