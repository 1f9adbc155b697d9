"""End conditions, intermediate supports and natural frequencies (skfem_beam.modes)."""
import importlib

import numpy as np
import pytest
from scipy.optimize import brentq

import skfem_beam
from conftest import rate
from skfem_beam import (Beam, BeamProblem, InitialState, InputError, Obstacles, Support,
                        beam_system, solve)
from skfem_beam.spaces import make_space

modes_module = importlib.import_module("skfem_beam.modes")   # skfem_beam.modes is the function

L, K2 = 1.501, 282.84
ELEMENTS = ("hermite", "bspline")

# characteristic equations f(βL) = 0, scaled (÷cosh) so that they stay O(1)
CHARACTERISTIC = {
    ("clamped", "free"): lambda z: np.cos(z) + 1 / np.cosh(z),      # cos cosh + 1 = 0
    ("pinned", "pinned"): np.sin,                                     # sin = 0
    ("clamped", "clamped"): lambda z: np.cos(z) - 1 / np.cosh(z),   # cos cosh − 1 = 0
    ("clamped", "pinned"): lambda z: np.sin(z) - np.cos(z) * np.tanh(z),   # tan = tanh
    ("sliding", "pinned"): np.cos,                                    # cos = 0
    ("free", "free"): lambda z: np.cos(z) - 1 / np.cosh(z),         # as clamped–clamped
}


def beta_L(ends, count):
    """The first ``count`` positive roots βL of the characteristic equation (brentq)."""
    f = CHARACTERISTIC[ends]
    grid = np.arange(0.5, 40.0, 0.01)
    v = f(grid)
    roots = [brentq(f, a, b, xtol=1e-14, rtol=1e-15)
             for a, b, fa, fb in zip(grid[:-1], grid[1:], v[:-1], v[1:]) if fa * fb < 0]
    return np.array(roots[:count])


def exact_omegas(ends, count, length=L):
    return beta_L(ends, count) ** 2 * np.sqrt(K2) / length**2


def omegas(ends, J, element, count=4, supports=()):
    problem = BeamProblem(Beam(L, K2), J=J, element=element, ends=ends, supports=supports)
    return skfem_beam.modes(problem, n=count).omega


def test_characteristic_roots_are_the_textbook_ones():
    # guards the root finder itself (the values every handbook lists)
    assert abs(beta_L(("clamped", "free"), 1)[0] - 1.8751040687) < 1e-9
    assert abs(beta_L(("clamped", "clamped"), 1)[0] - 4.7300407449) < 1e-9
    assert abs(beta_L(("clamped", "pinned"), 1)[0] - 3.9266023120) < 1e-9
    assert np.allclose(beta_L(("pinned", "pinned"), 4), np.pi * np.arange(1, 5), rtol=1e-14)


@pytest.mark.parametrize("element", ELEMENTS)
@pytest.mark.parametrize("ends", [("clamped", "free"), ("pinned", "pinned"),
                                  ("clamped", "clamped"), ("clamped", "pinned"),
                                  ("sliding", "pinned")])
def test_first_four_frequencies_converge_at_fourth_order(ends, element):
    exact = exact_omegas(ends, 4)
    Js = np.array([10, 20, 40, 80])
    errs = np.array([np.abs(omegas(ends, J, element) - exact) / exact for J in Js])
    # J = 40: ≤ 1e-5 except the clamped–clamped 4th mode, whose cubic-element error
    # ≈ (β₄h)⁴/1400 is 1.08e-5 (Hermite) and 1.11e-5 (B-spline) at J = 40
    tol = np.full(4, 1e-5)
    if ends == ("clamped", "clamped"):
        tol[3] = 1.2e-5
    assert np.all(errs[Js == 40][0] <= tol), errs[Js == 40]
    for m in range(4):
        assert rate(errs[:, m], 1.0 / Js) >= 3.8, (m, errs[:, m])


@pytest.mark.parametrize("element", ELEMENTS)
def test_free_free_beam_has_two_rigid_modes_then_the_flexible_ones(element):
    om = omegas(("free", "free"), 40, element, count=5)
    exact = exact_omegas(("free", "free"), 3)
    assert np.all(om[:2] < 1e-6 * exact[0])
    assert np.all(np.abs(om[2:] - exact) / exact < 1e-5)


@pytest.mark.parametrize("element", ELEMENTS)
def test_two_span_beam_has_the_single_span_frequencies(element):
    """Pinned at 0, L/2 and L: mode 1 is antisymmetric (each span pinned–pinned of length
    L/2), mode 2 symmetric (zero slope over the support: each span clamped–pinned)."""
    om = omegas(("pinned", "pinned"), 40, element, count=2, supports=(L / 2,))
    pp = exact_omegas(("pinned", "pinned"), 1, L / 2)[0]
    cp = exact_omegas(("clamped", "pinned"), 1, L / 2)[0]
    assert abs(om[0] / pp - 1) < 1e-6
    assert abs(om[1] / cp - 1) < 2e-6


def test_dense_and_shift_invert_agree(monkeypatch):
    problem = BeamProblem(Beam(L, K2), J=60, ends=("free", "free"), supports=(L / 3,))
    dense = skfem_beam.modes(problem, n=5)
    monkeypatch.setattr(modes_module, "DENSE_MAX", 10)
    arpack = skfem_beam.modes(problem, n=5)
    assert dense.omega[0] < 1e-4 and arpack.omega[0] < 1e-4        # rotation about x = L/3
    assert np.all(np.abs(dense.omega[1:] / arpack.omega[1:] - 1) < 1e-10)
    assert np.abs(np.abs(dense.shapes) - np.abs(arpack.shapes)).max() < 1e-8


@pytest.mark.parametrize("element", ELEMENTS)
def test_mode_shapes_are_mass_normalised_sines_for_a_pinned_beam(element):
    r = skfem_beam.modes(BeamProblem(Beam(L, K2), J=40, element=element,
                                     ends=("pinned", "pinned")), n=3)
    M = r.space.M
    assert np.abs(r.vectors.T @ M @ r.vectors - np.eye(3)).max() < 1e-12
    assert r.x[0] == 0.0 and r.x[-1] == L and np.all(np.diff(r.x) > 0)
    for m in range(3):
        sine = np.sqrt(2 / L) * np.sin((m + 1) * np.pi * r.x / L)    # ∫ sine² = 1, first value > 0
        assert np.abs(r.shapes[:, m] - sine).max() < 1e-5 * np.sqrt(2 / L)
    assert np.allclose(r.f, r.omega / (2 * np.pi), rtol=1e-15)


# --- the spaces with end conditions and supports ---------------------------------------

@pytest.mark.parametrize("element", ELEMENTS)
@pytest.mark.parametrize("ends, u, du", [
    (("pinned", "pinned"), lambda x: x * (L - x) * (x + 1),
     lambda x: -3 * x**2 + 2 * (L - 1) * x + L),
    (("sliding", "free"), lambda x: 1 + x**2 - x**3, lambda x: 2 * x - 3 * x**2),
    (("free", "clamped"), lambda x: (x - L) ** 2 * (2 - x), lambda x: (x - L) * (4 - 3 * x + L)),
])
def test_interpolation_is_exact_for_cubics_meeting_the_end_conditions(ends, u, du, element):
    space = make_space(element, np.linspace(0.0, L, 11), ends)
    c = space.interpolate(u, du)
    assert np.abs(space.interpolate(u) - c).max() < 1e-9    # slopes by five-point differences
    smp = space.sampler(np.linspace(0.0, 1.0, 7))
    assert np.abs(smp.E0 @ c - u(smp.x)).max() < 1e-11
    assert np.abs(space.nodal @ c - u(space.nodes)).max() < 1e-11
    assert np.abs(space.project(u) - c).max() < 1e-10


@pytest.mark.parametrize("element", ELEMENTS)
def test_supports_are_exact_zeros_and_keep_the_band(element):
    nodes = np.linspace(0.0, L, 21)
    sup = tuple(nodes[[1, 2, 3, 9, 19]])          # a run of three, an isolated one, one by x = L
    space = make_space(element, nodes, ("clamped", "pinned"), sup)
    v = np.random.default_rng(0).standard_normal(space.n)
    values = space.nodal @ v
    assert np.all(values[[0, 1, 2, 3, 9, 19, 20]] == 0.0)            # exactly
    assert np.all(values[[4, 5, 10, 18]] != 0.0)
    assert space.n == (2 * 21 - 2 - 1 - 5 if element == "hermite" else 23 - 2 - 1 - 5)
    for A in (space.M, space.S):
        coo = A.tocoo()
        assert np.abs(coo.col - coo.row).max() == 3
    smp = space.sampler(np.linspace(0.0, 1.0, 5))
    at_sup = np.isin(np.round(smp.x / (L / 20), 9), [1, 2, 3, 9, 19])
    assert np.abs(smp.E0[np.flatnonzero(at_sup)] @ v).max() < 1e-14 * np.abs(v).max()


def test_hermite_and_bspline_agree_with_supports():
    kw = dict(ends=("free", "sliding"), supports=(0.3002, 0.4503, 1.2008))
    h, b = (skfem_beam.modes(BeamProblem(Beam(L, K2), J=50, element=e, **kw), n=4)
            for e in ELEMENTS)
    assert np.all(np.abs(h.omega / b.omega - 1) < 1e-6)             # measured ≤ 9e-8
    assert np.abs(h.shapes - b.shapes).max() < 1e-5 * np.abs(h.shapes).max()


def test_default_problem_is_clamped_free_without_supports():
    p = BeamProblem(Beam(L, K2))
    assert p.ends == ("clamped", "free") and p.supports == ()
    s = beam_system(p)
    assert s.C.shape == (0, 2 * 19) and s.space.value_nodes.tolist() == list(range(1, 20))


def test_obstacle_rows_and_tip_observer_follow_the_end_conditions():
    p = BeamProblem(Beam(L, K2), J=10, ends=("free", "pinned"), supports=(0.6004,),
                    obstacles=Obstacles(-0.01, 0.01),
                    initial=InitialState(u0=lambda x: 0.001 * (1 - x / 0.6004)
                                         * np.cos(np.pi * x / (2 * L))))   # 0 where held
    s = beam_system(p)
    # u is free at x_0 (a row there), fixed at the support x_4 and the pinned tip x_10
    assert np.allclose(s.x_contact, np.linspace(0, L, 11)[[0, 1, 2, 3, 5, 6, 7, 8, 9]])
    assert s.C.shape == (9, s.n)
    # the pinned tip does not move: the default series observes the node of largest
    # first-mode amplitude instead (semidiscrete.observed_node)
    shape = np.abs(s.space.nodal @ skfem_beam.modes(p, 1).vectors[:, 0])
    node = int(np.argmax(shape))
    assert node not in (4, 10) and s.view.observed_x == pytest.approx(s.space.nodes[node])
    assert np.array_equal(s.observe["tip_displacement"], s.space.nodal[node].toarray().ravel())
    assert abs(s.C[0] @ s.u0 - 0.001) < 1e-15


def test_free_vibration_of_a_pinned_beam_follows_its_first_mode():
    J = 10
    p = BeamProblem(Beam(L, K2), J=J, ends=("pinned", "pinned"),
                    initial=InitialState(u0=lambda x: 0.01 * np.sin(np.pi * x / L)))
    r = skfem_beam.modes(p, n=1)
    system = beam_system(p)
    period = 2 * np.pi / r.omega[0]
    res = solve(system, dt=period / 400, T=period)
    mid = system.space.nodal[J // 2] @ res.frames_u.T
    expected = (system.space.nodal[J // 2] @ system.u0) * np.cos(r.omega[0] * res.frames_t)
    assert res.status == "success"
    # measured 2.5e-4 relative: the time scheme's O((ωΔt)²) phase error, ωΔt = 2π/400
    assert np.abs(mid - expected).max() < 5e-4 * 0.01


# --- refusals --------------------------------------------------------------------------

@pytest.mark.parametrize("kw, words", [
    (dict(ends=("clamped", "hinged")), ["ends.right='hinged'", "clamped, pinned, sliding, free"]),
    (dict(ends="clamped"), ["ends='clamped'", "pair"]),
    (dict(ends=("free",)), ["ends=('free',)", "pair"]),
    (dict(supports=(2.0,)), ["supports[0] x=2", "must lie on the beam [0, L=1.501]"]),
    (dict(supports=(float("nan"),)), ["supports[0]=nan"]),
    (dict(supports=(0.6004, 0.6004)), ["two supports at x=0.6004"]),
    (dict(supports=(0.0,)), ["supports[0] x=0 is at the clamped end", "already fixed"]),
    (dict(supports=(L,)), ["supports[0] x=1.501 is at the free end", "ends.right='pinned'"]),
    (dict(supports=(0.5,)), ["supports[0] x=0.5: the mesh has no node there", "x=0.4503"]),
    (dict(support=Support(0.01, 30.0), ends=("sliding", "free")),
     ["moving at x=0 is a sliding end", "only clamped or pinned ends"]),
    (dict(support=Support(0.01, 30.0, at=0.3)), ["moving support at=0.3", "supports=()"]),
    (dict(support=Support(0.01, 30.0, lifting="paper"), supports=(0.6004,)),
     ["lifting='paper' needs", "'static'"]),
    (dict(element="bspline", J=2, ends=("clamped", "pinned")), ["needs J ≥ 3"]),
    (dict(J=1, ends=("clamped", "clamped")), ["no degree of freedom"]),
    (dict(supports=(0.6004,), obstacles=Obstacles(0.001, 0.01)), ["exclude u=0 at the support"]),
])
def test_bad_input_is_refused_with_one_clear_line(kw, words):
    kw.setdefault("J", 10)
    with pytest.raises(InputError) as err:
        BeamProblem(Beam(L, K2), **kw)
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_modes_refuses_a_bad_count():
    p = BeamProblem(Beam(L, K2), J=3)
    for n in (0, 7, 2.0, True):
        with pytest.raises(InputError, match=r"n=.* modes: must be a whole number in \[1, 6\]"):
            skfem_beam.modes(p, n=n)
