"""Cubic B-splines on a uniform mesh (1 dof per node), section 3.2 of Dumont–Paoli 2008.

On element e = [x_e, x_e + h] with local abscissa ξ = (x − x_e)/h ∈ [0, 1] the four
B-splines B_{e−1}, B_e, B_{e+1}, B_{e+2} are the paper's cubics in ξ.  We first work
with all J+3 B-splines B_{−1}..B_{J+1} ("full" numbering, index j+1 for B_j, with
coefficient c_j) and then impose the end conditions and the supports by a sparse basis
change, full coefficients = T · λ.  Element matrices are integrated once in ξ (Gauss,
exact for the degree-6 products) and scaled by h, so round-off does not depend on where
the beam sits on the x axis.  scikit-fem has no B-spline element; we use its quadrature
rule and its MeshLine for output.

End conditions.  At x_0 = 0 only B₋₁, B₀, B₁ are nonzero, and

    u(0) = (c₋₁ + 4c₀ + c₁)/6,   u'(0) = (c₁ − c₋₁)/(2h),   u''(0) = (c₋₁ − 2c₀ + c₁)/h²,

so an end condition is a condition on (c₋₁, c₀, c₁).  A basis of its solutions
replaces B₋₁, B₀, B₁ (columns of ``END_BLOCKS``):

    clamped  u = u' = 0   c₋₁ = c₁, c₀ = −c₁/2:  Φ = 2B₋₁ − B₀ + 2B₁ (the paper's Φ1,
                          today's choice; the only such combination up to scale);
    pinned   u = 0        c₋₁ = −4c₀ − c₁:  B₀ − 4B₋₁ and B₁ − B₋₁ (value 0 at x = 0,
                          slopes 2/h and 1/h: the slope stays free);
    sliding  u' = 0       c₋₁ = c₁:  B₀ and B₁ + B₋₁ (slope 0, value free);
    free                  B₋₁, B₀, B₁ unchanged (no reduction).

At x_J = L the same blocks act on the mirror (B_{J+1}, B_J, B_{J−1}) of (B₋₁, B₀, B₁):
u' only changes sign, which none of the conditions sees.  The new functions live on the
supports of the B-splines they replace and keep the node order, so M and S keep their
half bandwidth 3.  The two end blocks must not share a B-spline: two constrained ends
need J ≥ 3.  The natural conditions (u'' = 0 at pinned and free ends, u''' = 0 at
sliding and free ends) come from the weak form and need nothing, as with Hermite.

Supports.  u(x_m) = (c_{m−1} + 4c_m + c_{m+1})/6 = 0 at an interior node is one row of
G = (nodal values at the supports)·T_ends; one coefficient per row (the one of largest
weight: c_m away from a constrained end) is eliminated, λ_E = −G_E⁻¹ G_F λ_F.  For an
isolated support this is c_m = −(c_{m−1} + c_{m+1})/4: B_{m−1} − B_m/4 and
B_{m+1} − B_m/4 replace B_{m−1}, B_m, B_{m+1}, and the half bandwidth stays 3.
Supports at r adjacent nodes couple through G_E = tridiag(1, 4, 1) (diagonally
dominant): the r eliminated coefficients depend on the two flanking ones only, so the
two flanking functions stretch over the run, but they are neighbours in the dof
numbering once the run is gone and the half bandwidth stays 3 (``kd`` is read off the
matrices all the same).
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
from .ends import DEFAULT_ENDS, check_ends, fixed_dofs, support_nodes
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


#: columns: the functions replacing (B₋₁, B₀, B₁) at x = 0 (the mirror at x = L)
END_BLOCKS = {
    "clamped": np.array([[2.0], [-1.0], [2.0]]),
    "pinned": np.array([[-4.0, -1.0], [1.0, 0.0], [0.0, 1.0]]),
    "sliding": np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]),
    "free": np.eye(3),
}


def end_reduction(J: int, ends) -> sp.csr_matrix:
    """T (J+3, ·): coefficients of B₋₁..B_{J+1} from the ones the end conditions leave."""
    left = sp.csr_matrix(END_BLOCKS[ends[0]])
    right = sp.csr_matrix(END_BLOCKS[ends[1]][::-1, ::-1])  # on (B_{J−1}, B_J, B_{J+1})
    if ends[1] == "free":
        return sp.block_diag([left, sp.identity(J)], format="csr")
    if ends[0] == "free":
        return sp.block_diag([sp.identity(J), right], format="csr")
    if J < 3:
        raise InputError(f"element='bspline' with ends={tuple(ends)!r} needs J ≥ 3 (got "
                         f"J={J}): the two end conditions would share a B-spline")
    return sp.block_diag([left, sp.identity(J - 3), right], format="csr")


def support_reduction(G: sp.csr_matrix) -> sp.csr_matrix:
    """T (n, n − s) with G T = 0, eliminating one coefficient per row of G (s × n)."""
    s, n = G.shape
    Gd = G.toarray()
    pivots: list[int] = []
    for i in range(s):
        w = np.abs(Gd[i])
        w[pivots] = -1.0
        pivots.append(int(w.argmax()))
    E = np.array(pivots)
    F = np.setdiff1d(np.arange(n), E)
    # exact zeros stay zero (G_E is block diagonal over runs of adjacent supports)
    X = np.linalg.solve(Gd[:, E], Gd[:, F])
    T = np.zeros((n, F.size))
    T[F, np.arange(F.size)] = 1.0
    T[E, :] = -X
    return sp.csr_matrix(T)


class BSplineSpace:
    """V_h = span of the reduced B-splines on a uniform mesh; nodal values C·λ (the paper's D)."""
    name = "bspline"
    kd = 3  # half bandwidth of M and S (set per instance from the matrices)

    def __init__(self, nodes, ends=DEFAULT_ENDS, supports=(), weights=None):
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
        self.ends = check_ends(ends)
        self.support_nodes = support_nodes(x, supports)

        # T: reduced coefficients λ -> coefficients of B_{-1}..B_{J+1} (module docstring)
        T = end_reduction(J, self.ends)
        if self.support_nodes.size:
            rows = sp.diags([1.0, 4.0, 1.0], [0, 1, 2], shape=(J + 1, J + 3)).tocsr()
            T = sp.csr_matrix(T @ support_reduction(rows[self.support_nodes] @ T))
            T.eliminate_zeros()
        self._T = T
        self.n = T.shape[1]
        if self.n == 0:
            raise InputError(f"ends={self.ends!r} and supports with J={J} leave no "
                             "degree of freedom")
        value_fixed, slope_fixed = fixed_dofs(J, self.ends, self.support_nodes)
        #: nodes whose displacement is free (obstacle rows may only sit there)
        self.value_nodes = np.flatnonzero(~value_fixed)
        self._free_slopes = [i for i in (0, J) if not slope_fixed[i]]
        # element e touches B_{e-1}..B_{e+2}, i.e. full indices e..e+3
        self._dofs = np.arange(J)[:, None] + np.arange(4)[None, :]

        self.n_full, self.T, self.weights = J + 3, T, weights
        Me, Se = element_matrices(h)
        wm, wk = (None, None) if weights is None else weights
        self._Am, self._As = self._assemble_full(Me, wm), self._assemble_full(Se, wk)
        self.M = self._reduce_cols(self._T.T @ self._Am)
        self.S = self._reduce_cols(self._T.T @ self._As)
        band = sp.triu(self.M).tocoo()
        self.kd = int((band.col - band.row).max(initial=0))
        # nodal values u(x_0..x_J): B_j(x_{j∓1}) = 1/6, B_j(x_j) = 4/6, with exact zero rows
        # where u is fixed; C (rows x_1..x_J) is the paper's D
        NB = sp.diags([1 / 6, 4 / 6, 1 / 6], [0, 1, 2], shape=(J + 1, J + 3))
        self.nodal = self._reduce_cols(sp.diags((~value_fixed).astype(float)) @ NB)
        self.C = self.nodal[1:]

    def _reduce_cols(self, A) -> sp.csr_matrix:
        A = sp.csr_matrix(A @ self._T)
        A.eliminate_zeros()
        return A

    def _assemble_full(self, Ae: np.ndarray, weight=None) -> sp.csr_matrix:
        """Σ_e weight_e A_e on all J+3 B-splines (weight 1 when None)."""
        d = self._dofs
        r = np.repeat(d, 4, axis=1).ravel()
        c = np.tile(d, (1, 4)).ravel()
        v = np.tile(Ae.ravel(), self.J) if weight is None else \
            (np.asarray(weight, dtype=float)[:, None] * Ae.ravel()[None, :]).ravel()
        return sp.csr_matrix((v, (r, c)), shape=(self.J + 3,) * 2)

    def full_matrices(self):
        """(M, S) on all J+3 B-splines, before the end conditions and supports."""
        return self._Am, self._As

    def point_rows(self, x, derivative: int = 0, full: bool = False) -> sp.csr_matrix:
        """Rows evaluating d^k u/dx^k (k = 0, 1, 2, 3) at abscissae x (on the element to
        the right of a node, the last one at x = L; the third derivative is constant on an
        element)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        e = np.clip(np.searchsorted(self.nodes, x, side="right") - 1, 0, self.J - 1)
        xi = (x - self.nodes[e]) / self._hu
        N = np.column_stack([p.deriv(derivative)(xi) if derivative else p(xi)
                             for p in SHAPES]) / self._hu ** derivative
        rows = np.repeat(np.arange(x.size), 4)
        A = sp.csr_matrix((N.ravel(), (rows, self._dofs[e].ravel())),
                          shape=(x.size, self.J + 3))
        return A if full else self._reduce_cols(A)

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
        """"Complete" cubic spline interpolant: u at the nodes where u is free and u' at
        the ends where u' is free (clamped–free: u at x_1..x_J and the tip slope u'(L)).

        These are as many conditions as coefficients (the complete interpolant's J+3
        minus the fixed ones), exact for every function of V_h and O(h⁴) accurate for
        smooth u meeting the fixed conditions.  The end slopes are ``du`` or, without it,
        a five-point centred difference of u (exact for quartics, so only round-off
        ~1e-13 for the cubics of V_h).
        """
        J, h, L = self.J, self._hu, self.nodes[-1]
        if du is None:
            du = five_point_slope(u, 1e-3 * (L - self.nodes[0]))
        # u'(x_i) = (c_{i+1} − c_{i−1}) / 2h in B-spline coefficients (full indices i, i+2)
        ends = self._free_slopes
        slope = sp.csr_matrix(([-0.5 / h, 0.5 / h] * len(ends),
                               (np.repeat(np.arange(len(ends)), 2),
                                [j for i in ends for j in (i, i + 2)])),
                              shape=(len(ends), J + 3))
        A = sp.vstack([self.nodal[self.value_nodes], self._reduce_cols(slope)]).tocsc()
        x, xe = self.nodes[self.value_nodes], self.nodes[ends]
        slopes = np.broadcast_to(np.asarray(du(xe), dtype=float), xe.shape) if ends else []
        return spla.spsolve(A, np.r_[np.broadcast_to(u(x), x.shape), slopes])

    def project(self, v) -> np.ndarray:
        return spla.spsolve(self.M.tocsc(), self.load_vector(v))
