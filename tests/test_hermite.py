"""The cubic Hermite space against closed forms and the cantilever's exact modes."""
import numpy as np
import pytest
import scipy.linalg

from conftest import rate
from skfem_beam.reference import CANTILEVER_BETA_L, cantilever_beta_l, cantilever_omegas
from skfem_beam.spaces.hermite import HermiteSpace


def closed_form(x):
    """M, S of the first paper (§4), assembled by hand, clamped dofs removed."""
    n = 2 * x.size
    M, S = np.zeros((n, n)), np.zeros((n, n))
    for e, h in enumerate(np.diff(x)):
        Me = h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                 [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
        Se = 2 / h**3 * np.array([[6, 3 * h, -6, 3 * h], [3 * h, 2 * h * h, -3 * h, h * h],
                                  [-6, -3 * h, 6, -3 * h], [3 * h, h * h, -3 * h, 2 * h * h]])
        d = np.arange(2 * e, 2 * e + 4)
        M[np.ix_(d, d)] += Me
        S[np.ix_(d, d)] += Se
    return M[2:, 2:], S[2:, 2:]


@pytest.mark.parametrize("x", [np.linspace(0, 1.501, 20), np.linspace(0, 10, 161),
                               np.linspace(100, 101.5, 200),
                               np.cumsum(np.r_[0, np.random.default_rng(0).uniform(0.5, 2, 30)])])
def test_matrices_equal_closed_forms(x):
    space = HermiteSpace(x)
    M, S = closed_form(x)
    assert np.abs(space.M.toarray() - M).max() <= 1e-13 * np.abs(M).max()
    assert np.abs(space.S.toarray() - S).max() <= 1e-13 * np.abs(S).max()


def test_cubics_are_reproduced_exactly():
    space = HermiteSpace(np.linspace(0, 1.5, 8))
    u = lambda x: x**2 * (0.3 - 0.1 * x)          # noqa: E731  (clamped cubic)
    du = lambda x: 0.6 * x - 0.3 * x**2           # noqa: E731
    c = space.interpolate(u, du)
    s = space.sampler(np.linspace(0, 1, 7))
    assert np.abs(s.E0 @ c - u(s.x)).max() < 1e-15
    assert np.abs(s.E2 @ c - (0.6 - 0.6 * s.x)).max() < 1e-12
    assert np.abs(space.C @ c - u(space.nodes[1:])).max() < 1e-15
    assert np.abs(space.project(u) - c).max() < 1e-12


def test_cantilever_roots():
    assert np.abs(cantilever_beta_l(4) - CANTILEVER_BETA_L).max() < 1e-8


def test_cantilever_frequencies_converge_at_rate_4():
    L, k2 = 1.501, 282.84
    exact = cantilever_omegas(L, k2, 4)
    Js = np.array([4, 8, 16, 32])
    errors = []
    for J in Js:
        sp = HermiteSpace(np.linspace(0, L, J + 1))
        # eigh(M, S) gives 1/ω² accurately for the lowest modes (docs/design.md §6: not eigh(S, M))
        mu = scipy.linalg.eigh(sp.M.toarray(), k2 * sp.S.toarray(), eigvals_only=True)
        omega = np.sort(1 / np.sqrt(mu[::-1][:4]))
        errors.append(np.abs(omega - exact) / exact)
    errors = np.array(errors)
    assert errors[-1, :4].max() < 1e-5
    for mode in (0, 1):
        assert rate(errors[:, mode], 1.0 / Js) >= 3.8
