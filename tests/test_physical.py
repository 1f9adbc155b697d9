"""Physical inputs: Material, Section, Beam.physical and stepped beams (issue "The
engineer's own beam and bar", beam part)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import skfem_beam
from skfem_beam import (Beam, BeamProblem, InitialState, InputError, Material, Obstacles,
                        Section, beam_system, scenes, solve)
from skfem_beam.spaces import make_space

STEEL = Material(2e11, 8000.0)
ALU = Material(7e10, 2700.0)
PIPE = Section.tube(0.01, 0.0005)


def test_sections_are_the_textbook_ones():
    D, d = 0.01, 0.009
    assert PIPE.I == pytest.approx(math.pi * (D**4 - d**4) / 64, rel=1e-15)
    assert PIPE.A == pytest.approx(math.pi * (D**2 - d**2) / 4, rel=1e-15)
    r = Section.rect(0.02, 0.005)
    assert (r.I, r.A) == (pytest.approx(0.02 * 0.005**3 / 12, rel=1e-15), 0.02 * 0.005)
    assert Section.rod(0.01).I == pytest.approx(math.pi * 1e-8 / 64, rel=1e-15)


def test_the_papers_pipe_from_its_material_and_section():
    # the first paper's k² = 282.84 m⁴/s² is EI/(ρA) of this pipe, rounded
    b = Beam.physical(1.501, STEEL, PIPE)
    assert b.k2 == pytest.approx(282.84, rel=1e-4)
    assert b.rho_S == pytest.approx(scenes.PIPE_RHO_S, rel=1e-15)
    assert b.EI == pytest.approx(2e11 * PIPE.I, rel=1e-15)


def test_physical_and_k2_forms_give_identical_runs():
    b = Beam.physical(1.501, STEEL, PIPE)
    p1 = scenes.point_stops(k2=b.k2, rho_S=b.rho_S)
    import dataclasses
    p2 = dataclasses.replace(p1, beam=b)
    s1, s2 = beam_system(p1), beam_system(p2)
    for name in ("M", "K"):
        assert (getattr(s1, name) != getattr(s2, name)).nnz == 0
    r1, r2 = (solve(s, dt=1e-4, T=0.05) for s in (s1, s2))
    np.testing.assert_array_equal(r1.observed["tip_displacement"],
                                  r2.observed["tip_displacement"])
    assert s2.view.rho_S == b.rho_S and s2.view.EI == b.EI and s2.view.k2 == b.k2


# --- stepped beams: element matrices against closed forms -----------------------------

def hermite_closed_forms(h):
    M = h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h**2, 13 * h, -3 * h**2],
                            [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h**2, -22 * h, 4 * h**2]])
    S = 1 / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h**2, -6 * h, 2 * h**2],
                             [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h**2, -6 * h, 4 * h**2]])
    return M, S, [lambda e: 2 * e + np.arange(4)]


def bspline_closed_forms(h):
    M = h / 5040 * np.array([[20, 129, 60, 1], [129, 1188, 933, 60],
                             [60, 933, 1188, 129], [1, 60, 129, 20]])
    # B'' on an element: (1−ξ, 3ξ−2, 1−3ξ, ξ)/h², products integrated by hand
    S = 1 / h**3 * np.array([[1 / 3, -1 / 2, 0, 1 / 6], [-1 / 2, 1, -1 / 2, 0],
                             [0, -1 / 2, 1, -1 / 2], [1 / 6, 0, -1 / 2, 1 / 3]])
    return M, S, [lambda e: e + np.arange(4)]


@pytest.mark.parametrize("element, forms", [("hermite", hermite_closed_forms),
                                            ("bspline", bspline_closed_forms)])
def test_weighted_element_matrices_are_the_closed_forms(element, forms):
    L, J = 1.2, 3
    x = np.linspace(0, L, J + 1)
    wm, wk = np.array([1.0, 2.5, 0.3]), np.array([1.0, 7.0, 0.05])
    space = make_space(element, x, ("free", "free"), (), (wm, wk))
    Mf, Sf = (A.toarray() for A in space.full_matrices())
    Me, Se, (dofs,) = forms(L / J)
    want_M, want_S = np.zeros_like(Mf), np.zeros_like(Sf)
    for e in range(J):
        d = dofs(e)
        want_M[np.ix_(d, d)] += wm[e] * Me
        want_S[np.ix_(d, d)] += wk[e] * Se
    np.testing.assert_allclose(Mf, want_M, rtol=0, atol=1e-14 * np.abs(want_M).max())
    np.testing.assert_allclose(Sf, want_S, rtol=0, atol=1e-12 * np.abs(want_S).max())


# --- stepped cantilever: first frequency against the transfer-matrix equation --------

PARTS = [(0.6, STEEL, PIPE), (0.9, ALU, Section.rod(0.012))]


def transfer(EI, rhoA, length, omega):
    """State (w, w', EI w'', EI w''') at the segment's end from its start."""
    b = (omega**2 * rhoA / EI) ** 0.25

    def phi(x):   # rows: w, w', EI w'', EI w''' of (cosh, sinh, cos, sin)(b x)
        c, s, C, S = np.cosh(b * x), np.sinh(b * x), np.cos(b * x), np.sin(b * x)
        return np.array([[c, s, C, S], [b * s, b * c, -b * S, b * C],
                         [EI * b**2 * c, EI * b**2 * s, -EI * b**2 * C, -EI * b**2 * S],
                         [EI * b**3 * s, EI * b**3 * c, EI * b**3 * S, -EI * b**3 * C]])
    return phi(length) @ np.linalg.inv(phi(0.0))


def stepped_cantilever_omega1():
    segs = [(ln, m.E * s.I, m.rho * s.A) for ln, m, s in PARTS]

    def det(omega):
        T = np.eye(4)
        for ln, EI, rhoA in segs:
            T = transfer(EI, rhoA, ln, omega) @ T
        # clamped at 0: state (0, 0, M0, V0); free at L: moment and shear vanish
        return np.linalg.det(T[2:, 2:])
    grid = np.linspace(1.0, 400.0, 4000)
    v = [det(w) for w in grid]
    i = next(i for i in range(len(v) - 1) if v[i] * v[i + 1] < 0)
    return brentq(det, grid[i], grid[i + 1], xtol=1e-13, rtol=1e-15)


def test_stepped_cantilever_first_frequency():
    exact = stepped_cantilever_omega1()
    beam = Beam.stepped(PARTS)
    assert beam.steps == (0.6,) and beam.L == pytest.approx(1.5)

    def error(J, element):
        w = skfem_beam.modes(BeamProblem(beam, J=J, element=element), n=1).omega[0]
        return abs(w / exact - 1)
    # Hermite (C¹) holds the jump of u'' where EI jumps: 1.7e-9 at J = 40, fourth order
    assert error(40, "hermite") < 3e-9
    assert error(20, "hermite") / error(40, "hermite") > 15
    # C² cubic splines cannot jump in u'': first order, 6.2e-4 at J = 40 (docs/design.md §6)
    e40, e80 = error(40, "bspline"), error(80, "bspline")
    assert e40 < 7e-4 and 1.9 < e40 / e80 < 2.1
    # a uniform stepped beam is the plain one
    uni = Beam.stepped([(0.6, STEEL, PIPE), (0.9, STEEL, PIPE)])
    assert uni.segments == () and uni == Beam.physical(1.5, STEEL, PIPE)


def test_stepped_beam_needs_a_node_at_the_step():
    with pytest.raises(InputError, match=r"no node at the beam's step x=0\.6"):
        BeamProblem(Beam.stepped(PARTS), J=7)


@pytest.mark.parametrize("make, words", [
    (lambda: Material(-2e11, 8000), ["E=-2e+11", "> 0"]),
    (lambda: Material(2e11, 0), ["rho=0", "> 0"]),
    (lambda: Section.tube(0.01, 0.005), ["wall=0.005", "outer radius 0.005"]),
    (lambda: Section.rect(0.02, float("nan")), ["h=nan"]),
    (lambda: Beam.stepped([]), ["at least one"]),
    (lambda: Beam.stepped([(0.5, STEEL)]), ["part 0", "(length, Material, Section)"]),
    (lambda: Beam.stepped([(-0.5, STEEL, PIPE)]), ["length of part 0=-0.5"]),
    # the kinds of a problem's parts (before: AttributeError or TypeError from inside)
    (lambda: BeamProblem(Beam(1.5, k2=282.84), (-0.1, 0.1), J=10),
     ["BeamProblem obstacles= is a tuple: it takes Obstacles(g1=-0.01, g2=0.01)"]),
    (lambda: Obstacles(g1="a", g2=0.1), ["g1='a' must be a number (m; ±inf: no bound)"]),
    # a NaN or complex bound ran as if there were none (NaN) or cast to its real part
    (lambda: Obstacles(g1=float("nan")), ["g1=nan must be a number"]),
    (lambda: Obstacles.stops([0.5, 1.0], [-0.1, np.nan], 0.1), ["g1=nan must be a number"]),
    (lambda: Obstacles(g2=np.complex128(0.1)), ["g2=(0.1+0j) must be a number"]),
    (lambda: Obstacles.stops([1.5], np.complex128(-0.1 + 1j), 0.1), ["g1=(-0.1+1j) must be"]),
    (lambda: Obstacles.span(0.0, 1.0, -0.1 + 1j, 0.1), ["g1=(-0.1+1j) must be a number"]),
    (lambda: InitialState(v0=np.zeros(5)), ["InitialState v0=", "must be a function of x"]),
    (lambda: skfem_beam.modes(beam_system(BeamProblem(Beam(1.5, k2=282.84), J=4)), 2),
     ["modes needs the BeamProblem (not SemiDiscrete"]),
    (lambda: skfem_beam.solve(BeamProblem(Beam(1.5, k2=282.84), J=4), 1e-4, 0.1),
     ["solve needs a semi-discrete system (beam_system(problem)", "not BeamProblem"]),
    # a stop where an end holds the beam never acts: it ran silently, 0 impacts
    (lambda: BeamProblem(Beam(1.5, k2=282.84), Obstacles.stops([1.5], -0.1, 0.1),
                         ends=("clamped", "pinned"), J=10),
     ["obstacle 0 bounds u only at x=1.5, where an end holds the beam"]),
])
def test_bad_physical_input_is_refused_with_one_clear_line(make, words):
    with pytest.raises(InputError) as err:
        make()
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_a_span_acts_at_its_end_nodes_a_rounding_away():
    """The nodes at a span's ends lie a rounding off them (linspace: 0.6003999999999999 for
    0.6004); the mesh check takes them as its nodes, so the span acts there: the first one
    was left free."""
    x = np.linspace(0.0, 1.501, 11)
    lo, hi = Obstacles.span(0.6004, 1.2008, -0.2, 0.1).bounds(x)
    assert x[4] < 0.6004 and x[8] < 1.2008
    assert list(np.flatnonzero(np.isfinite(lo))) == [4, 5, 6, 7, 8]
    assert list(np.flatnonzero(np.isfinite(hi))) == [4, 5, 6, 7, 8]
