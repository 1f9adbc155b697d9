"""Probes (--probe X): displacement, velocity, bending moment and shear at any x, against
exact solutions (a static tip load), the run's own tip value, and the lifting."""
import json
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from conftest import assert_refused
from skfem_beam import (Beam, BeamProblem, InputError, Load, Material, Section, beam_system,
                        scenes)
from skfem_beam.cases import point_stops
from skfem_beam.output.probes import probe_columns, third_derivative
from skfem_beam.problem import lifting_dd
from skfem_beam.results import read_run
from skfem_beam.semidiscrete import add_probes

STEEL, ALU, PIPE, L = Material(2e11, 8000.0), Material(7e10, 2700.0), \
    Section.tube(0.01, 0.0005), 1.5
BEAM = Beam.physical(L, STEEL, PIPE)
P = 3.0


def static_probes(beam, xs, element="hermite", J=10, nodes=None):
    """The probe columns of the static cantilever under a tip load P (in N·m and N)."""
    s = beam_system(BeamProblem(beam, load=Load.point(L, P), J=J, element=element,
                                nodes=nodes))
    add_probes(s, xs)
    f = s.loads @ np.array([float(a(np.array([0.0]))[0]) for a in s.load_time])
    u = spla.spsolve(s.K.tocsc(), f)
    obs = np.array([[row @ u for row in s.observe.values()]])
    run = SimpleNamespace(system=s, obs=obs, obsv=np.zeros_like(obs), save_every=1, dt=1.0)
    return probe_columns(run, 0, 1)


@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_static_tip_load_moment_shear_and_deflection_are_exact(element):
    # the exact solution is one cubic, in both spaces: M = P(L − x), shear σ̃ = −EIu''' = P,
    # u = P x²(3L − x)/(6EI); nodes, element interiors and the ends
    xs = [0.0, 0.15, 0.4, 0.75, 1.2, L]
    cols = static_probes(BEAM, xs, element)
    tip = P * L**3 / (3 * BEAM.EI)          # 0.1 m: the scale of u, 0 at the clamp x = 0
    for x in xs:
        c = {q: cols[f"probe_{x:g}_{q}"][0] for q in ("displacement", "moment", "shear")}
        assert c["moment"] == pytest.approx(P * (L - x), abs=1e-11 * P * L)
        assert c["shear"] == pytest.approx(P, rel=1e-11)
        assert c["displacement"] == pytest.approx(P * x**2 * (3 * L - x) / (6 * BEAM.EI),
                                                  rel=1e-10, abs=1e-17 * tip)


def test_stepped_beam_moment_uses_each_segment_EI():
    # aluminium rod on steel tube: u'' jumps at the step, M = EI(x)u'' = P(L − x) does not
    rod = Section.rod(0.008)
    beam = Beam.stepped([(0.6, STEEL, PIPE), (0.9, ALU, rod)])
    nodes = np.concatenate([np.linspace(0, 0.6, 5), np.linspace(0.6, L, 7)[1:]])
    xs = [0.3, 0.6, 0.9, 1.4]
    cols = static_probes(beam, xs, nodes=nodes)
    for x in xs:
        assert cols[f"probe_{x:g}_moment"][0] == pytest.approx(P * (L - x), abs=1e-11 * P * L)
        assert cols[f"probe_{x:g}_shear"][0] == pytest.approx(P, rel=1e-11)


def test_third_derivative_of_the_lifting_is_exact():
    # the paper's h: h''' = 8(1 − s)/L³, s = x/L (h'' is quadratic: the 3-point fit is exact)
    for a, b, x in [(0.0, 0.3, 0.0), (0.3, 0.6, 0.45), (1.2, 1.5, 1.5)]:
        assert third_derivative(lambda z: lifting_dd(z, L), x, a, b) == \
            pytest.approx(8 * (1 - x / L) / L**3, rel=1e-12, abs=4e-13 * 8 / L**3)  # 0 at L


def test_probes_are_refused_outside_the_beam_or_twice():
    s = beam_system(BeamProblem(BEAM, J=4))
    for bad in ([-0.1], [L + 1e-6], [0.5, 0.5]):
        with pytest.raises(InputError, match="probe x="):
            add_probes(beam_system(BeamProblem(BEAM, J=4)), bad)
    add_probes(s, [0.0, L])
    assert list(s.observe)[1:] == [f"probe_{x:g}_{q}" for x in (0.0, L)
                                   for q in ("displacement", "moment", "shear")]


def test_cli_refuses_a_probe_outside_the_beam(tmp_path, capsys):
    out = tmp_path / "sub"
    out.mkdir()
    assert_refused(point_stops.main, ["--T", "0.01", "--probe", "2", "--out", str(out / "r")],
                   "probe x=2", capsys, out)


@pytest.fixture(scope="module")
def pipe_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("probes") / "run"
    code = point_stops.main(["--dt", "1e-4", "--T", "0.3", "--frames", "30", "--format",
                             "none", "--probe", "1.501", "--probe", "0.8", "--out", str(out)])
    assert code == 0
    return read_run(out)


def test_tip_probe_equals_tip_displacement(pipe_run):
    s = pipe_run.series
    # the same row, and h(L) = −5.6e-17 taken as 0: bit for bit
    assert np.array_equal(s["probe_1.501_displacement"], s["tip_displacement"])
    assert np.array_equal(s["probe_1.501_velocity"], s["tip_velocity"])
    assert pipe_run.summary["units"]["probes"]["moment"].startswith("N·m")


def test_interior_probe_adds_the_support_motion():
    # ũ(x) = u(x) + h(x)φ(t) and k²ũ'' at x = 0.8 (inside an element), from the saved
    # coefficient frames evaluated independently
    from skfem_beam.scheme import Run, Stepping, drive
    from skfem_beam.scheme.beta import BetaScheme
    from skfem_beam.contact import resolve
    from skfem_beam.problem import lifting
    pb = scenes.point_stops()
    s = beam_system(pb)
    add_probes(s, [0.8])
    run = Run(BetaScheme(s, Stepping(1e-4, 0.2, 1, 2000), resolve("auto", None)))
    drive(run)
    cols, r = probe_columns(run, 0, run.n + 1), run.result()
    k = np.arange(0, run.n + 1, run.frame_every)
    phi = pb.support.phi(k * run.dt)
    sp_ = s.space
    u = sp_.point_rows([0.8], 0) @ r.frames_u.T
    upp = sp_.point_rows([0.8], 2) @ r.frames_u.T
    assert np.abs(phi).max() > 0.1
    np.testing.assert_allclose(cols["probe_0.8_displacement"][k],
                               u.ravel() + lifting(0.8, pb.beam.L) * phi, rtol=0,
                               atol=5e-13 * pb.support.amplitude)     # φ: 0.2 m amplitude
    moment = pb.beam.k2 * (upp.ravel() + lifting_dd(0.8, pb.beam.L) * phi) * pb.beam.rho_S
    np.testing.assert_allclose(cols["probe_0.8_moment"][k], moment, rtol=0,
                               atol=1e-12 * np.abs(moment).max())


def test_probe_flag_is_stored_for_resume(pipe_run):
    assert pipe_run.summary["config"]["probe"] == [1.501, 0.8]
    assert json.dumps(pipe_run.summary["units"]["probes"])


def test_a_probe_at_a_node_takes_the_mean_of_both_sides_moments():
    """A Hermite u'' jumps at a node where the elements' solutions differ (here a tip
    load P inside the element to the node's right): a probe at a node read the element
    to its right (0.52 against the bending_moment field's 0.39 N·m on flat_obstacles); it
    now takes the mean of both sides' EI u'', as the field does."""
    x = 0.75                                # a node (0.15 apart); the load at 0.8
    s = beam_system(BeamProblem(BEAM, load=Load.point(0.8, P), J=10))
    add_probes(s, [x])
    f = s.loads @ np.array([float(a(np.array([0.0]))[0]) for a in s.load_time])
    u = spla.spsolve(s.K.tocsc(), f)
    obs = np.array([[row @ u for row in s.observe.values()]])
    run = SimpleNamespace(system=s, obs=obs, obsv=np.zeros_like(obs), save_every=1, dt=1.0)
    mid = probe_columns(run, 0, 1)[f"probe_{x:g}_moment"][0]
    scale = s.meta["problem"].beam.k2 * probe_units_scale(s)      # EI u'' in N·m
    left, right = (scale * float((s.space.point_rows([x], 2, side=side) @ u)[0])
                   for side in ("left", "right"))
    assert left == pytest.approx(P * (0.8 - x), rel=1e-9)   # the left element is exact
    assert abs(left - right) > 0.1 * abs(left)               # the jump this is about
    assert mid == pytest.approx(0.5 * (left + right), rel=1e-12)


def probe_units_scale(system) -> float:
    """ρS: the probe columns' mass-normalised values times it are N·m."""
    return float(system.meta["problem"].beam.rho_S)


def test_a_b_spline_probe_at_a_section_step_is_the_field_s_moment():
    """A B-spline's u'' is continuous but EI jumps at a section step: the probe there read
    the right segment's EI u'' (−3.6 against the bending_moment field's −7.4 N·m in a
    user's run); it takes the mean of both sides' EI, as the field does."""
    from skfem_beam.output.fields import sample_line
    rod = Section.rod(0.008)
    beam = Beam.stepped([(0.6, STEEL, PIPE), (0.9, ALU, rod)])
    s = beam_system(BeamProblem(beam, load=Load.point(L, P), J=15, element="bspline"))
    add_probes(s, [0.6])
    f = s.loads @ np.array([float(a(np.array([0.0]))[0]) for a in s.load_time])
    u = spla.spsolve(s.K.tocsc(), f)
    obs = np.array([[row @ u for row in s.observe.values()]])
    run = SimpleNamespace(system=s, obs=obs, obsv=np.zeros_like(obs), save_every=1, dt=1.0)
    probe = probe_columns(run, 0, 1)["probe_0.6_moment"][0]
    line = sample_line(s, 8)
    field = line.fields(0.0, u, np.zeros_like(u), np.zeros(s.C.shape[0]))["bending_moment"]
    at = np.flatnonzero(np.isclose(line.points[:, 0], 0.6))
    assert at.size and probe == pytest.approx(field[at[0]], rel=1e-9)
    assert abs(probe) > 1.0
