"""The contact-law protocol: the registry, law objects of the user's, the start step."""
import re
import runpy
from pathlib import Path

import numpy as np
import pytest

from skfem_beam import InputError, beam_system, scenes, solve
from skfem_beam.contact import LAWS, SOLVERS, STEP_SOLVERS, ContactLaw, resolve
from skfem_beam.contact.penalty import Penalty
from skfem_beam.contact.restitution import Restitution
from skfem_beam.methods import Penalty as PenaltyMethod, PositionLevel

DESIGN_DOC = Path(__file__).parents[1] / "docs" / "design.md"


def test_the_documented_law_runs_and_agrees_with_projection(tmp_path):
    """The example of docs/design.md, run as written: the pipe hits its upper stop first
    (t ≈ 0.088 s); the lower-only law is the projection, to the last bit, until then."""
    code = re.search(r"## Adding a contact law.*?```python\n(.*?)```", DESIGN_DOC.read_text(),
                     re.S).group(1)
    script = tmp_path / "law_example.py"
    script.write_text(code)
    mine = runpy.run_path(str(script))["result"]
    ref = solve(beam_system(scenes.point_stops()), dt=5e-5, T=0.2, method=PositionLevel("projection"))
    tip, tip_ref = mine.observed["tip_displacement"], ref.observed["tip_displacement"]
    first_upper = np.flatnonzero(tip_ref >= 0.1)[0]
    assert 0.08 < mine.t[first_upper] < 0.1
    assert np.array_equal(tip[:first_upper], tip_ref[:first_upper])
    assert tip.max() > 0.1 + 1e-3           # no upper stop in the user's law


def test_registry_names_and_auto():
    assert set(STEP_SOLVERS) == {"projection", "active-set", "osqp", "daqp", "round-hole",
                                 "round-hole-friction", "pdas-sparse", "osqp-sparse",
                                 "clarabel-sparse"}
    assert set(LAWS) == {"penalty", "restitution"}           # named by their parameters
    assert "penalty" not in SOLVERS and "auto" in SOLVERS
    for name in ("projection", "active-set", "osqp", "daqp"):
        assert resolve(name).name == name
    assert isinstance(resolve("auto", stiffness=1e3), Penalty)
    system = beam_system(scenes.flat_obstacles())
    assert solve(system, 1e-3, 0.01).solver == "active-set"       # coupled
    assert solve(beam_system(scenes.point_stops()), 5e-5, 0.001).solver == "projection"


@pytest.mark.parametrize("method, word", [
    (lambda: PositionLevel("simplex"), "simplex"),
    (lambda: PositionLevel("penalty"), "stiffness"),
    (lambda: "osqp", "a method object is needed"),
    (lambda: PositionLevel("projection"), "decoupled"),
    (lambda: PenaltyMethod(-1.0), "stiffness=-1"),
])
def test_bad_laws_are_refused_by_name(method, word):
    """One route: solve() takes a method object; each refusal names the bad word."""
    with pytest.raises(InputError, match=word):
        solve(beam_system(scenes.flat_obstacles()), 1e-3, 0.01, method=method())


class _PythonActiveSet(ContactLaw):
    """A law solved in Python (like OSQP and daqp): the compiled active set, step by step."""
    name = "python-active-set"

    def solver(self, step):
        from skfem_beam.contact.active_set import box_qp

        class Solve:
            state = np.zeros(step.D.shape[0], np.int8)

            def solve(self, x_free, y_free, lo, hi):
                mu = np.zeros(y_free.size)
                return mu, box_qp(step.D, y_free, step.lo, step.hi, self.state, mu)
        return Solve()


def test_a_python_law_gives_the_compiled_run_and_solves_the_start_step():
    """A scene whose first step is in contact (v0 carries the tip 2 cm in one step, the
    obstacles are 1 cm away): the start step uses the chosen law, which must agree with
    the compiled one and hold the obstacles."""
    from skfem_beam.problem import InitialState
    pb = scenes.flat_obstacles(J=20)
    pb = type(pb)(pb.beam, pb.obstacles, load=pb.load, J=20,
                  initial=InitialState(v0=lambda x: -20.0 * (x / 10) ** 2))
    system = beam_system(pb)
    a = solve(system, 1e-3, 0.3, method=PositionLevel("active-set"))
    b = solve(system, 1e-3, 0.3, method=PositionLevel(_PythonActiveSet()))
    assert b.solver == "python-active-set" and a.impacts == b.impacts > 0
    assert b.observed["tip_displacement"][1] == pytest.approx(-0.01, rel=1e-13)  # the stop
    assert b.max_nodal_violation <= 1e-15
    # the warm starts differ (the Python law keeps its start step's): round-off grows to
    # ~1e-10 over the run, as between any two exact solvers on this scene
    scale = np.abs(a.frames_u).max()
    assert np.abs(a.frames_u - b.frames_u).max() <= 1e-10 * scale   # not chaotic: ~1e-10
    assert a.contact_force[1:].any()
    assert np.abs(a.contact_force - b.contact_force).max() <= 1e-9 * np.abs(a.contact_force).max()


def test_restitution_zero_is_the_scheme_bit_for_bit():
    system = beam_system(scenes.flat_obstacles())
    a = solve(system, 1e-3, 0.5)
    b = solve(system, 1e-3, 0.5, method=PositionLevel(Restitution(0.0)))
    assert np.array_equal(a.frames_u, b.frames_u) and a.impacts == b.impacts


@pytest.mark.parametrize("e", [0.0, 0.3, 0.7, 1.0])
def test_restitution_of_a_rigid_mass_is_e(e):
    """One mass, no spring, released towards a wall at speed 1: after the impact it
    leaves at speed e (Paoli–Schatzman on a rigid body), and the energy keeps e²."""
    import scipy.sparse as sp
    from skfem_beam import SemiDiscrete
    one = sp.csr_matrix(np.ones((1, 1)))
    system = SemiDiscrete(M=one, K=sp.csr_matrix((1, 1)), C=one, lo=np.zeros(1),
                          hi=np.array([np.inf]), x_contact=np.zeros(1), loads=np.zeros((1, 0)),
                          load_time=[], u0=np.array([0.0123]), v0=np.array([-1.0]),
                          observe={"u": np.ones(1)})
    r = solve(system, 1e-3, 0.1, method=PositionLevel(Restitution(e) if e else "auto"))
    v = r.velocity["u"]
    assert r.impacts == 1
    # against the approach speed |v0| = 1 m/s and ½|v0|² (e = 0: both to round-off)
    v0 = abs(system.v0[0])
    assert v[-1] == pytest.approx(e * v0, abs=1e-12 * v0)
    assert r.energy[-1] == pytest.approx(0.5 * e**2 * v0**2, abs=2e-12 * 0.5 * v0**2)


@pytest.mark.parametrize("kw, word", [
    ({"restitution": 1.5}, "restitution=1.5"), ({"restitution": -0.1}, "restitution=-0.1"),
    ({"restitution": 0.5, "stiffness": 1e3}, "stiffness"),
    ({"restitution": 0.5, "law": "osqp"}, "osqp"), ({"law": "restitution"}, "coefficient"),
])
def test_restitution_refusals(kw, word):
    with pytest.raises(InputError, match=word):
        resolve(**kw)
