"""The compiled banded kernels against dense numpy, including matrices narrower than the band."""
import numpy as np
import pytest
import scipy.sparse as sp

from skfem_beam.linalg import Banded, band_solve, rows_dot, rows_matvec


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
    rows_matvec(B.rows, x, y, 1.0, False)
    assert np.abs(y - a @ x).max() < 1e-14 * np.abs(a).sum(axis=1).max() * np.abs(x).max()
    y2 = z.copy()
    rows_matvec(B.rows, x, y2, -0.5, True)
    assert np.abs(y2 - (z - 0.5 * a @ x)).max() < 1e-13

    assert rows_dot(B.rows, x, z) == pytest.approx(x @ a @ z, rel=1e-13, abs=1e-13)
