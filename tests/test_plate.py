"""Kirchhoff–Love plates (skfem_beam.plate) against exact solutions: the static
deflection of a simply supported square under a sine load, the frequencies of a simply
supported rectangle (Navier), of a square simply supported on two edges and free on
two (Lévy), of a clamped square (Leissa), and the refusal of bad input.  The numbers
asserted are the ones docs/plate.md reports, each bound a little above what was measured."""
from functools import cache

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import rate
from skfem_beam.errors import InputError
from skfem_beam.plate import Plate, deflection_at_vertex, natural_frequencies, plate_space
from skfem_beam.plate.convergence import centre_deflection_error, frequency_parameters
from skfem_beam.plate.space import is_fixed

ALL_EDGES = ("left", "right", "bottom", "top")


@pytest.mark.parametrize("element, ns, error_bound, min_rate", [
    ("bfs", (4, 8, 16), 4e-6, 3.8),        # measured 7.7e-4, 4.9e-5, 3.1e-6: rate 3.96, 3.99
    ("morley", (8, 16, 32), 6e-3, 1.9),    # measured 8.4e-2, 2.1e-2, 5.3e-3: rate 1.99, 2.00
    ("argyris", (2, 4, 8), 2e-7, 4.5),     # measured 3.2e-4, 1.0e-5, 1.3e-7: rate 4.99, 6.26
])
def test_static_centre_deflection_converges(element, ns, error_bound, min_rate):
    errors = [centre_deflection_error(element, n) for n in ns]
    assert errors[-1] < error_bound, errors
    pair_rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert min(pair_rates) > min_rate, (errors, pair_rates)


A, B = 1.0, 0.6
# Navier: ω_mn = π²(m²/a² + n²/b²) √(D/(ρh)); the six lowest of the 1 × 0.6 rectangle
NAVIER = sorted((np.pi ** 2 * (m * m / A ** 2 + n * n / B ** 2), (m, n))
                for m in range(1, 8) for n in range(1, 8))[:6]


@cache
def navier_errors(n: int) -> np.ndarray:
    """Relative errors of the six lowest frequencies, BFS on n × n rectangles."""
    computed = frequency_parameters(Plate(a=A, b=B, nx=n, ny=n), 6)
    return computed / np.array([exact for exact, _ in NAVIER]) - 1.0


def test_navier_modes_in_order():
    assert [mn for _, mn in NAVIER] == [(1, 1), (2, 1), (3, 1), (1, 2), (2, 2), (4, 1)]


def test_simply_supported_rectangle_frequencies_at_20_by_20():
    errors = navier_errors(20)
    assert np.all(errors > 0), errors              # a conforming element: from above
    assert np.max(errors) < 1e-4, errors           # measured 7.8e-5, mode (4,1)
    assert np.argmax(errors) == 5


def test_simply_supported_rectangle_frequencies_converge_at_rate_4():
    errors = np.array([navier_errors(n) for n in (5, 10, 20)])      # (mesh, mode)
    pair_rates = np.log2(errors[:-1] / errors[1:])
    # measured from 3.83 (mode (4,1), 5 → 10) to 4.00
    assert pair_rates.min() > 3.75, pair_rates
    slopes = [rate(errors[:, k], [1 / 5, 1 / 10, 1 / 20]) for k in range(6)]
    assert min(slopes) > 3.85, slopes

def test_mode_shapes_at_the_vertices_are_the_navier_sines():
    """w_dofs and vertices pair each vertex with its deflection: on this uniform grid the
    discrete modes (1,1) and (2,1) sample sin(mπx/a) sin(πy/b) at the vertices exactly
    (the grid's sine symmetry), measured to 1.4e-11 and 2.7e-11 of their peak."""
    space = plate_space(Plate(a=A, b=B, nx=10, ny=10))
    _, shapes = natural_frequencies(space, 2)
    x, y = space.vertices
    for k, m in ((0, 1), (1, 2)):
        w = shapes[space.w_dofs, k]
        exact = np.sin(m * np.pi * x / A) * np.sin(np.pi * y / B)
        exact *= (w @ exact) / (exact @ exact)
        assert np.max(np.abs(w - exact)) < 1e-9 * np.max(np.abs(exact)), (k, m)


LEISSA_CLAMPED_SQUARE = 35.985      # ω a² √(ρh/D), all four edges clamped, ν = 0.3


@pytest.mark.parametrize("element, n, bound", [
    ("bfs", 12, 5e-5),          # measured 3.9e-5 (10 × 10: 7.3e-5; 20 × 20: 1.0e-5)
    ("argyris", 8, 2e-5),       # measured 8.5e-6 (the clamped u_n dofs at mid-edges)
])
def test_clamped_square_first_frequency(element, n, bound):
    plate = Plate(edges=dict.fromkeys(ALL_EDGES, "clamped"), element=element, nx=n, ny=n)
    parameter = frequency_parameters(plate, 1)[0] * plate.a ** 2
    assert abs(parameter / LEISSA_CLAMPED_SQUARE - 1.0) < bound, parameter


def levy_sfsf_parameter(nu: float, a: float, b: float) -> float:
    """The lowest ω √(ρh/D) of a plate simply supported at x = 0, a and free at y = 0, b
    (Lévy): w = sin(αx) Y(y), α = π/a, with ω √(ρh/D) = k² below α² (the free edges
    soften the plate below the strip's π²/a²), so Y = A cosh(py) + B cosh(ry) about
    mid-width, p² = α² + k², r² = α² − k²; at y = b/2 the free edge has M_y = 0
    (Y'' − να²Y = 0) and V_y = 0 (Y''' − (2 − ν)α²Y' = 0)."""
    alpha, c = np.pi / a, b / 2

    def determinant(k2):    # of the 2 × 2 system in (A, B), ÷ cosh(pc) cosh(rc)
        p, r = np.sqrt(alpha ** 2 + k2), np.sqrt(alpha ** 2 - k2)
        return ((p * p - nu * alpha ** 2) * r * (r * r - (2 - nu) * alpha ** 2) * np.tanh(r * c)
                - (r * r - nu * alpha ** 2) * p * (p * p - (2 - nu) * alpha ** 2)
                * np.tanh(p * c))

    return brentq(determinant, 0.5 * alpha ** 2, alpha ** 2 * (1 - 1e-12), xtol=1e-14)


def test_two_edges_free_square_first_frequency():
    """Free edges add no dof constraint; their natural conditions come from the energy."""
    plate = Plate(edges={"left": "simply_supported", "right": "simply_supported"}, nx=8, ny=8)
    exact = levy_sfsf_parameter(plate.nu, plate.a, plate.b)
    assert abs(exact - 9.631) < 5e-4                              # Leissa's table: 9.631
    error = frequency_parameters(plate, 1)[0] / exact - 1.0
    assert 0 < error < 3e-5, error                                # measured 1.9e-5


@pytest.mark.parametrize("dofname, support, normal_axis, fixed", [
    ("u", "simply_supported", 0, True), ("u_y", "simply_supported", 0, True),
    ("u_x", "simply_supported", 0, False), ("u_xy", "simply_supported", 0, False),
    ("u_xy", "clamped", 0, True), ("u_xx", "clamped", 0, False),
    ("u_yy", "simply_supported", 0, True), ("u_n", "clamped", 1, True),
    ("u_n", "simply_supported", 1, False), ("u", "free", 1, False),
])
def test_support_fixes_the_tangential_derivatives(dofname, support, normal_axis, fixed):
    assert is_fixed(dofname, support, normal_axis) is fixed


@pytest.mark.parametrize("kwargs, named", [
    ({"nu": 0.5}, "nu=0.5"),
    ({"nu": -1.2}, "nu=-1.2"),
    ({"h": 0.0}, "h=0 must be > 0"),
    ({"a": -1.0}, "a=-1 must be > 0"),
    ({"edges": {"front": "clamped"}}, "'front'"),
    ({"edges": {"left": "glued"}}, "'glued'"),
    ({"element": "dkt"}, "'dkt'"),
    ({"nx": 0}, "nx=0"),
])
def test_bad_input_is_refused_by_name(kwargs, named):
    with pytest.raises(InputError, match="plate") as refused:
        Plate(**kwargs)
    message = str(refused.value)
    assert named in message and "\n" not in message, message


def test_refusals_say_what_is_allowed():
    for kwargs, allowed in [({"nu": 0.7}, "(-1, 0.5)"), ({"h": -1e-3}, "> 0"),
                            ({"edges": {"front": "free"}}, "left, right, bottom, top"),
                            ({"edges": {"top": "glued"}}, "clamped, simply_supported, free"),
                            ({"element": "dkt"}, "bfs, morley, argyris")]:
        with pytest.raises(InputError) as refused:
            Plate(**kwargs)
        assert allowed in str(refused.value), refused.value


def test_what_the_python_api_would_drop_is_refused():
    """An amplitude without its mode (the plate started flat), a point force at a vertex
    its edges hold (it went into the support): one line each, not a run that ignores
    them."""
    from skfem_beam.plate.system import PlateInitial, PointForce
    with pytest.raises(InputError, match="amplitude=0.001 is a mode shape's"):
        PlateInitial(amplitude=1e-3)
    space = plate_space(Plate(nx=2, ny=2, edges={"left": "simply_supported"}))
    with pytest.raises(InputError, match=r"\(0, 0.5\) is a vertex the edges hold"):
        PointForce(0.0, 0.5, 10.0).vector(space)
    assert PointForce(1.0, 0.5, 10.0).vector(space).sum() == 10.0     # the free edge


def test_a_point_off_the_mesh_vertices_is_refused():
    space = plate_space(Plate(nx=2, ny=2))
    with pytest.raises(InputError, match=r"\(0.3, 0.5\)"):
        deflection_at_vertex(space, np.zeros(space.basis.N), 0.3, 0.5)


@pytest.mark.parametrize("name", ["bfs", "morley", "argyris"])
def test_the_elements_are_skfems_to_the_bit(name):
    """plate.space.MonomialsOnce evaluates the power basis once per point set: the basis
    (values, gradients, Hessians) and the matrices equal skfem's own element's bit for bit,
    on the plate's quadrature and on another point set (the moments' vertices)."""
    from skfem import Basis, ElementQuadBFS, ElementTriArgyris, ElementTriMorley
    from skfem_beam.plate.space import make_element, plate_mesh, stiffness_matrix
    plate = Plate(a=1.3, b=0.7, nx=3, ny=2, element=name)
    mesh = plate_mesh(plate)
    skfem_element = {"bfs": ElementQuadBFS, "morley": ElementTriMorley,
                     "argyris": ElementTriArgyris}[name]
    points = np.array([[0.0, 1.0, 0.0, 0.3], [0.0, 0.0, 1.0, 0.3]])
    for quadrature in ({}, {"quadrature": (points, np.ones(4))}):
        ours = Basis(mesh, make_element(name), **quadrature)
        theirs = Basis(mesh, skfem_element(), **quadrature)
        for a, b in zip(ours.basis, theirs.basis):
            (a,), (b,) = a, b       # a DiscreteField: the values, with .grad and .hess
            for x, y in ((a, b), (a.grad, b.grad), (a.hess, b.hess)):
                assert np.array_equal(np.asarray(x), np.asarray(y)) and np.ndim(x) >= 2
    K1, K2 = stiffness_matrix(ours, 1.0, 0.3), stiffness_matrix(theirs, 1.0, 0.3)
    assert (K1 != K2).nnz == 0 and K1.nnz > 0


@pytest.mark.parametrize("element", ["bfs", "morley", "argyris"])
@pytest.mark.parametrize("edges, motions", [
    ({}, 3),                                                    # free: w = a + bx + cy
    ({e: "sliding" for e in ALL_EDGES}, 1),                     # w = a
    ({"left": "sliding", "right": "sliding"}, 2),               # w = a + cy
    ({"left": "simply_supported"}, 1),                          # w = bx, about the edge
    ({"left": "simply_supported", "bottom": "simply_supported"}, 0),
    ({"left": "clamped"}, 0),
])
def test_rigid_motions_the_supports_leave(element, edges, motions):
    """What a static deflection must refuse: K w = f has no solution while the supports
    leave the plate a rigid motion (a free plate's static start gave w = −1.9e11 m)."""
    from skfem_beam.plate.static import rigid_motions, static_deflection
    from skfem_beam.plate.space import load_vector
    space = plate_space(Plate(a=0.4, b=1.2, nx=3, ny=5, element=element, edges=edges))
    assert rigid_motions(space) == motions
    f = load_vector(space, lambda x, y: np.full_like(x, 100.0))
    if motions:
        with pytest.raises(InputError, match="needs edges that hold the plate"):
            static_deflection(space, f)
    else:
        assert np.isfinite(static_deflection(space, f)).all()


def test_a_zero_static_load_is_the_flat_start_whatever_the_supports():
    """static_pressure = 0 on a free plate is the flat start the refusal points to."""
    from skfem_beam.plate.static import static_deflection
    space = plate_space(Plate(nx=3, ny=3, edges={}))
    assert not static_deflection(space, np.zeros(space.basis.N)).any()
