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
    """A symmetric banded matrix: ``band`` (n, kd+1) and, if factored, ``chol``."""

    def __init__(self, a, factor: bool = False):
        coo = sp.triu(sp.csr_matrix(a)).tocoo()
        n = a.shape[0]
        kd = int((coo.col - coo.row).max()) if coo.nnz else 0
        ab = np.zeros((kd + 1, n))
        ab[kd + coo.row - coo.col, coo.col] = coo.data
        self.n, self.kd = n, kd
        self.band = np.ascontiguousarray(ab.T)
        self.chol = None
        if factor:
            self.chol = np.ascontiguousarray(scipy.linalg.cholesky_banded(ab).T)

    def lapack_band(self, which: str = "band") -> np.ndarray:
        """The (kd+1, n) LAPACK layout of ``band`` or ``chol``."""
        return np.ascontiguousarray(getattr(self, which).T)


@njit(cache=True)
def band_solve(U, b):
    """Overwrite b with A⁻¹b, A = RᵀR, R upper banded stored in U (see module doc)."""
    n, w = U.shape
    kd = w - 1
    for j in range(n):
        s = b[j]
        for k in range(max(0, j - kd), j):
            s -= U[j, kd + k - j] * b[k]
        b[j] = s / U[j, kd]
    for j in range(n - 1, -1, -1):
        s = b[j]
        for k in range(j + 1, min(n, j + kd + 1)):
            s -= U[k, kd + j - k] * b[k]
        b[j] = s / U[j, kd]


@njit(cache=True)
def band_matvec(U, x, y, alpha):
    """y += alpha·A·x for the symmetric band A stored in U."""
    n, w = U.shape
    kd = w - 1
    for j in range(n):
        y[j] += alpha * U[j, kd] * x[j]
        for k in range(max(0, j - kd), j):
            a = alpha * U[j, kd + k - j]
            y[k] += a * x[j]
            y[j] += a * x[k]


@njit(cache=True)
def band_dot(U, x, z):
    """xᵀ A z for the symmetric band A stored in U."""
    n, w = U.shape
    kd = w - 1
    s = 0.0
    for j in range(n):
        s += U[j, kd] * x[j] * z[j]
        for k in range(max(0, j - kd), j):
            s += U[j, kd + k - j] * (x[k] * z[j] + x[j] * z[k])
    return s
