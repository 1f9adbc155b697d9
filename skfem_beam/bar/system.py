"""The bar's semi-discretisation (P1 or P2).  Units: everything is per unit cross-section
area (times A when the bar has one).  The semi-discrete equation is the paper's (2.9)
with the density kept:

    ρ M₁ ü + b S u̇ + a S u = f·(1, φ_i) + e₀ R,     (M₁ = (φ_i, φ_j), S = (φ_i', φ_j'))

so M carries ρ, every term is a force, f is a body force per unit volume (N/m³ for a
bar of unit cross-section; with ρ = 1 it equals the paper's f) and the spring
stiffness enters the shared scheme as κ = k itself, with no division by ρ.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..semidiscrete import SceneView, SemiDiscrete
from ..spaces.lagrange import LagrangeSpace
from .problem import Bar


def bar_system(bar: Bar) -> SemiDiscrete:
    """P1 or P2 semi-discretisation of the bar: M = ρA·M_mass, K = aA·S, B = bA·S (A = 1 per
    unit cross-section), a clamped far end's node dropped, one constrained value at
    the obstacle: u(0) ≥ 0 or u(L) ≤ 0.

    The constraint row is there for both obstacles: the rigid one enforces it, the
    elastic one is a spring on the same value (``Penalty(bar.k)``).
    """
    left = bar.obstacle_at == "left"
    fixed = () if bar.far_end == "free" else ((bar.N,) if left else (0,))
    space = LagrangeSpace(np.linspace(0.0, bar.L, bar.N + 1), bar.mass, fixed, bar.element)
    n, A = space.n, bar.section
    nodal = space.C.toarray()
    e0, eL = nodal[0], nodal[-1]
    loads = A * space.load_vector(lambda x: np.ones_like(x))[:, None] if bar.f != 0 \
        else np.zeros((n, 0))
    load_time = [lambda t, f=bar.f: np.full(np.shape(t), f)] if bar.f != 0 else []
    u0, v0 = (np.full(n, p) if isinstance(p, float) else space.interpolate(p)
              for p in (bar.u0, bar.v0))
    system = SemiDiscrete(
        M=(bar.rho * A * space.M).tocsr(), K=(bar.a * A * space.S).tocsr(),
        B=(bar.b * A * space.S).tocsr() if bar.b > 0 else None,
        C=sp.csr_matrix((e0 if left else eL)[None, :]),
        lo=np.array([0.0 if left else -np.inf]), hi=np.array([np.inf if left else 0.0]),
        x_contact=np.array([0.0 if left else bar.L]),
        loads=loads, load_time=load_time, u0=u0, v0=v0,
        # mean_u = (1/L)∫u dx: the centre of mass, and the load's potential −fAL·mean_u
        observe={"u0": e0, "uL": eL, "mean_u": space.load_vector(np.ones_like) / bar.L},
        space=space,
        meta={"kind": "bar", "L": bar.L, "a": bar.a, "b": bar.b, "rho": bar.rho,
              "obstacle": bar.obstacle, "k": bar.k, "N": bar.N, "mass": bar.mass,
              "far_end": bar.far_end, "obstacle_at": bar.obstacle_at, "A": bar.A,
              "element": bar.element},
        view=SceneView("bar", bar.L))
    if bar.mass == "redistributed":      # no inertia at the contact node (modified mass)
        from ..spaces.redistribution import redistributed
        system = redistributed(system)
    return system


def spring_step_ratio(bar: Bar, dt: float) -> float:
    """ω₀Δt, ω₀ = √(k/m₀): the contact node (mass m₀ = M₀₀) on the spring.  Well above 1
    the β-weighted one-sided spring mis-times each impact on the node and can gain
    energy there (measured: ×36 over Example 2 with k = 1e8, Δt = 1e-3)."""
    share = {"consistent": 1 / 3, "lumped": 1 / 2, "average": 5 / 12} if bar.element == "p1" \
        else {"consistent": 2 / 15, "lumped": 1 / 6, "average": 3 / 20}
    share = share.get(bar.mass, 0.0)
    if share == 0.0:      # a massless contact node has no impact to mis-time
        return 0.0
    m0 = bar.rho * bar.section * bar.h * share
    return math.sqrt(bar.k / m0) * dt
