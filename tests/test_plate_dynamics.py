"""The plate's dynamics through the one time scheme (skfem_beam/plate/system.py): exact
contact at the vertices, the scheme's energy identity, the same beam reproduced by a
strip in cylindrical bending, the band of the grid ordering, and the input checks."""
import numpy as np
import pytest

from skfem_beam import Beam, BeamProblem, InitialState, InputError, Load, Obstacles, beam_system
from skfem_beam.methods import make
from skfem_beam.plate import Plate, deflection_at_vertex, plate_space
from skfem_beam.plate.space import is_fixed, load_vector
from skfem_beam.plate.system import (PlateInitial, PlateObstacle, Pressure, full_dofs,
                                     half_bandwidth, plate_system)
from skfem_beam.scheme import solve


def closure(r):
    """energy − energy[0] + damping work − input work − contact work (0 by the identity)."""
    w = r.work
    return r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]


@pytest.fixture(scope="module")
def impact():
    """After GetFEM's plate_Impact: a simply supported 1 × 1 m steel plate (h = 1 cm,
    8 × 8 BFS) deflected upwards by 10 kPa, released at rest, swings down onto a flat
    obstacle under the whole plate at half its static centre deflection."""
    space = plate_space(Plate(nx=8, ny=8))
    start = PlateInitial(static=Pressure(1e4))
    free = plate_system(space, initial=start)
    w_max = float(free.observe["w(0.5,0.5)"] @ free.u0)           # 2.11 mm
    system = plate_system(space, obstacles=[PlateObstacle(g1=-0.5 * w_max)], initial=start)
    return system, w_max


def test_plate_hits_a_flat_obstacle_at_several_vertices_without_penetration(impact):
    system, w_max = impact
    r = solve(system, 1e-4, 0.04)                  # the first period is 20 ms
    assert r.success and r.solver == "active-set"
    assert r.impacts > 0
    assert (r.contact_force > 0).sum(axis=1).max() >= 5            # 9 vertices at once
    y = r.frames_u @ system.C.T                                    # w at the vertices
    assert (y - system.lo).min() >= -1e-12 * w_max                 # measured 0
    assert r.max_nodal_violation <= 1e-12 * w_max                  # measured 2e-19 m
    assert r.observed["w(0.5,0.5)"].min() == pytest.approx(-0.5 * w_max, rel=1e-12)
    scale = np.abs(r.energy).max()
    assert np.abs(closure(r)).max() <= 1e-9 * scale                # measured 1.8e-14
    assert r.work["contact"][-1] < -0.01 * r.energy[0]             # impacts lose energy


@pytest.mark.parametrize("method", [make(law="penalty", stiffness=1e9),
                                    make(law="moreau-jean")])
def test_penalty_and_moreau_jean_run_the_plate_with_the_identity_closed(impact, method):
    system, w_max = impact
    r = solve(system, 1e-4, 0.04, method=method)
    assert r.success and r.impacts > 0
    assert np.abs(closure(r)).max() <= 1e-9 * np.abs(r.energy).max()   # measured 2e-14
    assert 0 < r.max_nodal_violation < 0.1 * w_max          # 1.8e-5, 4.2e-5 m: not exact


A, B, H, E, RHO, J = 1.0, 0.1, 0.01, 210e9, 7850.0, 10
GAP, V0, P = 2e-3, -0.3, -500.0


def strip_and_beam(long_sides: str):
    """A strip A × B, ν = 0, clamped at x = 0, free at x = A, its long sides
    ``long_sides``, J × 1 BFS, a stop w ≥ −GAP at both vertices of x = A; and the beam
    of the same EI = D·B, ρA = ρh·B, J Hermite elements, a point stop at its tip.  Both
    start flat at v0 = V0 under the pressure P (the beam's load: P/(ρh) per unit mass)."""
    edges = {"left": "clamped"}
    if long_sides != "free":
        edges.update(bottom=long_sides, top=long_sides)
    plate = Plate(a=A, b=B, h=H, E=E, rho=RHO, nu=0.0, edges=edges, nx=J, ny=1)
    strip = plate_system(plate_space(plate), obstacles=[PlateObstacle(g1=-GAP,
                                                                      region=(A, A, 0, B))],
                         loads=[Pressure(P)], initial=PlateInitial(v0=V0),
                         observe=[(A, 0.0), (A, B)])
    rho_A = RHO * H * B
    problem = BeamProblem(Beam(A, plate.D * B / rho_A, rho_A),
                          obstacles=Obstacles.point_stops(A, -GAP, np.inf),
                          load=Load.uniform(lambda t: np.full(np.shape(t), P / (RHO * H))),
                          initial=InitialState(v0=lambda x: np.full(np.shape(x), V0)), J=J)
    return strip, beam_system(problem), rho_A


def tip_difference(long_sides: str):
    """The strip's and the beam's tip deflection over 80 ms (about four periods, 32
    impacts of the beam's tip), |w − u| / GAP before the beam's first and second
    impacts and over the run; and the two runs."""
    strip, beam, rho_A = strip_and_beam(long_sides)
    rp, rb = solve(strip, 2e-5, 0.08), solve(beam, 2e-5, 0.08)
    d = np.abs(rp.observed["w(1,0)"] - rb.observed["tip_displacement"]) / GAP
    starts = rb.impact_events["t_start"]
    return d[rb.t < starts[0]].max(), d[rb.t < starts[1]].max(), d.max(), rp, rb, rho_A


def test_a_strip_with_sliding_long_sides_is_the_beam_against_a_tip_stop():
    """Sliding long sides (∂w/∂y = 0) keep the strip cylindrical through the impacts:
    by symmetry the two corner stops push equally, and the only symmetric function of y
    left in the space is the constant.  The strip is then the beam (in N, J: × ρA)."""
    first, second, whole, rp, rb, rho_A = tip_difference("sliding")
    assert rb.impacts >= 2
    assert second <= 1e-10                                         # measured 1.9e-13
    assert whole <= 1e-9                                           # 2.8e-11 over 32 impacts
    assert rp.energy[-1] == pytest.approx(rho_A * rb.energy[-1], rel=1e-9)
    np.testing.assert_allclose(rp.contact_force.sum(axis=1), rho_A * rb.contact_force[:, 0],
                               rtol=0, atol=1e-8 * rho_A * np.abs(rb.contact_force).max())


def test_a_strip_with_free_long_sides_leaves_the_beam_at_its_first_impact():
    """Free long sides: the same until the first impact (the motion is w(x)·1 while no
    stop pushes), then the point forces at the two corners excite the slope dofs u_y,
    u_xy of the free edges, which a uniform line force along x = A would not (∫φ dy ≠ 0
    for the edges' slope functions, φ = 0 at both vertices): 0.7 % of the gap by the
    second impact.  The discrete model's, not the scheme's: the vertex stops are not the
    consistent line load."""
    first, second, _, rp, _, _ = tip_difference("free")
    assert first <= 1e-10                                          # measured 1.7e-13
    assert 1e-3 < second < 3e-2                                    # measured 7.2e-3
    assert np.abs(closure(rp)).max() <= 1e-9 * np.abs(rp.energy).max()


def test_grid_order_gives_the_banded_factor_a_narrow_band_and_maps_back():
    space = plate_space(Plate(nx=20, ny=20))
    system = plate_system(space, loads=[Pressure(1e3)], observe=[(0.5, 0.5), (0.25, 0.75)])
    assert half_bandwidth(system.K + system.M) == 87               # 4 (n + 2) − 1
    assert half_bandwidth(space.K[space.free_dofs][:, space.free_dofs]) == 87
    u = np.linspace(-1.0, 1.0, system.n)
    full = full_dofs(system, u)
    for (x, y), row in zip([(0.5, 0.5), (0.25, 0.75)], system.observe.values()):
        assert deflection_at_vertex(space, full, x, y) == row @ u


def test_a_regional_pressure_and_point_stops():
    space = plate_space(Plate(a=2.0, b=1.0, nx=8, ny=4, edges={"left": "clamped"}))
    b = Pressure(3.0, region=(1.0, 2.0, 0.0, 0.5)).vector(space)
    assert b[space.w_dofs].sum() == pytest.approx(3.0 * 1.0 * 0.5, rel=1e-12)  # Σ w-shapes = 1
    stops = PlateObstacle(g1=-1e-3, g2=lambda x, y: 1e-3 + 0 * x,
                          points=((2.0, 0.0), (2.0, 1.0), (1.0, 0.5)))
    system = plate_system(space, obstacles=[stops, PlateObstacle(g1=-2e-3, region=(2, 2, 0, 1))])
    assert system.C.shape[0] == 6                                  # 5 vertices at x = 2, 1 inside
    assert sorted(zip(system.x_contact, system.meta["y_contact"], system.lo, system.hi))[0] \
        == (1.0, 0.5, -1e-3, 1e-3)
    edge = system.x_contact == 2.0
    along = np.argsort(system.meta["y_contact"][edge])
    assert system.lo[edge][along].tolist() == [-1e-3, -2e-3, -2e-3, -2e-3, -1e-3]
    assert system.hi[edge][along].tolist() == [1e-3, np.inf, np.inf, np.inf, 1e-3]


@pytest.mark.parametrize("kwargs, message", [
    ({"obstacles": [PlateObstacle(g1=1e-3, region=(0, 0, 0, 1))]},
     r"held at w = 0 by its support, outside \[0.001, inf\] \(g1 of obstacles\[0\]\)"),
    # only at held vertices: it ran with solver "none" and no contact (a beam's is refused)
    ({"obstacles": [PlateObstacle(g1=-1e-3, region=(0, 0, 0, 1))]},
     r"obstacles\[0\] acts only at vertices its plate's supports hold at w = 0"),
    ({"obstacles": [PlateObstacle(g1=-1e-3, points=((0.0, 0.5),))]}, "it would never act"),
    ({"obstacles": [PlateObstacle(points=((0.3, 0.3),), g1=0.0)]}, "not a vertex"),
    ({"obstacles": [PlateObstacle(g1=1e-3, g2=0.0)]}, "need g1 < g2"),
    # two obstacles that cross: the line names which one gave each bound
    ({"obstacles": [PlateObstacle(g1=-1e-3, g2=1e-3),
                    PlateObstacle(g1=2e-3, region=(0.5, 1, 0, 1))]},
     r"g1=0.002 of obstacles\[1\], g2=0.001 of obstacles\[0\]\)"),
    ({"obstacles": [PlateObstacle(g1=1e-6, region=(0.5, 1, 0, 1))],
      "initial": PlateInitial(static=Pressure(-1e3))},
     "violates the obstacles"),
])
def test_refusals(kwargs, message):
    with pytest.raises(InputError, match=message):
        plate_system(plate_space(Plate(nx=4, ny=4, edges={"left": "clamped"})), **kwargs)


ORDER = r"\(x0, x1, y0, y1\) in m \(a scene file writes \[x0, y0, x1, y1\]\)"


@pytest.mark.parametrize("kwargs, message", [
    # a scene file's corner order given to Python: one point, refused (it held one vertex)
    ({"obstacles": [PlateObstacle(g1=-1e-3, region=(0.25, 0.25, 0.75, 0.75))]},
     r"region=\(0.25, 0.25, 0.75, 0.75\) needs x0 ≤ x1 and y0 ≤ y1, not one point: " + ORDER),
    ({"obstacles": [PlateObstacle(g1=-1e-3, region=(0.8, 0.9, 0.7, 0.2))]}, "needs x0 ≤ x1"),
    ({"obstacles": [PlateObstacle(g1=-1e-3, region=(0.5, 2.0, 0.0, 1.0))]}, "is off"),
    ({"obstacles": [PlateObstacle(g1=-1e-3, region=(0.51, 0.52, 0.51, 0.52))]},
     "holds no vertex"),
    ({"loads": [Pressure(1e4, region=(0.5, 0.5, 0.0, 1.0))]},
     "Pressure region=.* needs x0 < x1 and y0 < y1"),
    ({"obstacles": PlateObstacle(g1=-1e-3)}, "obstacles= must be a list of PlateObstacle"),
    ({"loads": [1e4]}, "loads= must be a list of Pressure"),
    ({"initial": Pressure(1e4)}, "initial=.* must be a PlateInitial or None"),
])
def test_python_inputs_are_refused_in_one_line(kwargs, message):
    """Each mistake of a Python user refused by name (before: silently no load or one
    vertex, or an AttributeError from inside)."""
    with pytest.raises(InputError, match=message):
        plate_system(plate_space(Plate(nx=4, ny=4)), **kwargs)


@pytest.mark.parametrize("make_it, message", [
    (lambda: Plate(E=0), "plate E=0 must be > 0"),
    (lambda: Plate(rho=-1), "plate rho=-1 must be > 0"),
    (lambda: Plate(E=float("nan")), "plate E=nan must be a finite number"),
    (lambda: Plate(h=[0.01]), r"plate thickness h=\[0.01\] is not a number"),
    (lambda: Plate(edges=["left"]), "plate edges=.* must map edges to supports"),
    (lambda: Pressure(float("nan")), r"Pressure p=nan must be a finite number \(Pa\)"),
    (lambda: PlateInitial(static=1e4), "must be a Pressure"),
    (lambda: PlateInitial(v0=np.zeros(3)), "PlateInitial v0=.* must be a finite number"),
])
def test_plate_parts_check_their_values(make_it, message):
    with pytest.raises(InputError, match=message):
        make_it()


def test_modes_and_statics_check_their_arguments():
    from skfem_beam.plate import natural_frequencies, static_deflection
    from skfem_beam.plate.space import load_vector
    space = plate_space(Plate(nx=4, ny=4))
    for n in (0, 65, "6", True):     # 64 free dofs, the dense solve: all 64 modes
        with pytest.raises(InputError, match=r"must be a whole number in \[1, 64\]"):
            natural_frequencies(space, n)
    assert natural_frequencies(space, 64)[0].size == 64
    with pytest.raises(InputError, match=r"f has shape \(5,\): a load vector over all 100"):
        static_deflection(space, np.ones(5))
    # a number is a uniform pressure: 1 kPa on 1 m² is 1 kN in all
    assert load_vector(space, 1e3).sum() == pytest.approx(1e3, rel=1e-12)


@pytest.mark.parametrize("dofname, normal_axis, fixed", [
    ("u", 1, False), ("u_y", 1, True), ("u_xy", 1, True), ("u_x", 1, False),
    ("u_yy", 1, False), ("u_n", 0, True), ("u_xx", 0, False)])
def test_a_sliding_edge_fixes_the_dofs_with_one_normal_derivative(dofname, normal_axis, fixed):
    assert is_fixed(dofname, "sliding", normal_axis) is fixed


def _boom(x, y):
    return 1 / 0


@pytest.mark.parametrize("call, message", [
    # silent wrong answers before: a NaN point read vertex 0, NaN data ran to a NaN energy
    (lambda S: deflection_at_vertex(S, np.zeros(S.basis.N), np.nan, 0.5), "x=nan"),
    (lambda S: plate_system(S, observe=[(np.nan, np.nan)]), "x=nan must be a finite"),
    (lambda S: plate_system(S, loads=[Pressure(lambda x, y: np.nan * x)]),
     r"Pressure p is nan at \(.*\): it must be a finite number there"),
    (lambda S: plate_system(S, initial=PlateInitial(v0=lambda x, y: np.nan * x)),
     "PlateInitial v0 is nan"),
    # errors from inside numpy, the user's own function or the scheme before
    (lambda S: plate_system(S, loads=[Pressure(lambda x, y: np.ones(3))]),
     "Pressure p: its function of x, y at the 784 points must return one number per point"),
    (lambda S: plate_system(S, obstacles=[PlateObstacle(g1=_boom)]),
     "PlateObstacle g1: .* gave ZeroDivisionError"),
    (lambda S: Pressure(1e3, time=lambda t: 1.0), "Pressure time must be vectorised"),
    (lambda S: PlateObstacle(points=(0.5, 0.5)), r"points=\(0.5, 0.5\) must be vertices"),
    (lambda S: plate_system(S, observe=(0.5, 0.5)), "observe=.* must be vertices"),
    (lambda S: PlateObstacle(g1="abc"), "g1='abc' must be a number"),
    (lambda S: PlateObstacle(g2=np.nan), "PlateObstacle g2=nan must be a number"),
    (lambda S: plate_system(S, obstacles=None), "obstacles= must be a list"),
    (lambda S: PlateObstacle(g1=-1e-3, points=[(0.5, 0.5)], region=(0, 0.25, 0, 0.25)),
     "give one of region, disk, points"),
    (lambda S: Pressure(1e3, time=lambda t: np.nan * t), "Pressure time gives"),
    (lambda S: load_vector(S, lambda x, y: np.nan * x), "load_vector p is nan"),
])
def test_python_values_are_checked_in_one_line(call, message):
    S = plate_space(Plate(nx=4, ny=4))
    with pytest.raises(InputError, match=message):
        call(S)
    # points as an array of rows is one point stop ("ambiguous truth value" before)
    stop = PlateObstacle(g1=-1e-3, points=np.array([[0.5, 0.5]]))
    assert plate_system(S, obstacles=[stop]).C.shape == (1, 64)


@pytest.mark.parametrize("call, message", [
    (lambda: Plate(a=None), "plate side a=None is not a number"),
    (lambda: Plate(b=np.inf), "plate side b=inf must be a finite number"),
    (lambda: Plate(nx=[4, 4]), r"plate nx=\[4, 4\] must be a whole number ≥ 1"),
    (lambda: beam_system(Plate()), "beam_system needs a BeamProblem, not Plate"),
    (lambda: plate_space("x"), "plate_space needs a Plate or a MeshPlate"),
    (lambda: full_dofs(plate_system(plate_space(Plate(nx=2, ny=2))), np.zeros(3)),
     "its last axis must be the system's"),
])
def test_plate_api_calls_check_their_arguments(call, message):
    with pytest.raises(InputError, match=message):
        call()


@pytest.mark.parametrize("element", ["bfs", "morley", "argyris"])
@pytest.mark.parametrize("region", [(0.5, 0.51, 0.0, 1.0), (0.13, 0.71, 0.27, 0.88),
                                    (0.5, 0.625, 0.0, 1.0)])
def test_a_pressure_over_a_rectangle_that_cuts_cells_has_its_exact_resultants(element, region):
    """The force and first moments of p over the rectangle, whether its sides are grid lines
    (0.5, 0.625 on 8 × 8) or cut cells (a strip inside one element had 81 % of its force):
    Σ b_i r_i for the interpolants r of 1, x and xy."""
    space = plate_space(Plate(a=1.0, b=1.0, nx=8, ny=8, element=element))
    b = Pressure(2.0, region=region).vector(space)
    x0, x1, y0, y1 = region
    exact = [2.0 * (x1 - x0) * (y1 - y0), (x1 ** 2 - x0 ** 2) * (y1 - y0),
             0.5 * (x1 ** 2 - x0 ** 2) * (y1 ** 2 - y0 ** 2)]
    got = [b[space.w_dofs].sum()] + [b @ space.basis.project(f) for f in (
        lambda x: x[0], lambda x: x[0] * x[1])]
    assert got == pytest.approx(exact, rel=1e-9)


@pytest.mark.parametrize("kwargs, message", [
    ({"points": [], "g1": -1e-3}, "points=\\(\\) names no vertex"),
    ({}, "needs g1 and/or g2"),
    ({"g1": -np.inf, "points": [(0.5, 0.5)]}, "needs g1 and/or g2"),
])
def test_an_obstacle_that_would_act_nowhere_or_everywhere_is_refused(kwargs, message):
    """PlateObstacle(points=[]) acted under the whole plate (an empty list read as no
    points given), and one with neither g1 nor g2 ran with no constraint, silently."""
    with pytest.raises(InputError, match=message):
        PlateObstacle(**kwargs)
