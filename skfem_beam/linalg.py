"""Banded symmetric (and CSR) algebra for the compiled time loop.

Matrices of the schemes are symmetric and banded (half bandwidth kd = 3 for cubic
Hermite and cubic B-splines, 1 for P1).  They are kept in LAPACK's upper band format,
transposed so that row j holds column j of the band: ``U[j, kd + i - j] = a[i, j]``.
The factor comes from LAPACK (scipy.linalg.cholesky_banded); the substitutions are
written out in numba because, at n ≈ 40, calling LAPACK's dpbtrs through ctypes costs
the same (0.93 vs 0.96 µs per solve, measured) and cannot be cached by numba.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numba import njit


class Banded:
    """A symmetric banded matrix.

    ``band`` (n, kd+1): the upper band as above; ``rows`` (n, 2kd+1): row j holds
    a[j, j−kd..j+kd] (zero outside), for products written as row dot products;
    ``chol`` (if factored): the Cholesky factor in the ``band`` layout, with the
    diagonal replaced by its reciprocal (the substitutions multiply, not divide).
    """

    def __init__(self, a, factor: bool = False):
        a = sp.csr_matrix(a)
        coo = sp.triu(a).tocoo()
        n = a.shape[0]
        kd = int((coo.col - coo.row).max()) if coo.nnz else 0
        ab = np.zeros((kd + 1, n))
        ab[kd + coo.row - coo.col, coo.col] = coo.data
        self.n, self.kd = n, kd
        self.band = np.ascontiguousarray(ab.T)
        full = a.tocoo()
        self.rows = np.zeros((n, 2 * kd + 1))
        self.rows[full.row, kd + full.col - full.row] = full.data
        self.chol = None
        if factor:
            self.chol = np.ascontiguousarray(scipy.linalg.cholesky_banded(ab).T)
            self.chol[:, kd] = 1.0 / self.chol[:, kd]

    def lapack_band(self, which: str = "band") -> np.ndarray:
        """The (kd+1, n) LAPACK layout of ``band`` or of the true Cholesky factor."""
        b = getattr(self, which).copy()
        if which == "chol":
            b[:, self.kd] = 1.0 / b[:, self.kd]
        return np.ascontiguousarray(b.T)


# The loops below treat the kd boundary rows apart from the interior ones, whose band
# needs no clipping: the interior loops then run about twice as fast (measured at n = 38),
# and the order of every sum is the same as with clipped loops, so results are unchanged.

@njit(cache=True)
def band_solve(U, b):
    """Overwrite b with A⁻¹b, A = RᵀR, R upper banded in U (reciprocal diagonal)."""
    n, w = U.shape
    kd = w - 1
    for j in range(min(kd, n)):
        s = b[j]
        for k in range(j):
            s -= U[j, kd + k - j] * b[k]
        b[j] = s * U[j, kd]
    for j in range(kd, n):
        s = b[j]
        for o in range(kd):
            s -= U[j, o] * b[j - kd + o]
        b[j] = s * U[j, kd]
    for j in range(n - 1, max(n - 1 - kd, -1), -1):
        s = b[j]
        for k in range(j + 1, n):
            s -= U[k, kd + j - k] * b[k]
        b[j] = s * U[j, kd]
    for j in range(n - 1 - kd, -1, -1):
        s = b[j]
        for o in range(1, kd + 1):
            s -= U[j + o, kd - o] * b[j + o]
        b[j] = s * U[j, kd]


@njit(cache=True)
def _edge_row(P, x, j):
    """Σ_o P[j, kd+o] x[j+o] for a row near the ends (band clipped to 0..n−1)."""
    n, w = P.shape
    kd = w // 2
    s = 0.0
    for o in range(max(-kd, -j), min(kd, n - 1 - j) + 1):
        s += P[j, kd + o] * x[j + o]
    return s


@njit(cache=True)
def rows_matvec(P, x, y, c, add):
    """y = c P x (or y += c P x with ``add``) for banded P in row layout.  No defaults,
    and compiled callers pass ``np.bool_(add)``: every call then has one signature and
    the first run compiles it once (a bare True is a literal type, a second compile)."""
    n, w = P.shape
    kd = w // 2
    for j in range(min(kd, n)):
        y[j] = y[j] + c * _edge_row(P, x, j) if add else c * _edge_row(P, x, j)
    for j in range(kd, n - kd):
        s = 0.0
        for o in range(w):
            s += P[j, o] * x[j - kd + o]
        y[j] = y[j] + c * s if add else c * s
    for j in range(max(kd, n - kd), n):
        y[j] = y[j] + c * _edge_row(P, x, j) if add else c * _edge_row(P, x, j)


@njit(cache=True)
def rows_dot(P, x, z):
    """xᵀ P z for banded P in row layout."""
    n, w = P.shape
    kd = w // 2
    s = 0.0
    for j in range(min(kd, n)):
        s += x[j] * _edge_row(P, z, j)
    for j in range(kd, n - kd):
        t = 0.0
        for o in range(w):
            t += P[j, o] * z[j - kd + o]
        s += x[j] * t
    for j in range(max(kd, n - kd), n):
        s += x[j] * _edge_row(P, z, j)
    return s


@njit(cache=True)
def csr_product(Rp, Ri, Rx, u, y):
    """y ← R u for R given as CSR arrays."""
    for r in range(y.size):
        s = 0.0
        for p in range(Rp[r], Rp[r + 1]):
            s += Rx[p] * u[Ri[p]]
        y[r] = s
