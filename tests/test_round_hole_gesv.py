"""The round-hole law's polish solves its Newton step by LAPACK's dgesv through numba's own
entry point (contact.round_hole.gesv): the same routine on the same copies as
np.linalg.solve, so the same bits, and False where np.linalg.solve raises."""
import numpy as np
import pytest

from conftest import compiled
from skfem_beam.contact.round_hole import gesv, solve_numpy


def test_gesv_is_np_linalg_solve_bit_for_bit():
    rng = np.random.default_rng(5)
    for _ in range(400):
        k = int(rng.integers(1, 9))
        J = rng.standard_normal((k, k)) * 10.0 ** rng.uniform(-3, 3, (k, k))
        F = rng.standard_normal(k)
        mine, theirs = F.copy(), F.copy()
        assert compiled(gesv)(J, mine) and solve_numpy(J, theirs)
        assert mine.tobytes() == theirs.tobytes() == np.linalg.solve(J, F).tobytes()


@pytest.mark.parametrize("bad", ["singular", "nan in J", "inf in F"])
def test_gesv_refuses_where_np_linalg_solve_raises(bad):
    J, F = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([1.0, 1.0])
    if bad == "singular":
        J[1] = 2 * J[0]
    elif bad == "nan in J":
        J[0, 1] = np.nan
    else:
        F[1] = np.inf
    assert not compiled(gesv)(J, F.copy())
    assert not solve_numpy(J, F.copy())


def test_matvec_is_numbas_d_at_x_bit_for_bit():
    """The law's D @ x by BLAS dgemv through numba's entry point (contact.round_hole.matvec):
    the call numba's own D @ x makes, so the same bits, empty shapes included."""
    from skfem_beam.contact.round_hole import matvec, matvec_numpy
    rng = np.random.default_rng(7)
    for _ in range(300):
        m, n = int(rng.integers(0, 12)), int(rng.integers(0, 12))
        D = rng.standard_normal((m, n)) * 10.0 ** rng.uniform(-3, 3, (m, n))
        x = rng.standard_normal(n)
        mine, theirs = compiled(matvec)(D, x), matvec_numpy(D, x)
        assert mine.shape == (m,) and mine.tobytes() == theirs.tobytes()
