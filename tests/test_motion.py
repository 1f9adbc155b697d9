"""Prescribed support motion: time functions, the lifting for any end conditions and
supports, obstacles anywhere (fixed or carried) with a moving support."""
import dataclasses

import numpy as np
import pytest

from skfem_beam.methods import PositionLevel

from skfem_beam import (Beam, BeamProblem, InitialState, InputError, Obstacles, Support,
                        beam_system, scenes, solve)
from skfem_beam.timefunctions import Constant, Sine, SumOfSines, Table, band_limited

K2 = 282.84


# --- time functions ---------------------------------------------------------------------

def test_time_functions_derivatives_and_shapes():
    t = np.linspace(0, 1, 12).reshape(3, 4)        # any shape: the loop passes (4, block)
    d = 1e-5
    for f in (Sine(0.2, 10.0, 0.3), SumOfSines((0.1, 0.05), (7.0, 31.0), (0.0, 1.0)),
              band_limited(0.01, 2.0, 8.0, seed=3)):
        assert f(t).shape == f.d(t).shape == f.dd(t).shape == (3, 4)
        np.testing.assert_allclose(f.d(t), (f(t + d) - f(t - d)) / (2 * d), atol=1e-8)
        np.testing.assert_allclose(f.dd(t), (f.d(t + d) - f.d(t - d)) / (2 * d), atol=1e-6)
    assert Constant(2.0)(t).shape == (3, 4) and not Constant(2.0).dd(t).any()


def test_band_limited_is_reproducible_and_has_its_rms():
    a, b = band_limited(0.01, 2.0, 8.0, seed=7), band_limited(0.01, 2.0, 8.0, seed=7)
    t = np.linspace(0, 200, 400001)
    assert np.array_equal(a(t), b(t))
    assert not np.array_equal(a(t), band_limited(0.01, 2.0, 8.0, seed=8)(t))
    assert np.sqrt(np.mean(a(t) ** 2)) == pytest.approx(0.01, rel=0.02)


def test_table_of_a_sine_reproduces_the_sine():
    # not-a-knot cubic spline of 0.2 sin 10t sampled every 1 ms: measured errors
    # 5.2e-12 (φ), 1.6e-8 (φ'), 1.7e-4 (φ'', relative to 20: 8e-6)
    t = np.arange(0, 0.4, 1e-3)
    tab = Table(tuple(t), tuple(0.2 * np.sin(10 * t)))
    s = np.linspace(0, 0.3, 3001)
    assert np.abs(tab(s) - 0.2 * np.sin(10 * s)).max() < 1e-11
    assert np.abs(tab.d(s) - 2 * np.cos(10 * s)).max() < 3e-8
    assert np.abs(tab.dd(s) + 20 * np.sin(10 * s)).max() < 3e-4
    # ... and the first paper's run: tip within 1.03e-9 m over the first impact (T = 0.15)
    p1 = scenes.point_stops()
    p2 = dataclasses.replace(p1, support=Support(motion=tab))
    r1, r2 = (solve(beam_system(p), dt=5e-5, T=0.15) for p in (p1, p2))
    diff = np.abs(r1.observed["tip_displacement"] - r2.observed["tip_displacement"]).max()
    assert diff < 3e-9, diff


def test_table_from_csv_and_its_refusals(tmp_path):
    f = tmp_path / "phi.csv"
    f.write_text("t,phi\n0,0\n0.1,1\n0.2,4\n0.3,9\n")
    tab = Table.from_csv(f)
    assert tab(0.15) == pytest.approx(0.15**2 * 100, rel=1e-12)   # cubics are exact
    f.write_text("t,phi\n0,0\n0.1,1\n0.1,4\n0.3,9\n")
    with pytest.raises(InputError, match=r"phi\.csv: t is not increasing at row 4 "
                                          r"\(t=0\.1 after 0\.1\)"):
        Table.from_csv(f)
    f.write_text("0,0\n0.1,x\n")
    with pytest.raises(InputError, match=r"row 2 is not two numbers"):
        Table.from_csv(f)
    with pytest.raises(InputError, match=r"cannot read the table"):
        Table.from_csv(tmp_path / "missing.csv")
    # Excel's "CSV UTF-8" starts with a byte-order mark: its first row was taken for a
    # header and silently left out; another encoding was a UnicodeDecodeError traceback
    # a NaN on the file's line 3 was "phi ... in row 2" (its row among the numbers)
    f.write_text("t,phi\n0,0\n0.1,nan\n0.2,4\n0.3,9\n")
    with pytest.raises(InputError, match=r"the second column is not a finite number in row 3"):
        Table.from_csv(f)
    f.write_bytes("\ufeff0,0\n0.1,1\n0.2,4\n0.3,9\n".encode("utf-8"))
    assert Table.from_csv(f).t == (0.0, 0.1, 0.2, 0.3)
    f.write_bytes("t,déplacement µm\n0,0\n".encode("latin-1"))
    with pytest.raises(InputError, match=r"phi\.csv: not a UTF-8 text file"):
        Table.from_csv(f)


# --- the lifting --------------------------------------------------------------------------

@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_static_lifting_of_a_cantilever_is_the_rigid_translation(element):
    p = BeamProblem(Beam(1.5, K2), support=Support(0.01, 10.0, lifting="static"), J=10,
                    element=element)
    s = beam_system(p)
    x = np.linspace(0, 1.5, 31)
    assert np.abs(s.view.lift.h(x) - 1).max() < 1e-11
    assert np.abs(s.view.lift.h_dd(x)).max() < 1e-10
    assert s.view.support is None and s.view.lift.kind == "static"


@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_static_lifting_meets_the_other_supports(element):
    # pinned–pinned with a support at 0.6, the right end moving
    p = BeamProblem(Beam(1.5, K2), support=Support(0.01, 10.0, at=1.5), J=10,
                    ends=("pinned", "pinned"), supports=(0.6,), element=element)
    s = beam_system(p)
    h = s.view.lift.h(np.array([0.0, 0.6, 1.5]))
    np.testing.assert_allclose(h, [0, 0, 1], atol=1e-12)
    assert p.lifting == "static"
    # a(h, w) = 0 on V_h: the φ column of the load is round-off
    assert np.abs(s.loads[:, 1]).max() < 1e-9 * np.abs(K2 * s.space.S).max()


def test_paper_and_static_liftings_give_the_same_physical_tip():
    # no obstacles, at rest in the fixed frame; centred load window (second order in Δt):
    # measured 2.3e-8 m at Δt = 1e-4, J = 20 (the forward window differs by O(Δt): 1.8e-4)
    base = BeamProblem(Beam(1.501, K2), support=Support(0.2, 10.0, lifting="paper"), J=20,
                       initial=InitialState(fixed_frame=True))
    ra = solve(beam_system(base), dt=1e-4, T=0.5, load_window="centered")
    st = dataclasses.replace(base, support=Support(0.2, 10.0, lifting="static"))
    rs = solve(beam_system(st), dt=1e-4, T=0.5, load_window="centered")
    tip = rs.observed["tip_displacement"] + 0.2 * np.sin(10 * rs.t)     # h(L) = 1
    assert np.abs(ra.observed["tip_displacement"] - tip).max() < 5e-8


# --- obstacles anywhere with a moving support ---------------------------------------------

def span_problem(carried, lifting="auto", motion=None):
    obs = Obstacles.combine(Obstacles.span(0.6, 1.2, -0.004, 0.004, carried=carried),
                            Obstacles.stops([1.5], -0.01, 0.02, carried=carried))
    sup = Support(motion=motion, lifting=lifting) if motion is not None else \
        Support(0.02, 20.0, lifting=lifting)
    return BeamProblem(Beam(1.5, K2), obs, sup, J=20, initial=InitialState(fixed_frame=True))


def observe_constraints(system):
    for i in range(system.C.shape[0]):
        system.observe[f"y{i}"] = system.C[i].toarray().ravel()
    return system


@pytest.mark.parametrize("carried", [False, True])
@pytest.mark.parametrize("lifting", ["paper", "static"])
def test_moving_support_with_obstacles_over_the_span(carried, lifting):
    s = observe_constraints(beam_system(span_problem(carried, lifting)))
    h = s.view.lift.h(s.x_contact)
    want = (1.0 if carried else 0.0) - h
    if s.bound_shift is None:   # carried on a rigidly translating cantilever: at rest in u
        assert carried and lifting == "static" and np.abs(want).max() < 1e-9
        phi, shift0 = (lambda t: np.zeros_like(t)), np.zeros_like(h)
    else:
        np.testing.assert_allclose(s.bound_shift, want, atol=1e-12)
        phi, shift0 = s.bound_motion, s.bound_shift
    r = solve(s, dt=1e-4, T=1.0, method=PositionLevel("active-set"))
    assert r.success and r.impacts > 5
    y = np.column_stack([r.observed[f"y{i}"] for i in range(s.C.shape[0])])
    shift = np.outer(phi(r.t), shift0)
    violation = np.maximum(s.lo + shift - y, y - s.hi - shift).max()
    assert violation <= 1e-10, violation
    assert r.max_nodal_violation <= 1e-10


def test_still_support_carried_and_fixed_are_identical():
    for motion in (None, Constant(0.0)):
        runs = []
        for carried in (False, True):
            p = span_problem(carried, motion=motion) if motion is not None else \
                dataclasses.replace(span_problem(carried), support=Support())
            runs.append(solve(beam_system(p), dt=1e-4, T=0.3, method=PositionLevel("active-set")))
        assert np.array_equal(runs[0].observed["tip_displacement"],
                              runs[1].observed["tip_displacement"])


@pytest.mark.parametrize("kw, words", [
    (lambda: dict(support=Support(0.01, 10.0, at=1.5)), ["moving at x=1.5 is a free end"]),
    (lambda: dict(support=Support(0.01, 10.0, lifting="bent")), ["lifting='bent'",
                                                                  "auto, paper"]),
    (lambda: dict(support=Support(0.01, 10.0, motion=Sine(1, 1))), ["either amplitude/omega"]),
    (lambda: dict(obstacles=Obstacles.combine(
        Obstacles.stops([0.75], -0.1, np.inf),
        Obstacles.stops([0.75], -np.inf, 0.1, carried=True))),
     ["carried and a fixed obstacle both act at x=0.75"]),
    (lambda: dict(obstacles=Obstacles.span(0.9, 0.6, -1, 1)), ["span [a=0.9, b=0.6]"]),
])
def test_bad_motion_input_is_refused_with_one_clear_line(kw, words):
    with pytest.raises(InputError) as err:
        BeamProblem(Beam(1.5, K2), J=10, **kw())
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


ROD = Beam(0.5, k2=2.0e11 * np.pi * 0.01 ** 4 / 64 / (7800 * np.pi * 0.01 ** 2 / 4))


def test_a_support_displaced_at_the_start_carries_the_beam_at_rest():
    """A clamp at φ(0) = 1 mm and no u0 (at rest, fixed frame): the beam was read flat,
    the interpolant dropped the 1 mm at the clamp, and the strain energy of that kink grew
    as J³ (4.3 J at J = 10, 1,236 J at J = 80).  It now starts on its support: with the
    clamp held still, the tip stays at 1 mm on every mesh; a u0 that misses the clamp is
    refused in one line."""
    for J in (10, 40):
        p = BeamProblem(ROD, support=Support(motion=Constant(0.001)), J=J,
                        initial=InitialState(fixed_frame=True))
        r = solve(beam_system(p), 1e-5, 0.01)
        assert np.abs(r.observed["tip_displacement"] - 0.001).max() < 1e-9
    with pytest.raises(InputError, match=r"the start misses what holds the beam at x=0 at "
                                         r"t = 0 by -0.001 m \(the support is at 0.001 m "
                                         r"there\)"):
        beam_system(dataclasses.replace(p, initial=InitialState(
            u0=lambda x: np.zeros(np.shape(x)), fixed_frame=True)))


@pytest.mark.parametrize("phase", [np.pi / 2, np.pi])
def test_a_sine_support_starts_where_its_phase_puts_it(phase):
    """φ(0) = A sin(phase): 1 mm at π/2 (the beam starts on it, finite energy on every
    step), round-off at π (2.4e-17 m: not refused as a start off the support)."""
    p = BeamProblem(ROD, support=Support(motion=Sine(0.001, 50.0, phase=phase)), J=10,
                    initial=InitialState(u0=lambda x: np.zeros(np.shape(x)), fixed_frame=True)
                    if phase == np.pi else InitialState(fixed_frame=True))
    assert np.isfinite(solve(beam_system(p), 1e-5, 0.002).energy).all()


SHAKEN = """kind = "beam"
[mass_normalised]
k2 = 282.84
rho_S = 0.11938052083641222
[geometry]
L = 1.501
[motion]
end = "left"
amplitude = 0.2
omega = 10.0
lifting = "{lift}"
[[obstacles]]
x = 1.501
g1 = -0.1
g2 = 0.1
carried = {carried}
[time]
dt = 1e-5
T = 0.1
[output]
format = "none"
"""


@pytest.mark.parametrize("carried", ["false", "true"])
@pytest.mark.parametrize("lift", ["paper", "static"])
def test_an_impacts_velocity_is_relative_to_its_obstacle_whatever_the_lifting(
        tmp_path, lift, carried):
    """impacts.csv's velocity was the lifted variable's: a fixed stop under the static
    lifting read +3.74 for +5.02 m/s, a carried one under the paper's −0.43 for −2.17.
    Now the tip's velocity relative to its stop at the state before the first contact:
    the series' tip_velocity there, less φ' = 2 cos 10t for a carried stop (to the
    difference between the scheme's velocity and the backward difference)."""
    import csv
    from conftest import exit_code
    from skfem_beam.scenefile import run_main
    scene, out = tmp_path / "shaken.toml", tmp_path / "run"
    scene.write_text(SHAKEN.format(lift=lift, carried=carried))
    assert exit_code(run_main, [str(scene), "--out", str(out)]) == 0
    first = next(csv.DictReader(open(out / "impacts.csv")))
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    t = np.array([float(r["t"]) for r in rows])
    i = int(np.argmin(np.abs(t - float(first["t_start"])))) - 1
    truth = float(rows[i]["tip_velocity"]) - (2 * np.cos(10 * t[i]) if carried == "true"
                                               else 0.0)
    assert abs(truth) > 1.0
    assert float(first["velocity"]) == pytest.approx(truth, rel=1e-4)


def test_damping_acts_on_the_motion_relative_to_the_support_whatever_the_lifting():
    """Rayleigh damping on the paper's lifted u = ũ − hφ (h(L) = 0, not the support's
    rigid motion) damped part of the support's own motion: the damped pipe's tip at
    φ = 0 read −2.27e-4 m with the paper's lifting against −1.55e-4 with the static one
    (h ≡ 1).  A load B(r − h)φ' makes both damp ũ − rφ (r the static lifting): they now
    agree as the undamped ones do (2e-6 m of a 3e-3 m amplitude, h's discretisation)."""
    from skfem_beam.output.fields import physical_tip
    from skfem_beam.problem import Damping
    w, A = 20.0, 0.001
    d = Damping.ratio(0.02, 4.1771484888546, 26.177742732411378)
    P = 2 * np.pi / w
    spp = round(P / 1e-4)
    dt = P / spp
    from skfem_beam.problem import lifting
    rest = {"paper": lambda x: -A * w * lifting(x, 1.501),       # at rest in the fixed
            "static": lambda x: -A * w * np.ones_like(x)}         # frame: v0 = −h φ'(0)
    tips = {}
    for lift in ("paper", "static"):
        problem = scenes.point_stops(omega=w, amplitude=A, gap=100.0, damping=d)
        problem = dataclasses.replace(problem, support=dataclasses.replace(
            problem.support, lifting=lift), initial=InitialState(v0=rest[lift]))
        system = beam_system(problem)
        r = solve(system, dt, (16 * spp - 0.5) * dt, save_every=spp, frames=1)
        tips[lift] = physical_tip(system.view, r.t, r.observed["tip_displacement"],
                                  r.velocity["tip_displacement"])[0]
    scale = np.abs(tips["static"]).max()                 # 2.9e-3 m
    assert np.abs(tips["paper"] - tips["static"]).max() < 1e-3 * scale
