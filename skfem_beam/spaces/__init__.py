"""Finite element spaces V_h ⊂ V = {w ∈ H²(0,L): w(0) = w'(0) = 0} (and P1 for the bar).

Every space offers the same small interface, used by :mod:`skfem_beam.semidiscrete`:

- ``nodes`` (J+1,), ``n`` (number of free dofs), ``mesh`` (the real ``skfem.MeshLine``);
- ``M`` mass (u, v) and ``S`` bending (u'', v'') as CSR matrices on the free dofs;
- ``C`` (J × n): the nodal values u(x_1..x_J) = C·coefficients (constraint (8));
- ``sampler(xi)``: values and second derivatives at local abscissae ξ ∈ [0, 1] of
  every element, as sparse matrices (penetration between nodes, output sub-points);
- ``load_vector(b)``: (b, φ_i) for a profile b(x);
- ``interpolate(u, du)``: coefficients of a function given by u(x) (and u'(x));
- ``project(v)``: the L² projection (used for the initial velocity, see DESIGN).
"""
from __future__ import annotations

from .hermite import HermiteSpace


def make_space(element: str, nodes):
    if element == "hermite":
        return HermiteSpace(nodes)
    if element == "bspline":
        from .bspline import BSplineSpace
        return BSplineSpace(nodes)
    if element == "p1":
        from .lagrange import LagrangeSpace
        return LagrangeSpace(nodes)
    raise ValueError(f"unknown element {element!r}")
