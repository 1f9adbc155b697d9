"""Cubic B-splines on a uniform mesh (1 dof per node), section 3.2 of Dumont–Paoli 2008.

On element e = [x_e, x_e + h] with local abscissa ξ = (x − x_e)/h ∈ [0, 1] the four
B-splines B_{e−1}, B_e, B_{e+1}, B_{e+2} are the paper's cubics in ξ.  We first work
with all J+3 B-splines B_{−1}..B_{J+1} ("full" numbering, index j+1 for B_j) and then
impose the clamp through the paper's basis

    Φ1 = 2B₋₁ − B₀ + 2B₁  (the only combination of B₋₁, B₀, B₁ with u(0) = u'(0) = 0),
    Φ_i = B_i for i = 2..J+1,

i.e. full coefficients = T · λ with T of shape (J+3, J+1).  Element matrices are
integrated once in ξ (Gauss, exact for the degree-6 products) and scaled by h, so
round-off does not depend on where the beam sits on the x axis.  scikit-fem has no
B-spline element; we use its quadrature rule and its MeshLine for output.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.polynomial import Polynomial
from skfem import MeshLine
from skfem.quadrature import get_quadrature
from skfem.refdom import RefLine

from ..errors import InputError
from .hermite import Sampler, five_point_slope

_t = Polynomial([0.0, 1.0])
# the paper's shape functions on one element, in ξ: B_{e-1}, B_e, B_{e+1}, B_{e+2}
SHAPES = (
    (1 - _t) ** 3 / 6,
    (4 - 3 * _t + 3 * (1 - _t) ** 2 - 3 * (1 - _t) ** 3) / 6,
    (1 + 3 * _t + 3 * _t**2 - 3 * _t**3) / 6,
    _t**3 / 6,
)
QUAD_ORDER = 10  # Gauss in ξ: exact for M_e, S_e; accurate for smooth loads


def local_shapes(xi, derivative: int = 0) -> np.ndarray:
    """(len(xi), 4): d^k/dξ^k of the four element shape functions at ξ."""
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    return np.column_stack([p.deriv(derivative)(xi) if derivative else p(xi) for p in SHAPES])


def element_matrices(h: float) -> tuple[np.ndarray, np.ndarray]:
    """Element mass (u, v) and bending (u'', v'') matrices in the B-spline basis (no k²)."""
    X, W = get_quadrature(RefLine, QUAD_ORDER)
    N0 = local_shapes(X[0], 0)
    N2 = local_shapes(X[0], 2)
    Me = h * (N0.T * W) @ N0
    Se = (N2.T * W) @ N2 / h**3  # d²/dx² = h⁻² d²/dξ², dx = h dξ
    return (Me + Me.T) / 2, (Se + Se.T) / 2  # exactly symmetric (BLAS sums need not be)


class BSplineSpace:
    """V_h = span{Φ1..Φ_{J+1}} on a uniform mesh; nodal values C·λ (the paper's D)."""
    name = "bspline"
    kd = 3  # half bandwidth of M and S

    def __init__(self, nodes):
        x = np.asarray(nodes, dtype=float)
        if x.ndim != 1 or x.size < 2:
            raise InputError("B-spline space: nodes must be a 1-D array of at least 2 abscissae")
        self.J = J = x.size - 1
        span = x[-1] - x[0]
        h = span / J
        if not span > 0 or np.abs(np.diff(x) - h).max() > 1e-9 * h:
            raise InputError(f"B-spline space needs a uniform mesh: element lengths range "
                             f"over [{np.diff(x).min():g}, {np.diff(x).max():g}] "
                             f"(use element='hermite')")
        self.nodes = x
        self.h = np.diff(x)  # element lengths (equal up to round-off); matrices use span/J
        self._hu = h
        self.mesh = MeshLine(x)
        self.n = J + 1

        # T: clamped coefficients λ -> coefficients of B_{-1}..B_{J+1}
        rows = np.r_[0, 1, 2, np.arange(3, J + 3)]
        cols = np.r_[0, 0, 0, np.arange(1, J + 1)]
        vals = np.r_[2.0, -1.0, 2.0, np.ones(J)]
        self._T = sp.csr_matrix((vals, (rows, cols)), shape=(J + 3, J + 1))
        # element e touches B_{e-1}..B_{e+2}, i.e. full indices e..e+3
        self._dofs = np.arange(J)[:, None] + np.arange(4)[None, :]

        Me, Se = element_matrices(h)
        self.M = self._assemble(Me)
        self.S = self._assemble(Se)
        # nodal values: B_j(x_{j∓1}) = 1/6, B_j(x_j) = 4/6 -> the paper's D (rows x_1..x_J)
        CB = sp.diags([1 / 6, 4 / 6, 1 / 6], [1, 2, 3], shape=(J, J + 3))
        self.C = self._reduce_cols(CB)

    def _reduce_cols(self, A) -> sp.csr_matrix:
        A = sp.csr_matrix(A @ self._T)
        A.eliminate_zeros()
        return A

    def _assemble(self, Ae: np.ndarray) -> sp.csr_matrix:
        d = self._dofs
        r = np.repeat(d, 4, axis=1).ravel()
        c = np.tile(d, (1, 4)).ravel()
        A = sp.csr_matrix((np.tile(Ae.ravel(), self.J), (r, c)), shape=(self.J + 3,) * 2)
        return self._reduce_cols(self._T.T @ A)

    def _element_rows(self, N: np.ndarray) -> sp.csr_matrix:
        """Rows (element-major, then ξ) of point evaluations with local shape values N (nq, 4)."""
        ne, nq = self.J, N.shape[0]
        r = np.broadcast_to(np.arange(ne * nq).reshape(ne, nq, 1), (ne, nq, 4))
        c = np.broadcast_to(self._dofs[:, None, :], (ne, nq, 4))
        v = np.broadcast_to(N[None, :, :], (ne, nq, 4))
        A = sp.csr_matrix((v.ravel(), (r.ravel(), c.ravel())), shape=(ne * nq, self.J + 3))
        return self._reduce_cols(A)

    def sampler(self, xi) -> Sampler:
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        E0 = self._element_rows(local_shapes(xi, 0))
        E2 = self._element_rows(local_shapes(xi, 2) / self._hu**2)
        x = (self.nodes[:-1, None] + self.h[:, None] * xi[None, :]).ravel()
        return Sampler(x, E0, E2)

    def load_vector(self, b) -> np.ndarray:
        X, W = get_quadrature(RefLine, QUAD_ORDER)
        h = self._hu
        xq = self.nodes[:-1, None] + self.h[:, None] * X[0][None, :]   # (J, nq)
        bq = np.broadcast_to(np.asarray(b(xq), dtype=float), xq.shape)
        Fe = h * (bq * W) @ local_shapes(X[0], 0)       # (J, 4): ∫ b B_a dx per element
        F = np.bincount(self._dofs.ravel(), Fe.ravel(), minlength=self.J + 3)
        return self._T.T @ F

    def interpolate(self, u, du=None) -> np.ndarray:
        """Clamped "complete" cubic spline interpolant: u at x_1..x_J and the tip slope u'(L).

        With the clamp this is J+1 conditions for J+1 coefficients, exact for every
        function of V_h (so for clamped cubics) and O(h⁴) accurate for smooth u.  The
        tip slope is ``du(L)`` or, without ``du``, a five-point centred difference of u
        (exact for quartics, so only round-off ~1e-13 for the cubics of V_h).
        """
        J, h, L = self.J, self._hu, self.nodes[-1]
        if du is None:
            du = five_point_slope(u, 1e-3 * (L - self.nodes[0]))
        # u'(x_J) = (c_{J+1} − c_{J−1}) / 2h in B-spline coefficients (full indices J, J+2)
        slope = sp.csr_matrix(([-0.5 / h, 0.5 / h], ([0, 0], [J, J + 2])), shape=(1, J + 3))
        A = sp.vstack([self.C, self._reduce_cols(slope)]).tocsc()
        x = self.nodes[1:]
        tip_slope = np.asarray(du(np.array([L])), dtype=float).ravel()[:1]
        return spla.spsolve(A, np.r_[np.broadcast_to(u(x), x.shape), tip_slope])

    def project(self, v) -> np.ndarray:
        return spla.spsolve(self.M.tocsc(), self.load_vector(v))
