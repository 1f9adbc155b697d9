"""Cubic Hermite elements (2 dofs per node: value and slope) through scikit-fem.

scikit-fem's ``ElementLineHermite`` builds its basis in global monomials, so its
round-off grows with the distance from the origin over the element size (measured:
3.6e-9 relative error in M at J=160 on [0, 10], 9e-3 at J=199 on [100, 101.5]).  We
therefore assemble on a *broken* copy of the mesh in which every element starts at
x = 0 — the element matrices are translation invariant — and gather the element
blocks into the global numbering.  The result equals the closed forms to round-off.

End conditions and supports (:mod:`.ends`) drop degrees of freedom: a clamped end its
value and slope, a pinned end its value, a sliding end its slope, a free end nothing,
a rigid support the value at its node.  The remaining dofs keep the node order, so M
and S stay banded (half bandwidth 3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementLineHermite, LinearForm, MeshLine
from skfem.helpers import dd

from ..errors import InputError
from .ends import DEFAULT_ENDS, check_ends, fixed_dofs, support_nodes


@BilinearForm
def mass(u, v, w):
    return u * v


@BilinearForm
def bending(u, v, w):
    return dd(u)[0, 0] * dd(v)[0, 0]


@BilinearForm
def weighted_mass(u, v, w):
    return w["c"] * u * v


@BilinearForm
def weighted_bending(u, v, w):
    return w["c"] * dd(u)[0, 0] * dd(v)[0, 0]


@LinearForm
def load(v, w):
    return w["b"] * v


def five_point_slope(u, step: float):
    """u' by the centred five-point difference (exact for quartics: only round-off for cubics)."""
    return lambda z: (u(z - 2 * step) - 8 * u(z - step) + 8 * u(z + step) - u(z + 2 * step)) \
        / (12 * step)


@dataclass
class Sampler:
    """Point evaluation: ``x`` (abscissae), ``E0 @ c`` values, ``E2 @ c`` second derivatives."""
    x: np.ndarray
    E0: sp.csr_matrix
    E2: sp.csr_matrix


class HermiteSpace:
    name = "hermite"
    kd = 3  # half bandwidth of M and S

    def __init__(self, nodes, ends=DEFAULT_ENDS, supports=(), weights=None):
        x = np.asarray(nodes, dtype=float)
        self.nodes = x
        self.J = J = x.size - 1
        self.h = np.diff(x)
        self.ends = check_ends(ends)
        self.support_nodes = support_nodes(x, supports)
        self.mesh = MeshLine(x)
        p = np.zeros(2 * J)
        p[1::2] = self.h
        # a fresh element per mesh (docs/design.md §6: the element caches mesh data)
        self._broken = MeshLine(p, np.ascontiguousarray(np.arange(2 * J).reshape(J, 2).T))
        self._basis = Basis(self._broken, ElementLineHermite(), intorder=8)
        # P: global dofs (2 per node: value, slope; node 0 first) -> broken dofs; then keep
        # the dofs that the end conditions and supports leave free
        ed = self._basis.element_dofs
        glob = 2 * np.arange(J)[None, :] + np.arange(4)[:, None]
        P = sp.csr_matrix((np.ones(ed.size), (ed.ravel(), glob.ravel())),
                          shape=(self._basis.N, 2 * J + 2))
        value_fixed, slope_fixed = fixed_dofs(J, self.ends, self.support_nodes)
        free = np.flatnonzero(~np.column_stack([value_fixed, slope_fixed]).ravel())
        if free.size == 0:
            raise InputError(f"ends={self.ends!r} with J={J} leave no degree of freedom")
        self._free = free
        self._P = P[:, free].tocsr()
        self.n = free.size
        #: nodes whose displacement is free (obstacle rows may only sit there)
        self.value_nodes = np.flatnonzero(~value_fixed)
        self._Pall = P
        self.n_full = 2 * J + 2
        self.T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))),
                               shape=(self.n_full, free.size))
        self.weights = weights
        if weights is None:
            self._Am, self._As = mass.assemble(self._basis), bending.assemble(self._basis)
        else:   # per element ρA_e/ρA_ref, EI_e/EI_ref (a stepped beam)
            nq = self._basis.X.shape[1]
            wm, wk = (np.broadcast_to(np.asarray(w, dtype=float)[:, None], (J, nq))
                      for w in weights)
            self._Am = weighted_mass.assemble(self._basis, c=wm)
            self._As = weighted_bending.assemble(self._basis, c=wk)
        self.M = self._gather(self._Am)
        self.S = self._gather(self._As)
        # nodal values u(x_0..x_J) = nodal @ c (zero rows where u is fixed); C: x_1..x_J
        col = np.searchsorted(free, 2 * self.value_nodes)
        self.nodal = sp.csr_matrix((np.ones(col.size), (self.value_nodes, col)),
                                   shape=(J + 1, self.n))
        self.C = self.nodal[1:]

    def _gather(self, A):
        return (self._P.T @ A @ self._P).tocsr()

    def full_matrices(self):
        """(M, S) on every dof, fixed ones included (2 per node, value first)."""
        return (self._Pall.T @ self._Am @ self._Pall).tocsr(), \
            (self._Pall.T @ self._As @ self._Pall).tocsr()

    def point_rows(self, x, derivative: int = 0, full: bool = False,
                   side: str = "right") -> sp.csr_matrix:
        """Rows evaluating d^k u/dx^k (k = 0, 1, 2, 3) at abscissae x, from the closed-form
        cubic Hermite shape functions on the element holding each x (the one to the
        ``side`` of a node, right by default; the last one at x = L, the first at 0; the
        third derivative is constant on an element, the second jumps at a node)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        e = np.clip(np.searchsorted(self.nodes, x, side=side) - 1, 0, self.J - 1)
        h = self.h[e]
        s = (x - self.nodes[e]) / h
        one = np.ones_like(s)
        N = {0: (1 - 3 * s**2 + 2 * s**3, h * (s - 2 * s**2 + s**3), 3 * s**2 - 2 * s**3,
                 h * (s**3 - s**2)),
             1: ((6 * s**2 - 6 * s) / h, 1 - 4 * s + 3 * s**2, (6 * s - 6 * s**2) / h,
                 3 * s**2 - 2 * s),
             2: ((12 * s - 6) / h**2, (6 * s - 4) / h, (6 - 12 * s) / h**2,
                 (6 * s - 2) / h),
             3: (12 / h**3, 6 / h**2, -12 / h**3, 6 / h**2)}[derivative]
        rows = np.tile(np.arange(x.size), 4)
        cols = np.concatenate([2 * e + k for k in range(4)])
        A = sp.csr_matrix((np.concatenate([v * one for v in N]), (rows, cols)),
                          shape=(x.size, self.n_full))
        return A if full else (A @ self.T).tocsr()

    def sampler(self, xi) -> Sampler:
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        b = Basis(self._broken, ElementLineHermite(), quadrature=(xi[None, :], np.ones(xi.size)))
        ne, nq = self.J, xi.size
        rows = np.arange(ne * nq).reshape(ne, nq)
        r, c, v0, v2 = [], [], [], []
        for i in range(4):
            phi = b.basis[i][0]
            r.append(rows)
            c.append(np.broadcast_to(b.element_dofs[i][:, None], (ne, nq)))
            v0.append(np.asarray(phi))
            v2.append(phi.hess[0, 0])
        r, c = np.concatenate(r).ravel(), np.concatenate(c).ravel()
        shape = (ne * nq, b.N)
        E0 = sp.csr_matrix((np.concatenate(v0).ravel(), (r, c)), shape=shape) @ self._P
        E2 = sp.csr_matrix((np.concatenate(v2).ravel(), (r, c)), shape=shape) @ self._P
        x = (self.nodes[:-1, None] + self.h[:, None] * xi[None, :]).ravel()
        return Sampler(x, E0.tocsr(), E2.tocsr())

    def load_vector(self, b) -> np.ndarray:
        xq = self._basis.mapping.F(self._basis.X)[0] + self.nodes[:-1, None]
        bq = np.broadcast_to(np.asarray(b(xq), dtype=float), xq.shape)
        return self._P.T @ load.assemble(self._basis, b=bq)

    def interpolate(self, u, du=None) -> np.ndarray:
        if du is None:
            du = five_point_slope(u, 1e-3 * (self.nodes[-1] - self.nodes[0]))
        c = np.empty(self.n)
        is_value = self._free % 2 == 0
        x = self.nodes[self._free[is_value] // 2]
        c[is_value] = np.broadcast_to(u(x), x.shape)
        x = self.nodes[self._free[~is_value] // 2]
        c[~is_value] = np.broadcast_to(du(x), x.shape)
        return c

    def project(self, v) -> np.ndarray:
        import scipy.sparse.linalg as spla
        return spla.spsolve(self.M.tocsc(), self.load_vector(v))
