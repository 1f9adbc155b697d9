"""Continuous P1 or P2 elements on a ``skfem.MeshLine`` (the bar of Do, Raupp & Feijoo).

The unknowns are the nodal values of the nodes that are not ``fixed`` (P2: and the
values at the element midpoints), numbered along x, so that M and S are banded with
half band ``kd`` = the degree.  A clamped end (u = 0) drops its node; a free end and the
end at an obstacle keep theirs (the obstacle is a constraint, not a boundary condition).
``C`` maps the unknowns to the values at every node (the identity for P1 when nothing is
fixed); ``sampler``, ``load_vector``,
``interpolate`` and ``project`` work on the unknowns.  The interface follows
:class:`~skfem_beam.spaces.hermite.HermiteSpace` where it applies; ``S`` here is the
stiffness (u', v') instead of the bending form.

Mass matrices (the choice sets the dispersion error of a wave, docs/design.md §6, "Bar accuracy"):

- ``consistent``: (u, v) exactly; waves travel too slowly on the mesh;
- ``lumped``: row sums on the diagonal (P2: h/6, 2h/3, h/6); waves travel too fast;
- ``average``: ½(consistent + lumped); the two leading phase errors cancel, so the
  dispersion error drops from O((ωh)²) to O((ωh)⁴);
- ``redistributed``: the average mass here; the system built on the space empties the
  contact node's mass row and moves its mass to the neighbours, keeping the total mass
  and the centre of mass (:mod:`.redistribution`: only the system knows its constraints).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementLineP1, ElementLineP2, LinearForm, MeshLine
from skfem.helpers import dot, grad

from .hermite import Sampler

MASSES = ("consistent", "lumped", "average", "redistributed")
ELEMENTS = {"p1": ElementLineP1, "p2": ElementLineP2}


@BilinearForm
def mass_form(u, v, w):
    return u * v


@BilinearForm
def stiffness(u, v, w):
    return dot(grad(u), grad(v))


@LinearForm
def load(v, w):
    return w["b"] * v


def lump(M: sp.spmatrix) -> sp.csr_matrix:
    """Row-sum lumping: the diagonal matrix with the same total mass."""
    return sp.diags(np.asarray(M.sum(axis=1)).ravel()).tocsr()


class LagrangeSpace:

    def __init__(self, nodes, mass: str = "consistent", fixed=(), element: str = "p1"):
        if mass not in MASSES:
            raise ValueError(f"mass={mass!r} is not one of: {', '.join(MASSES)}")
        if element not in ELEMENTS:
            raise ValueError(f"element={element!r} is not one of: {', '.join(ELEMENTS)}")
        x = np.asarray(nodes, dtype=float)
        self.name, self.kd = element, int(element[1])   # kd: half band of M and S
        self.nodes = x
        self.J = x.size - 1
        self.h = np.diff(x)
        self.mesh = MeshLine(x)
        self._basis = Basis(self.mesh, ELEMENTS[element]())
        # every dof (vertices, P2's midpoints) by increasing x: element e holds kd·e … kd·e + kd
        order = np.argsort(self._basis.doflocs[0], kind="stable")
        self.dof_x = self._basis.doflocs[0][order]
        at = np.empty_like(order)
        at[order] = np.arange(order.size)
        vertex = at[self._basis.nodal_dofs[0]]      # the position of each vertex's dof
        assert np.allclose(self.dof_x[vertex], x)
        free = np.setdiff1d(np.arange(order.size), vertex[np.asarray(fixed, dtype=int)])
        self.free = free
        self.n = free.size
        # R: unknowns -> every dof in skfem's numbering (a fixed dof reads 0); matrices are
        # Rᵀ(·)R; C: unknowns -> the values at the vertices
        R = sp.csr_matrix((np.ones(free.size), (order[free], np.arange(free.size))),
                          shape=(order.size, free.size))
        self._R = R
        self._to_x = sp.csr_matrix((np.ones(order.size), (np.arange(order.size), order)),
                                   shape=(order.size, order.size)) @ R
        self.C = self._to_x[vertex].tocsr()
        Mc = mass_form.assemble(self._basis).tocsr()
        Ml = lump(Mc)      # lumped on the whole mesh, then restricted (row sums kept)
        self.M_consistent = (R.T @ Mc @ R).tocsr()
        self.M_lumped = (R.T @ Ml @ R).tocsr()
        self.mass_kind = mass
        self.M = {"consistent": self.M_consistent, "lumped": self.M_lumped,
                  "average": (0.5 * (self.M_consistent + self.M_lumped)).tocsr()}[
            "average" if mass == "redistributed" else mass]
        self.S = (R.T @ stiffness.assemble(self._basis) @ R).tocsr()

    def sampler(self, xi) -> Sampler:
        """Values (and, for P2, the constant second derivatives) at local abscissae ξ of
        every element; P1 has no second derivative inside an element, so ``E2`` is zero."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        ne, nq, kd = self.J, xi.size, self.kd
        if kd == 1:
            shapes, curvatures = [1 - xi, xi], [0 * xi, 0 * xi]
        else:
            shapes = [(1 - xi) * (1 - 2 * xi), 4 * xi * (1 - xi), xi * (2 * xi - 1)]
            curvatures = [4 + 0 * xi, -8 + 0 * xi, 4 + 0 * xi]
        rows = np.tile(np.arange(ne * nq), kd + 1)
        cols = np.concatenate([np.repeat(kd * np.arange(ne) + k, nq) for k in range(kd + 1)])
        h2 = np.repeat(self.h ** 2, nq)
        E0, E2 = (sp.csr_matrix((np.concatenate([np.tile(f, ne) / scale for f in funcs]),
                                 (rows, cols)), shape=(ne * nq, self.dof_x.size)) @ self._to_x
                  for funcs, scale in ((shapes, 1.0), (curvatures, h2)))
        x = (self.nodes[:-1, None] + self.h[:, None] * xi[None, :]).ravel()
        return Sampler(x, E0.tocsr(), E2.tocsr())

    def load_vector(self, b) -> np.ndarray:
        """(b, φ_i) for a profile b(x), by scikit-fem's quadrature."""
        xq = self._basis.mapping.F(self._basis.X)[0]
        bq = np.broadcast_to(np.asarray(b(xq), dtype=float), xq.shape)
        return self._R.T @ load.assemble(self._basis, b=bq)

    def interpolate(self, u, du=None) -> np.ndarray:
        """Nodal interpolation (the paper's (7.3)(ii): ζ⁰(x_j) = u₀(x_j)) at the free dofs."""
        values = np.broadcast_to(np.asarray(u(self.dof_x), dtype=float), self.dof_x.shape)
        return values[self.free].copy()

    def project(self, v) -> np.ndarray:
        """L² projection with the consistent mass (onto the space with its fixed nodes)."""
        import scipy.sparse.linalg as spla
        return spla.spsolve(self.M_consistent.tocsc(), self.load_vector(v))
