"""The compiled banded kernels against dense numpy, including matrices narrower than the band."""
import numpy as np
import pytest
import scipy.sparse as sp

from skfem_beam.linalg import Banded, add_columns, band_solve, rows_dot, rows_matvec


def banded_spd(n, kd, seed):
    rng = np.random.default_rng(seed)
    a = np.zeros((n, n))
    for o in range(1, min(kd, n - 1) + 1):
        d = rng.uniform(-1, 1, n - o)
        a += np.diag(d, o) + np.diag(d, -o)
    return a + np.diag(2 * kd + 1 + rng.uniform(0, 1, n))   # diagonally dominant


@pytest.mark.parametrize("n", [1, 2, 3, 4, 6, 7, 38])
@pytest.mark.parametrize("kd", [0, 1, 3])
def test_banded_kernels_equal_dense(n, kd):
    a = banded_spd(n, kd, seed=10 * n + kd)
    B = Banded(sp.csr_matrix(a), factor=True)
    rng = np.random.default_rng(n + kd)
    x, z = rng.normal(size=n), rng.normal(size=n)

    b = x.copy()
    band_solve(B.chol, b)
    assert np.abs(a @ b - x).max() < 1e-13 * np.abs(x).max() * np.linalg.cond(a)

    y = np.full(n, np.nan)   # overwritten, never read
    rows_matvec(B.rows, B.cols, x, y, 1.0, False)
    assert np.abs(y - a @ x).max() < 1e-14 * np.abs(a).sum(axis=1).max() * np.abs(x).max()
    y2 = z.copy()
    rows_matvec(B.rows, B.cols, x, y2, -0.5, True)
    assert np.abs(y2 - (z - 0.5 * a @ x)).max() < 1e-13

    assert rows_dot(B.rows, B.cols, x, z) == pytest.approx(x @ a @ z, rel=1e-13, abs=1e-13)


# The loops of the kernels before they left the band's zeros out and ran four forward rows
# at once (plain Python): each sum in the same order, so the results must be the same bits
# (the pinned runs rely on it, tests/reference).
def dense_rows(a, kd):
    n = a.shape[0]
    P = np.zeros((n, 2 * kd + 1))
    for j in range(n):
        for o in range(-kd, kd + 1):
            if 0 <= j + o < n:
                P[j, kd + o] = a[j, j + o]
    return P


def old_matvec(P, x):
    n, w = P.shape
    kd = w // 2
    y = np.zeros(n)
    for j in range(n):
        s = 0.0
        for o in range(max(-kd, -j), min(kd, n - 1 - j) + 1):
            s += P[j, kd + o] * x[j + o]
        y[j] = s
    return y


def old_solve(U, b):
    n, w = U.shape
    kd = w - 1
    b = b.copy()
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
    return b


@pytest.mark.parametrize("gaps", [False, True])
@pytest.mark.parametrize("n, kd", [(5, 4), (9, 4), (30, 4), (31, 7), (60, 12), (61, 20)])
def test_kernels_give_the_plain_loops_bits(n, kd, gaps):
    """kd ≥ 4 (the four-row forward substitution), a full band (a beam's) or one with
    zeros inside (``gaps``, as a plate's: nonzeros at offsets 0, ±1, ±(kd−1), ±kd): the
    same bits as the plain loops over the band."""
    a = banded_spd(n, kd, seed=n + kd)
    if gaps:
        offset = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
        a[(offset >= 2) & (offset <= kd - 2)] = 0.0
    B = Banded(sp.csr_matrix(a), factor=True)
    assert B.rows.shape[1] == (a != 0).sum(axis=1).max()      # the zeros are left out
    rng = np.random.default_rng(kd)
    x = rng.normal(size=n)
    P = dense_rows(a, kd)
    y = np.empty(n)
    rows_matvec(B.rows, B.cols, x, y, 1.0, False)
    Px = old_matvec(P, x)
    assert np.array_equal(y, Px)
    assert rows_dot(B.rows, B.cols, x, x) == sum(x[j] * Px[j] for j in range(n))
    U = B.lapack_band("chol").T.copy()
    U[:, kd] = 1.0 / U[:, kd]
    b = x.copy()
    band_solve(B.chol, b)
    assert np.array_equal(b, old_solve(U, x))


@pytest.mark.parametrize("shape", [(80, 41), (1100, 500)])
def test_add_columns_gives_the_plain_loops_bits(shape):
    """x += W c over the nonzero c from Wt = Wᵀ (W's columns contiguous), each x[i]'s
    sum in the order of j, as the plain loop on W."""
    n, m = shape
    rng = np.random.default_rng(m)
    W = rng.normal(size=(n, m))
    c = np.where(rng.uniform(size=m) < 0.2, rng.normal(size=m), 0.0)
    x0 = rng.normal(size=n)
    x = x0.copy()
    add_columns(np.ascontiguousarray(W.T), c, x)
    plain = x0.copy()
    for j in np.flatnonzero(c):
        for i in range(n):
            plain[i] += W[i, j] * c[j]
    assert np.count_nonzero(c) > 5
    assert np.array_equal(x, plain)
