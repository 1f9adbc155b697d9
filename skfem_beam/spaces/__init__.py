"""Finite element spaces V_h ⊂ V = {w ∈ H²(0,L): the end conditions and supports} (and P1, P2
for the bar).  The beam spaces take ``ends`` (default clamped at 0, free at L: the papers'
V = {w(0) = w'(0) = 0}) and ``supports`` (abscissae of rigid supports), see :mod:`.ends`.

Every space offers the same small interface, used by :mod:`skfem_beam.semidiscrete`:

- ``nodes`` (J+1,), ``n`` (number of free dofs), ``mesh`` (the real ``skfem.MeshLine``);
- ``M`` mass (u, v) and ``S`` bending (u'', v'') as CSR matrices on the free dofs;
- ``nodal`` ((J+1) × n): the nodal values u(x_0..x_J) = nodal·coefficients (zero rows
  where u is fixed), ``value_nodes``: the nodes where u is free;
- ``C`` (J × n): the rows x_1..x_J of ``nodal`` (constraint (8));
- ``sampler(xi)``: values and second derivatives at local abscissae ξ ∈ [0, 1] of
  every element, as sparse matrices (penetration between nodes, output sub-points);
- ``load_vector(b)``: (b, φ_i) for a profile b(x);
- ``interpolate(u, du)``: coefficients of a function given by u(x) (and u'(x));
- ``project(v)``: the L² projection (used for the initial velocity, see docs/design.md §2);
- ``point_rows(x, derivative, full)``: rows evaluating u, u' or u'' at any abscissae;
- ``T`` (n_full × n): the free coefficients in the full space (fixed dofs included),
  ``full_matrices()``: M, S there (the lifting of a moving support lives in it).

``weights`` = (ρA_e/ρA_ref, EI_e/EI_ref) per element make M and S those of a stepped
beam (variable coefficients, constant on each element).
"""
from __future__ import annotations

import numpy as np

from .ends import DEFAULT_ENDS, END_CONDITIONS, fixed_dofs  # noqa: F401
from .hermite import HermiteSpace


def has_rigid_motion(space) -> bool:
    """Whether some w = a + b·x ≠ 0 meets the fixed conditions (then S is singular)."""
    value, slope = fixed_dofs(space.J, space.ends, space.support_nodes)
    rows = [[1.0, x] for x in space.nodes[value]] + [[0.0, 1.0]] * int(slope.sum())
    return not rows or np.linalg.matrix_rank(np.array(rows)) < 2


def make_space(element: str, nodes, ends=DEFAULT_ENDS, supports=(), weights=None):
    """The space of ``element`` on ``nodes``; ``ends``/``supports`` for the beam spaces;
    ``weights`` = (mass, bending) factors per element (a stepped beam), None: uniform."""
    if element == "hermite":
        return HermiteSpace(nodes, ends, supports, weights)
    if element == "bspline":
        from .bspline import BSplineSpace
        return BSplineSpace(nodes, ends, supports, weights)
    if element == "p1":
        from .lagrange import LagrangeSpace
        return LagrangeSpace(nodes)
    raise ValueError(f"unknown element {element!r}")
