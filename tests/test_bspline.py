"""Cubic B-spline space (Dumont–Paoli 2008, §3.2) against the paper and the Hermite space."""
import numpy as np
import pytest
import scipy.linalg as sla
from skfem.quadrature import get_quadrature
from skfem.refdom import RefLine

from skfem_beam import Beam, BeamProblem, Load, Obstacles, beam_system, solve
from skfem_beam.errors import InputError
from skfem_beam.reference import cantilever_omegas
from skfem_beam.spaces import make_space
from skfem_beam.spaces.bspline import BSplineSpace, element_matrices
from skfem_beam.spaces.hermite import HermiteSpace

L, K2 = 1.501, 282.84

# the element matrices printed in the paper (without h/5040 and k²/(6h³))
PAPER_M = np.array([[20, 129, 60, 1], [129, 1188, 933, 60],
                    [60, 933, 1188, 129], [1, 60, 129, 20]], dtype=float)
PAPER_S = np.array([[2, -3, 0, 1], [-3, 6, -3, 0],
                    [0, -3, 6, -3], [1, 0, -3, 2]], dtype=float)


def rel(a, b):
    return np.abs(np.asarray(a) - b).max() / np.abs(b).max()


def clamped_cubic(x0):
    """u = a s² + b s³ with s = x − x0: in V_h on any mesh starting at x0."""
    a, b = 0.3, -0.7
    u = lambda x: a * (x - x0) ** 2 + b * (x - x0) ** 3            # noqa: E731
    du = lambda x: 2 * a * (x - x0) + 3 * b * (x - x0) ** 2         # noqa: E731
    ddu = lambda x: 2 * a + 6 * b * (x - x0)                         # noqa: E731
    # exact ∫u² and ∫(u'')² over [x0, x0 + ℓ]
    int_u2 = lambda l: a**2 * l**5 / 5 + 2 * a * b * l**6 / 6 + b**2 * l**7 / 7       # noqa: E731
    int_ddu2 = lambda l: 4 * a**2 * l + 12 * a * b * l**2 + 12 * b**2 * l**3          # noqa: E731
    return u, du, ddu, int_u2, int_ddu2


# --- 1. element and global matrices ---------------------------------------------------

def test_element_matrices_equal_the_paper():
    h = 0.37
    Me, Se = element_matrices(h)
    assert rel(Me, h / 5040 * PAPER_M) < 1e-12
    assert rel(Se, PAPER_S / (6 * h**3)) < 1e-12


@pytest.mark.parametrize("x0, x1, J", [(0.0, 10.0, 160), (100.0, 101.5, 199), (0.0, L, 19)])
def test_global_matrices_far_from_origin(x0, x1, J):
    s = BSplineSpace(np.linspace(x0, x1, J + 1))
    h = (x1 - x0) / J
    M, S = s.M.toarray(), s.S.toarray()
    # interior rows (past Φ1's three elements, before the free end): the paper's
    # element matrices summed over the 4 elements a B-spline covers
    m_row = h / 5040 * np.array([1, 120, 1191, 2416, 1191, 120, 1])
    s_row = np.array([1, 0, -9, 16, -9, 0, 1]) / (6 * h**3)
    for i in range(4, J - 3):
        assert rel(M[i, i - 3:i + 4], m_row) < 1e-12
        assert rel(S[i, i - 3:i + 4], s_row) < 1e-12
    # the clamped corner and the whole assembly: energies of a clamped cubic are exact.
    # cᵀSc is a fourth difference of smooth data (cancellation ~eps·J⁴), so its error is
    # measured against the round-off bound eps·|c|ᵀ|S||c| (measured 0.07–0.3 of it)
    u, du, _, int_u2, int_ddu2 = clamped_cubic(x0)
    c = s.interpolate(u, du)
    assert abs(c @ s.M @ c / int_u2(x1 - x0) - 1) < 1e-13
    bound = np.finfo(float).eps * (np.abs(c) @ abs(s.S) @ np.abs(c))
    assert abs(c @ s.S @ c - int_ddu2(x1 - x0)) < 5 * bound
    # symmetric positive definite, half bandwidth 3
    assert np.abs(M - M.T).max() == 0 and np.abs(S - S.T).max() == 0
    assert sla.eigvalsh(M).min() > 0 and sla.eigvalsh(S).min() > 0
    i, j = np.nonzero(M)
    assert np.abs(i - j).max() == s.kd == 3


def test_same_interface_as_hermite():
    x = np.linspace(0.0, L, 20)
    b, hm = make_space("bspline", x), HermiteSpace(x)
    assert isinstance(b, BSplineSpace) and b.name == "bspline"
    assert b.n == b.J + 1 == 20 and b.mesh.p.shape == hm.mesh.p.shape
    assert b.M.shape == b.S.shape == (b.n, b.n) and b.C.shape == (b.J, b.n)
    assert b.M.format == b.S.format == b.C.format == "csr"
    assert np.allclose(b.h, hm.h) and b.kd == hm.kd
    smp_b, smp_h = b.sampler([0.0, 0.5, 1.0]), hm.sampler([0.0, 0.5, 1.0])
    assert np.array_equal(smp_b.x, smp_h.x) and smp_b.E0.shape == (3 * b.J, b.n)


def test_non_uniform_mesh_is_refused():
    x = np.linspace(0.0, L, 11)
    x[3] += 0.01
    with pytest.raises(InputError, match="uniform"):
        BSplineSpace(x)


# --- 2. nodal values, interpolation, sampling, loads ----------------------------------

def test_nodal_value_matrix_is_the_papers_D():
    J = 7
    D = (np.diag(np.full(J, 4.0)) + np.diag(np.ones(J - 1), 1) + np.diag(np.ones(J - 1), -1))
    D = np.hstack([D, np.zeros((J, 1))])
    D[-1, -1] = 1.0
    D[0, 0], D[1, 0] = 7.0, 2.0   # Φ1(x_1) = −1 + 2·4, Φ1(x_2) = 2·1  (×1/6)
    C = BSplineSpace(np.linspace(0.0, L, J + 1)).C.toarray()
    assert np.abs(C - D / 6).max() < 1e-15


@pytest.mark.parametrize("x0, J", [(0.0, 16), (100.0, 40)])
def test_clamped_cubic_is_reproduced(x0, J):
    s = BSplineSpace(np.linspace(x0, x0 + L, J + 1))
    u, du, ddu, *_ = clamped_cubic(x0)
    c = s.interpolate(u, du)
    assert np.abs(s.C @ c - u(s.nodes[1:])).max() < 1e-13
    smp = s.sampler(np.linspace(0.0, 1.0, 7))
    assert np.abs(smp.E0 @ c - u(smp.x)).max() < 1e-10
    assert np.abs(smp.E2 @ c - ddu(smp.x)).max() < 1e-10
    # without the slope (five-point difference), with the L² projection
    assert np.abs(s.interpolate(u) - c).max() < 1e-10
    assert np.abs(s.project(u) - c).max() < 1e-10
    # the load vector of a V_h function is M·c
    assert rel(s.load_vector(u), s.M @ c) < 1e-12


def test_interpolation_error_is_fourth_order():
    errs = []
    for J in (10, 20, 40):
        s = BSplineSpace(np.linspace(0.0, L, J + 1))
        u = lambda x: np.sin(2 * x) - 2 * x          # noqa: E731  clamped: u(0) = u'(0) = 0
        smp = s.sampler(np.linspace(0.0, 1.0, 11))
        errs.append(np.abs(smp.E0 @ s.interpolate(u) - u(smp.x)).max())
    rates = np.log2(np.array(errs[:-1]) / errs[1:])
    assert rates.min() > 3.8, (errs, rates)


# --- 3. cantilever eigenfrequencies ---------------------------------------------------

def omegas(space, count):
    """ω_n of (k²S, M).  eigh(M, S) → 1/μ keeps the lowest modes (docs/design.md §6); then a
    Rayleigh quotient with (v'', v'') summed as squares at Gauss points removes the
    round-off of the assembled S·v (~eps·J⁴: a fourth difference of smooth data)."""
    mu, V = sla.eigh(space.M.toarray(), space.S.toarray())
    V = V[:, ::-1][:, :count]
    X, W = get_quadrature(RefLine, 6)
    E2, w = space.sampler(X[0]).E2, np.tile(W, space.J) * space.h[0]
    raw = np.sqrt(K2 / mu[::-1][:count])
    polished = np.sqrt([K2 * np.sum(w * (E2 @ v) ** 2) / (v @ space.M @ v) for v in V.T])
    return raw, polished


def test_cantilever_frequencies_converge_at_fourth_order():
    exact = cantilever_omegas(L, K2, 4)
    errs = []
    for J in (8, 16, 32, 64):
        raw, om = omegas(BSplineSpace(np.linspace(0.0, L, J + 1)), 2)
        errs.append(np.abs(om - exact[:2]) / exact[:2])
        assert np.all(np.abs(raw - om) / om < 2e-9)   # the round-off floor of eigh itself
    errs = np.array(errs)
    rates = np.log2(errs[:-1] / errs[1:])
    assert rates.min() >= 3.8, (errs, rates)
    assert errs[-1, 0] < 1e-9 and errs[-1, 1] < 3e-8


# --- 4. Hermite and B-spline converge to the same beam --------------------------------

def tip_history(J, element):
    pb = BeamProblem(Beam(10.0, 282.84), Obstacles(),
                     load=Load.uniform(lambda t: np.sin(10 * t)), J=J, element=element)
    return solve(beam_system(pb), dt=1e-3, T=0.5, beta=0.5).observed["tip_displacement"]


def test_hermite_and_bspline_tip_histories_agree_as_J_grows():
    diffs = []
    for J in (20, 40, 80):
        tip_h, tip_b = tip_history(J, "hermite"), tip_history(J, "bspline")
        diffs.append(np.abs(tip_h - tip_b).max() / np.abs(tip_h).max())
    diffs = np.array(diffs)
    assert diffs[0] < 1e-5
    assert np.all(diffs[:-1] / diffs[1:] > 8), diffs   # ≥ h³; measured ~20–37 (≈ h⁴·⁵)


STEPPED = """kind = "beam"
[[segments]]
length = 0.6
material = { E = 2.0e11, rho = 7800.0 }
section = { tube = { outer_diameter = 0.02, wall = 0.002 } }
[[segments]]
length = 0.4
material = { E = 7.0e10, rho = 2700.0 }
section = { rod = { diameter = 0.012 } }
[mesh]
J = 20
element = "ELEMENT"
[time]
dt = 1e-5
T = 0.01
"""


def test_bsplines_on_a_stepped_beam_warn_of_first_order(tmp_path, capsys):
    """C² B-splines cannot follow u'''s jump at a step: the second frequency of a steel
    tube + aluminium rod is 3.1 % off at J = 20 (Hermite: 4e-7 of the transfer-matrix
    488.253 rad/s), which ran without a word."""
    from skfem_beam.scenefile import modes_main
    omega = {}
    for element in ("bspline", "hermite"):
        path = tmp_path / f"{element}.toml"
        path.write_text(STEPPED.replace("ELEMENT", element))
        assert modes_main([str(path), "--n", "2"]) in (0, None)
        out = capsys.readouterr()
        omega[element] = float(out.out.splitlines()[2].split()[2])
        assert ("converge at first order" in out.err) == (element == "bspline"), out.err
    assert abs(omega["hermite"] / 488.253 - 1) < 1e-5
    assert omega["bspline"] / 488.253 - 1 > 0.02
