"""Banded symmetric algebra for the compiled time loop.

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


@njit(cache=True)
def band_solve(U, b):
    """Overwrite b with A⁻¹b, A = RᵀR, R upper banded in U (reciprocal diagonal)."""
    n, w = U.shape
    kd = w - 1
    for j in range(n):
        s = b[j]
        for k in range(max(0, j - kd), j):
            s -= U[j, kd + k - j] * b[k]
        b[j] = s * U[j, kd]
    for j in range(n - 1, -1, -1):
        s = b[j]
        for k in range(j + 1, min(n, j + kd + 1)):
            s -= U[k, kd + j - k] * b[k]
        b[j] = s * U[j, kd]


@njit(cache=True)
def rows_matvec2(P, x, Q, z, y):
    """y = P x − Q z for banded P, Q in row layout (the scheme's right-hand side)."""
    n, w = P.shape
    kd = w // 2
    for j in range(n):
        s = 0.0
        for o in range(max(-kd, -j), min(kd, n - 1 - j) + 1):
            s += P[j, kd + o] * x[j + o] - Q[j, kd + o] * z[j + o]
        y[j] = s


@njit(cache=True)
def rows_dot(P, x, z):
    """xᵀ P z for banded P in row layout."""
    n, w = P.shape
    kd = w // 2
    s = 0.0
    for j in range(n):
        t = 0.0
        for o in range(max(-kd, -j), min(kd, n - 1 - j) + 1):
            t += P[j, kd + o] * z[j + o]
        s += x[j] * t
    return s
