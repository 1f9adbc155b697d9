"""Continuous P1 elements on a ``skfem.MeshLine`` (the bar of Do, Raupp & Feijoo).

The unknowns are the nodal values of the nodes that are not ``fixed``: a clamped end
(u = 0) drops its node; a free end and the end at an obstacle keep theirs (the obstacle
is a constraint, not a boundary condition).  ``C`` maps the unknowns to the values at
every node (the identity when nothing is fixed); ``sampler``, ``load_vector``,
``interpolate`` and ``project`` work on the unknowns.  The interface follows
:class:`~skfem_beam.spaces.hermite.HermiteSpace` where it applies; ``S`` here is the
stiffness (u', v') instead of the bending form.

Mass matrices (the choice sets the dispersion error of a wave, docs/design.md §6, "Bar accuracy"):

- ``consistent``: (u, v) exactly; waves travel too slowly on the mesh;
- ``lumped``: row sums on the diagonal; waves travel too fast;
- ``average``: ½(consistent + lumped); the two leading phase errors cancel, so the
  dispersion error drops from O((ωh)²) to O((ωh)⁴);
- ``redistributed``: the average mass here; the system built on the space empties the
  contact node's mass row and moves its mass to the neighbours, keeping the total mass
  and the centre of mass (:mod:`.redistribution`: only the system knows its constraints).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementLineP1, LinearForm, MeshLine
from skfem.helpers import dot, grad

from .hermite import Sampler

MASSES = ("consistent", "lumped", "average", "redistributed")


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
    name = "p1"
    kd = 1  # half bandwidth of the consistent M and of S

    def __init__(self, nodes, mass: str = "consistent", fixed=()):
        if mass not in MASSES:
            raise ValueError(f"mass={mass!r} is not one of: {', '.join(MASSES)}")
        x = np.asarray(nodes, dtype=float)
        self.nodes = x
        self.J = x.size - 1
        self.h = np.diff(x)
        self.mesh = MeshLine(x)
        self._basis = Basis(self.mesh, ElementLineP1())
        # the basis numbers dofs by mesh vertex; MeshLine keeps the given order
        assert np.allclose(self._basis.doflocs[0], x)
        free = np.setdiff1d(np.arange(x.size), np.asarray(fixed, dtype=int))
        self.free = free
        self.n = free.size
        # C: unknowns -> values at every node (a fixed node reads 0); matrices are Cᵀ(·)C
        self.C = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))),
                               shape=(x.size, free.size))
        P = self.C
        Mc = mass_form.assemble(self._basis).tocsr()
        Ml = lump(Mc)      # lumped on the whole mesh, then restricted (row sums kept)
        self.M_consistent = (P.T @ Mc @ P).tocsr()
        self.M_lumped = (P.T @ Ml @ P).tocsr()
        self.mass_kind = mass
        self.M = {"consistent": self.M_consistent, "lumped": self.M_lumped,
                  "average": (0.5 * (self.M_consistent + self.M_lumped)).tocsr()}[
            "average" if mass == "redistributed" else mass]
        self.S = (P.T @ stiffness.assemble(self._basis) @ P).tocsr()

    def sampler(self, xi) -> Sampler:
        """Values at local abscissae ξ of every element; P1 has no second derivative
        inside an element, so ``E2`` is zero."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        ne, nq = self.J, xi.size
        rows = np.arange(ne * nq).reshape(ne, nq)
        left = np.broadcast_to(np.arange(ne)[:, None], (ne, nq))
        r = np.concatenate([rows.ravel(), rows.ravel()])
        c = np.concatenate([left.ravel(), left.ravel() + 1])
        v = np.concatenate([np.broadcast_to(1 - xi, (ne, nq)).ravel(),
                            np.broadcast_to(xi, (ne, nq)).ravel()])
        E0 = sp.csr_matrix((v, (r, c)), shape=(ne * nq, self.nodes.size)) @ self.C
        x = (self.nodes[:-1, None] + self.h[:, None] * xi[None, :]).ravel()
        return Sampler(x, E0.tocsr(), sp.csr_matrix((ne * nq, self.n)))

    def load_vector(self, b) -> np.ndarray:
        """(b, φ_i) for a profile b(x), by scikit-fem's quadrature."""
        xq = self._basis.mapping.F(self._basis.X)[0]
        bq = np.broadcast_to(np.asarray(b(xq), dtype=float), xq.shape)
        return self.C.T @ load.assemble(self._basis, b=bq)

    def interpolate(self, u, du=None) -> np.ndarray:
        """Nodal interpolation (the paper's (7.3)(ii): ζ⁰(x_j) = u₀(x_j)) at the free nodes."""
        values = np.broadcast_to(np.asarray(u(self.nodes), dtype=float), self.nodes.shape)
        return values[self.free].copy()

    def project(self, v) -> np.ndarray:
        """L² projection with the consistent mass (onto the space with its fixed nodes)."""
        import scipy.sparse.linalg as spla
        return spla.spsolve(self.M_consistent.tocsc(), self.load_vector(v))
