"""The output in the frame and units an engineer reads: the physical ũ for any lifting
(fields, tip columns), obstacles carried by the support drawn where they are, moments of
stepped beams, energies and work in J, the bar's field force as the obstacle's push."""
import json

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from conftest import exit_code
from skfem_beam import (Beam, BeamProblem, InitialState, Obstacles, Support, beam_system,
                        read_run, solve)
from skfem_beam.bar import Bar, bar_system
from skfem_beam.cases import point_stops
from skfem_beam.output.fields import physical_tip, sample_line
from skfem_beam.problem import Damping, Load, Material, Section
from skfem_beam.timefunctions import Sine

STEEL = Material(E=2e11, rho=7850.0)
TUBE = Section.tube(0.02, 0.002)
SHAKE = Sine(0.002, 60.0)                      # φ = 2 mm sin 60t at the root


def _shaken(lift="static", obstacles=Obstacles(), J=20, **kw):
    """A 1 m steel tube cantilever shaken at its root, at rest in the fixed frame."""
    return BeamProblem(Beam.physical(1.0, STEEL, TUBE), obstacles,
                       Support(motion=SHAKE, lifting=lift),
                       initial=InitialState(fixed_frame=True), J=J, **kw)


def test_static_lifting_fields_show_the_physical_displacement():
    """A cantilever shaken at its root: the static lifting is h ≡ 1, so ũ = u + φ(t),
    ũ_t = v + φ'(t) at every point, and the clamp sits on φ(t)."""
    s = beam_system(_shaken())
    r = solve(s, dt=1e-5, T=0.05, frames=10)
    line = sample_line(s)
    # the discrete h is 1 to the static solve's round-off: 7.95e-12 on this machine, a
    # margin of 12 for another machine's (its condition number times ε)
    dh = 1e-10
    assert s.view.lift.kind == "static" and np.abs(line.h - 1).max() < dh
    for k in (3, 7, 10):
        t, u, v = r.frames_t[k], r.frames_u[k], r.frames_v[k]
        f = line.fields(t, u, v, r.frames_force[k])
        phi, dphi = float(SHAKE(t)), 0.002 * 60 * np.cos(60 * t)
        assert abs(phi) > 2e-4
        # the field is E0 u + hφ: it differs from E0 u + φ by (h − 1)φ (7.95e-12 |φ| here),
        # plus the sum's round-off
        want, want_v = line.E0 @ u + phi, line.E0 @ v + dphi
        np.testing.assert_allclose(f["displacement"], want, rtol=0,
                                   atol=dh * abs(phi) + 1e-14 * np.abs(want).max())
        np.testing.assert_allclose(f["velocity"], want_v, rtol=0,
                                   atol=dh * abs(dphi) + 1e-14 * np.abs(want_v).max())
        # h(0) = 1 is imposed at the clamp (0 measured): 5e-12 |φ| ≤ 1e-14 m at |φ| ≤ 2 mm
        assert f["displacement"][0] == pytest.approx(phi, rel=5e-12)
        # h'' = 0 up to the solve's round-off: the moment is the relative u's (N·m: × ρS)
        np.testing.assert_allclose(f["bending_moment"], line.rho_S * line.k2 * (line.E2 @ u),
                                   rtol=0, atol=1e-9 * np.abs(f["bending_moment"]).max())


def test_tip_columns_are_the_physical_tip_for_any_lifting():
    """The paper's lifting (h(L) = 0) and the static one (h(L) = 1) solve the same beam:
    their physical tips ũ(L) agree to the scheme's first-order load lag, which halves with
    Δt (u(L) of the static run alone is off by φ, up to 2 mm)."""
    diffs = []
    for dt in (2e-5, 1e-5):
        tips = {}
        for lift in ("paper", "static"):
            s = beam_system(_shaken(lift, J=10))
            r = solve(s, dt=dt, T=0.05)
            tips[lift] = physical_tip(s.view, r.t, r.observed["tip_displacement"],
                                      r.velocity["tip_displacement"])
            if lift == "paper":     # h(L) = −5.6e-17: the column is u(L), bit for bit
                assert tips[lift][0] is r.observed["tip_displacement"]
        diffs.append([np.abs(tips["paper"][i] - tips["static"][i]).max() for i in (0, 1)])
        assert np.abs(tips["paper"][0]).max() > 4e-3
    (d1, v1), (d2, v2) = diffs
    assert d2 < 1.2e-6 and v2 < 8e-5                        # against φ up to 2e-3 m, 0.12 m/s
    assert 1.9 < d1 / d2 < 2.1 and 1.9 < v1 / v2 < 2.1      # first order in Δt


def test_carried_obstacles_are_drawn_where_they_are():
    """A stop carried by the shaken frame at x = 0.5 (±0.5 mm) and one fixed to the ground at
    the tip (±4 mm): the field's g1, g2 are in the frame of ũ, the carried one at g + φ(t),
    the fixed one at g, and the nodal ũ stays between them at every frame."""
    obs = Obstacles.combine(Obstacles.stops([0.5], -5e-4, 5e-4, carried=True),
                            Obstacles.point_stops(1.0, -0.004, 0.004))
    s = beam_system(_shaken(obstacles=obs))
    r = solve(s, dt=1e-5, T=0.1, frames=500)
    line = sample_line(s)
    i_mid, i_tip = (int(np.argmin(np.abs(line.x - x))) for x in (0.5, 1.0))
    touches = 0
    for k, t in enumerate(r.frames_t):
        f = line.fields(t, r.frames_u[k], r.frames_v[k], r.frames_force[k])
        phi = float(SHAKE(t))
        assert f["g1"][i_mid] == -5e-4 + phi and f["g2"][i_mid] == 5e-4 + phi
        assert f["g1"][i_tip] == -0.004 and f["g2"][i_tip] == 0.004
        assert np.isnan(f["g1"][[0, i_mid - 1, i_mid + 1, i_tip - 1]]).all()
        y = f["displacement"][line.contact]
        assert (y >= f["g1"][line.contact] - 1e-10).all()
        assert (y <= f["g2"][line.contact] + 1e-10).all()
        touches += np.isclose(y[0], [f["g1"][i_mid], f["g2"][i_mid]], atol=1e-10).any()
    assert touches >= 5 and r.impacts > 0       # it does lean on the moving stop


def _stepped(ends=("clamped", "free"), **kw):
    al = Material(E=7e10, rho=2700.0)
    beam = Beam.stepped([(0.6, STEEL, Section.tube(0.012, 0.001)),
                         (0.9, al, Section.rod(0.01))])
    return BeamProblem(beam, J=15, ends=ends, **kw)        # a node at the step x = 0.6


def test_stepped_beam_bending_moment_is_EI_u_second_derivative():
    """A stepped cantilever under a static tip force P: the exact u is cubic on every
    element, so the moment field EI(x)u'' is P(L − x) N·m to round-off, on both segments
    and at the step (k²u'' alone is off by EI₂/EI₁ beyond it)."""
    P = 3.0
    pb = _stepped(load=Load.point(1.5, P))
    s = beam_system(pb)
    u = spla.spsolve(s.K.tocsc(), s.loads[:, 0] * float(s.load_time[0](np.array([0.0]))[0]))
    line = sample_line(s)
    f = line.fields(0.0, u, np.zeros_like(u), np.zeros(s.C.shape[0]))
    want = P * (1.5 - line.x)
    np.testing.assert_allclose(f["bending_moment"], want, rtol=0, atol=1e-9 * want.max())


def test_stepped_static_lifting_moment_is_continuous_and_linear():
    """A clamped–clamped stepped beam whose left clamp moves: with u = 0 the moment field is
    the lifting's EI h''φ, which (EI h'')'' = 0 makes linear in x across the step, where
    h'' itself jumps by EI₁/EI₂."""
    pb = _stepped(("clamped", "clamped"), support=Support(motion=Sine(1.0, 1.0)))
    s = beam_system(pb)
    assert s.view.lift.kind == "static"
    line = sample_line(s)
    n = s.n
    f = line.fields(np.pi / 2, np.zeros(n), np.zeros(n), np.zeros(s.C.shape[0]))   # φ = 1
    m = f["bending_moment"]
    fit = np.polyval(np.polyfit(line.x, m, 1), line.x)
    assert np.abs(m).max() > 1.0
    np.testing.assert_allclose(m, fit, rtol=0, atol=1e-8 * np.abs(m).max())
    phi = 1.0                                   # m: the support's amplitude, at t = π/2
    assert f["displacement"][0] == pytest.approx(phi, rel=1e-12)
    assert f["displacement"][-1] == pytest.approx(0.0, abs=1e-12 * phi)   # the fixed end


def test_case_writes_physical_units_and_the_energy_balance(monkeypatch, tmp_path):
    """A physical beam through a case command: damped, loaded, shaken with the static
    lifting, against fixed tip stops.  energy_J = ρS·energy and the work columns likewise;
    energy − energy[0] + work_damping = work_input + work_contact in the CSV to round-off;
    tip_displacement is the physical ũ(L) (the field's value at x = L); units named."""
    pb = _shaken(obstacles=Obstacles.point_stops(1.0, -0.004, 0.004),
                 damping=Damping.ratio(0.02, 20.0, 400.0), load=Load.point(1.0, 2.0))
    monkeypatch.setattr(point_stops.scenes, "point_stops", lambda **kw: pb)
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.1", "--dt", "1e-5", "--gap", "0.004",
                                        "--frames", "20", "--format", "xdmf",
                                        "--out", str(out)]) == 0
    run = read_run(out)
    d, rho = run.series, pb.beam.rho_S
    assert d["energy_J"].tolist() == (d["energy"] * rho).tolist()
    for k in ("damping", "input", "contact"):
        assert d[f"work_{k}_J"].tolist() == (d[f"work_{k}"] * rho).tolist()
    assert d["contact_force_N"].tolist() == (d["contact_force"] * rho).tolist()
    assert d["work_damping"][-1] > 0 and d["work_contact"][-1] < 0 and run.summary["impacts"] > 0
    closure = d["energy"] - d["energy"][0] + d["work_damping"] - d["work_input"] \
        - d["work_contact"]
    assert np.abs(closure).max() <= 1e-11 * np.abs(d["energy"]).max()
    # the physical tip: the field's ũ at x = L at every frame time (ũ(L) − u(L) = φ(t))
    f = run.fields
    rows = np.searchsorted(d["t"], f.t - 1e-12)
    np.testing.assert_allclose(d["t"][rows], f.t, atol=1e-11 * d["t"][-1])     # T = 0.1 s
    tip = f["displacement"][:, -1]
    np.testing.assert_allclose(d["tip_displacement"][rows], tip,
                               rtol=0, atol=2.5e-13 * np.abs(tip).max())
    assert np.abs(d["tip_displacement"]).max() == pytest.approx(0.004, rel=2.5e-7)  # the stop
    units = run.summary["units"]
    assert set(d) - {"t"} <= set(units) and "J" in units["energy_J"]
    assert "fixed frame" in units["tip_displacement"]
    assert json.loads((out / "summary.json").read_text())["status"] == "success"


def test_bar_field_force_is_the_obstacles_push():
    """The bar's field contact_force is R ≥ 0 at either end: an obstacle at x = L gives the
    mirror image of one at x = 0 (mirrored data), to round-off, not −λ ≤ 0."""
    got = {}
    for side, v0 in (("left", -1.0), ("right", 1.0)):
        r = solve(bar_system(Bar(obstacle_at=side, v0=v0, N=20)), dt=0.01, T=3.0, beta=0.25,
                  frames=100)
        line = sample_line(r.system, 1)
        got[side] = np.array([line.fields(t, r.frames_u[k], r.frames_v[k],
                                          r.frames_force[k])["contact_force"]
                              for k, t in enumerate(r.frames_t)])
    left, right = got["left"][:, 0], got["right"][:, -1]
    assert left.max() > 0.1 and left.min() >= 0.0 and right.min() >= 0.0
    np.testing.assert_allclose(right, left, rtol=0, atol=1e-12 * left.max())
