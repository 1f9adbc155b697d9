"""Banded symmetric (and CSR) algebra for the compiled time loop.

Matrices of the schemes are symmetric and banded (half bandwidth kd = 3 for cubic
Hermite and cubic B-splines, 1 for P1; a BFS plate's grows with its side, 167 at
40 × 40, with 36 nonzeros a row).  They are kept in LAPACK's upper band format,
transposed so that row j holds column j of the band: ``U[j, kd + i - j] = a[i, j]``.
The factor comes from LAPACK (scipy.linalg.cholesky_banded); the substitutions are
written out in numba because, at n ≈ 40, calling LAPACK's dpbtrs through ctypes costs
the same (0.93 vs 0.96 µs per solve, measured) and cannot be cached by numba.  The
kernels' sums are those of plain loops over the band, term by term in the same order,
so that a faster layout never changes a pinned run's bits (tests/test_linalg.py).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numba import njit


class Banded:
    """A symmetric banded matrix.

    ``band`` (n, kd+1): the upper band as above; ``rows`` and ``cols`` (n, w): the row
    layout of the products, written as row dot products: row j's nonzeros a[j, cols[j]]
    in increasing column order (`row_layout`); the band's zeros left out (a plate's row
    has 36 nonzeros in a band of 2kd+1 = 335 at 40 × 40) change no sum's value or order;
    ``chol`` (if factored): (n, 2kd+1), row j holds the Cholesky factor R's column j
    above the diagonal, the reciprocal of R[j, j] (the substitutions multiply, not
    divide), then R's row j right of the diagonal, so that both substitutions read rows.
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
        self.rows, self.cols = row_layout(a)
        self.chol = None
        if factor:
            R = np.ascontiguousarray(scipy.linalg.cholesky_banded(ab).T)
            self.chol = np.zeros((n, 2 * kd + 1))
            self.chol[:, :kd + 1] = R
            self.chol[:, kd] = 1.0 / R[:, kd]
            for o in range(1, min(kd, n - 1) + 1):     # R[j, j+o] = R's column j+o
                self.chol[:n - o, kd + o] = R[o:, kd - o]

    def lapack_band(self, which: str = "band") -> np.ndarray:
        """The (kd+1, n) LAPACK layout of ``band`` or of the true Cholesky factor."""
        b = getattr(self, which)[:, :self.kd + 1].copy()
        if which == "chol":
            b[:, self.kd] = 1.0 / b[:, self.kd]
        return np.ascontiguousarray(b.T)


def row_layout_of(b: Banded | None) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of ``b``; empty (0 rows) for None (no damping)."""
    if b is None:
        return np.zeros((0, 1)), np.zeros((0, 1), dtype=np.int64)
    return b.rows, b.cols


def row_layout(a) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of ``a`` for ``Banded``: each row's nonzero values and their
    columns, increasing, padded with zeros at the row's own column to the longest row."""
    a = sp.csr_matrix(a, copy=True)
    a.sum_duplicates()
    a.sort_indices()
    a.eliminate_zeros()
    n = a.shape[0]
    length = np.diff(a.indptr)
    w = max(int(length.max()) if n else 0, 1)
    rows = np.zeros((n, w))
    cols = np.repeat(np.arange(n, dtype=np.int64)[:, None], w, axis=1)
    at = np.arange(a.nnz) - np.repeat(a.indptr[:-1], length)
    which = np.repeat(np.arange(n), length)
    rows[which, at] = a.data
    cols[which, at] = a.indices
    return rows, cols


# The substitutions treat the kd boundary rows apart from the interior ones, whose band
# needs no clipping (about twice as fast, measured at n = 38), and the forward one runs
# four interior rows at a time: each row's sum is still taken term by term in the same
# order, so every result is the same to the bit, but the four sums' additions overlap
# instead of waiting for each other.  The backward sums cannot overlap: each row's first
# term is the row just solved (docs/plate.md, "The scheme's own step").

@njit(cache=True)
def band_solve(F, b):
    """Overwrite b with A⁻¹b, A = RᵀR, R in ``Banded.chol``'s layout ``F`` (n, 2kd+1)."""
    n, w = F.shape
    kd = (w - 1) // 2
    for j in range(min(kd, n)):
        s = b[j]
        for k in range(j):
            s -= F[j, kd + k - j] * b[k]
        b[j] = s * F[j, kd]
    j = kd
    if kd >= 4:
        while j + 4 <= n:
            s0, s1, s2, s3 = b[j], b[j + 1], b[j + 2], b[j + 3]
            for o in range(kd - 3):     # the terms of rows j..j+3 known before row j
                s0 -= F[j, o] * b[j - kd + o]
                s1 -= F[j + 1, o] * b[j + 1 - kd + o]
                s2 -= F[j + 2, o] * b[j + 2 - kd + o]
                s3 -= F[j + 3, o] * b[j + 3 - kd + o]
            for o in range(kd - 3, kd):
                s0 -= F[j, o] * b[j - kd + o]
            b[j] = s0 * F[j, kd]
            for o in range(kd - 3, kd):
                s1 -= F[j + 1, o] * b[j + 1 - kd + o]
            b[j + 1] = s1 * F[j + 1, kd]
            for o in range(kd - 3, kd):
                s2 -= F[j + 2, o] * b[j + 2 - kd + o]
            b[j + 2] = s2 * F[j + 2, kd]
            for o in range(kd - 3, kd):
                s3 -= F[j + 3, o] * b[j + 3 - kd + o]
            b[j + 3] = s3 * F[j + 3, kd]
            j += 4
    for i in range(j, n):
        s = b[i]
        for o in range(kd):
            s -= F[i, o] * b[i - kd + o]
        b[i] = s * F[i, kd]
    for j in range(n - 1, max(n - 1 - kd, -1), -1):
        s = b[j]
        for k in range(j + 1, n):
            s -= F[j, kd + k - j] * b[k]
        b[j] = s * F[j, kd]
    for j in range(n - 1 - kd, -1, -1):
        s = b[j]
        for o in range(1, kd + 1):
            s -= F[j, kd + o] * b[j + o]
        b[j] = s * F[j, kd]


@njit(cache=True)
def rows_matvec(P, J, x, y, c, add):
    """y = c P x (or y += c P x with ``add``) for P in the row layout (P, J) of
    ``Banded``.  No defaults, and compiled callers pass ``np.bool_(add)``: every call
    then has one signature and the first run compiles it once (a bare True is a literal
    type, a second compile)."""
    n, w = P.shape
    for j in range(n):
        s = 0.0
        for o in range(w):
            s += P[j, o] * x[J[j, o]]
        y[j] = y[j] + c * s if add else c * s


@njit(cache=True)
def rows_dot(P, J, x, z):
    """xᵀ P z for P in the row layout (P, J) of ``Banded``."""
    n, w = P.shape
    s = 0.0
    for j in range(n):
        t = 0.0
        for o in range(w):
            t += P[j, o] * z[J[j, o]]
        s += x[j] * t
    return s


@njit(cache=True)
def add_columns(Wt, c, x):
    """x += W c with Wt = Wᵀ (m × n, W's columns as its rows: contiguous), over the
    columns j where c[j] ≠ 0, each x[i]'s sum in the order of j."""
    for j in range(c.size):
        if c[j] != 0.0:
            for i in range(x.size):
                x[i] += Wt[j, i] * c[j]


@njit(cache=True)
def csr_product(Rp, Ri, Rx, u, y):
    """y ← R u for R given as CSR arrays."""
    for r in range(y.size):
        s = 0.0
        for p in range(Rp[r], Rp[r + 1]):
            s += Rx[p] * u[Ri[p]]
        y[r] = s
