"""Loads in physical units (N, N/m), gravity, and Rayleigh damping of the beam."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

import skfem_beam
from skfem_beam import (Beam, BeamProblem, Damping, InitialState, InputError, Load, Material,
                        Section, beam_system, solve)
from skfem_beam.timefunctions import Ramp

STEEL, PIPE, L = Material(2e11, 8000.0), Section.tube(0.01, 0.0005), 1.5
BEAM = Beam.physical(L, STEEL, PIPE)
EI = BEAM.EI


def static_tip(load, element="hermite", J=10):
    s = beam_system(BeamProblem(BEAM, load=load, J=J, element=element))
    f = s.loads @ np.array([float(a(np.array([0.0]))[0]) for a in s.load_time])
    return s.observe["tip_displacement"] @ spla.spsolve(s.K.tocsc(), f)


@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_static_loads_give_the_textbook_deflections(element):
    # Hermite nodal values are exact for the beam equation; cubic splines for these loads
    P, q, g = 3.0, 2.0, 9.81
    assert static_tip(Load.point(L, P), element) == pytest.approx(P * L**3 / (3 * EI), rel=1e-11)
    assert static_tip(Load.distributed(q), element) == pytest.approx(q * L**4 / (8 * EI),
                                                                      rel=1e-11)
    assert static_tip(Load.gravity(g), element) == pytest.approx(-g * BEAM.rho_S * L**4
                                                                 / (8 * EI), rel=1e-11)
    # a point force at mid-span: tip = P a²(3L − a)/(6EI)
    a = L / 2
    assert static_tip(Load.point(a, P), element) == pytest.approx(
        P * a**2 * (3 * L - a) / (6 * EI), rel=1e-11)


def test_slowly_applied_tip_load_settles_at_the_static_deflection():
    # ramp over 2 s (≫ the first period 0.24 s), ζ = 5 %: the tip settles at PL³/(3EI)
    P = 1.0
    w1 = skfem_beam.modes(BeamProblem(BEAM, J=10), n=2).omega
    damping = Damping.ratio(0.05, w1[0] / (2 * np.pi), w1[1] / (2 * np.pi))
    p = BeamProblem(BEAM, load=Load.point(L, P, Ramp(2.0)), J=10, damping=damping)
    r = solve(beam_system(p), dt=1e-3, T=6.0, beta=0.25)
    exact = P * L**3 / (3 * EI)
    assert abs(r.observed["tip_displacement"][-1] / exact - 1) < 1e-3


def test_forces_in_newtons_need_the_mass_per_length():
    with pytest.raises(InputError, match="forces in N or N/m need the beam's mass per length"):
        BeamProblem(Beam(L, 282.84), load=Load.point(L, 1.0), J=10)
    with pytest.raises(InputError, match=r"point force at x=2 lies outside \[0, L=1\.5\]"):
        BeamProblem(BEAM, load=Load.point(2.0, 1.0), J=10)


# --- damping ----------------------------------------------------------------------------

def test_damping_ratio_at_two_frequencies():
    d = Damping.ratio(0.02, 3.0, 40.0)
    for f in (3.0, 40.0):
        w = 2 * np.pi * f
        assert d.alpha / (2 * w) + d.alpha_K * w / 2 == pytest.approx(0.02, rel=1e-14)
    with pytest.raises(InputError, match="f1=3 and f2=3 must differ"):
        Damping.ratio(0.02, 3.0, 3.0)
    with pytest.raises(InputError, match="zeta=-0.1 must be ≥ 0"):
        Damping.ratio(-0.1, 3.0, 4.0)


def test_logarithmic_decrement_of_the_first_mode():
    zeta = 0.02
    m = skfem_beam.modes(BeamProblem(BEAM, J=20), n=3)
    f1, f3 = m.f[0], m.f[2]
    p = BeamProblem(BEAM, J=20, damping=Damping.ratio(zeta, f1, f3),
                    initial=InitialState())
    s = beam_system(p)
    s.u0 = 0.01 * m.vectors[:, 0] / (s.observe["tip_displacement"] @ m.vectors[:, 0])
    dt = 1 / f1 / 2000
    r = solve(s, dt=dt, T=10 / f1, beta=0.25)
    tip = r.observed["tip_displacement"]
    peaks = [i for i in range(1, tip.size - 1) if tip[i - 1] < tip[i] >= tip[i + 1]]
    # parabolic refinement of each peak, then δ = ln(x_0/x_n)/n over the run
    vals = []
    for i in peaks:
        a, b, c = tip[i - 1], tip[i], tip[i + 1]
        vals.append(b - (a - c) ** 2 / (8 * (a - 2 * b + c)))
    n = len(vals) - 1
    delta = np.log(vals[0] / vals[-1]) / n
    measured = delta / np.sqrt(4 * np.pi**2 + delta**2)
    assert n >= 8 and abs(measured / zeta - 1) < 0.01, (measured, n)


GRAVITY_TUBE = """kind = "beam"
planes = 2
[material]
E = 2.0e11
rho = 8000.0
[section]
rect = { b = 0.02, h = 0.04 }
[geometry]
L = 1.0
[ends]
left = "pinned"
right = "pinned"
[[loads]]
LOAD
direction = [0.0, -1.0]
[damping]
modal = 0.9
[mesh]
J = 20
[time]
dt = 1e-4
T = 0.5
"""


def test_gravity_pulls_along_its_direction_in_two_planes(tmp_path):
    """direction = [0, -1] moved a distributed load down in w and the beam's weight up
    (1.533e-4 m above against below): gravity's direction was read as up."""
    from skfem_beam.scenefile import load as load_scene
    w = {}
    for name, load in (("gravity", "gravity = 9.81"),
                       ("weight", "distributed = true\nvalue = 62.784")):    # ρAg, N/m
        path = tmp_path / f"{name}.toml"
        path.write_text(GRAVITY_TUBE.replace("LOAD", load))
        scene = load_scene(path)
        r = solve(beam_system(scene.problem), 1e-4, 0.5, progress=False)
        w[name] = r.observed["tip_displacement_w"][-1]      # midspan (pinned–pinned)
    assert w["gravity"] < 0 and w["gravity"] == pytest.approx(w["weight"], rel=1e-6)
