"""One method object per class (skfem_beam.methods): its defaults and checks, solve()
reaching every class, and every method's run checkpointing and resuming bit for bit
(Moreau–Jean and the laws solved in Python included), the latter with moving bounds."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skfem_beam import methods, scenes
from skfem_beam.errors import InputError
from skfem_beam.methods import MoreauJean, Penalty, PositionLevel
from skfem_beam.scheme import Stepping, drive, solve
from skfem_beam.scenefile import load
from skfem_beam.scheme.solve import moreau_jean
from skfem_beam.semidiscrete import beam_system
from skfem_beam.problem import Beam, BeamProblem, Obstacles

from test_motion import observe_constraints, span_problem

PS = [sys.executable, "-m", "skfem_beam.cases.point_stops", "--dt", "1e-4",
      "--flush-every", "150", "--format", "none"]


def test_defaults_and_checks():
    assert PositionLevel().default_beta == 0.5 and Penalty(1e6).default_beta == 0.25
    assert PositionLevel().beta == 0.5 and Penalty(1e6).beta == 0.25     # None: the default
    assert PositionLevel(beta=0.25).beta == 0.25 and not hasattr(MoreauJean(), "beta")
    assert methods.make("position", params={"beta": 0.3}).beta == 0.3
    assert methods.make("moreau-jean", params={"beta": 0.3}) == MoreauJean()   # no β
    assert methods.default_beta(MoreauJean(), "bar") == 0.25
    for bad, word in [(lambda: PositionLevel(restitution=1.5), "restitution=1.5 must lie"),
                      (lambda: PositionLevel("simplex"), "solver='simplex' is not one of"),
                      (lambda: Penalty(0.0), "stiffness=0 must be > 0"),
                      (lambda: MoreauJean(theta=0.2), "theta=0.2 must lie in [1/2, 1]"),
                      (lambda: PositionLevel(beta=0.7), "beta=0.7 must lie in [0, 1/2]"),
                      (lambda: Penalty(1.0, beta=-0.1), "beta=-0.1 must lie in [0, 1/2]"),
                      (lambda: methods.make("moreau-jean", params={"beta": 0.6}), "beta=0.6"),
                      (lambda: methods.make("moreau-jean", "osqp"), "does not apply"),
                      (lambda: methods.make("penalty", restitution=0.5, stiffness=1.0),
                       "cannot be combined with stiffness"),
                      # from Python the lines name the keywords, not the command's flags
                      (lambda: methods.make("lagrange"), "law='lagrange' is not one of"),
                      (lambda: methods.make("penalty"),
                       "law=penalty needs the springs' stiffness: stiffness=K")]:
        with pytest.raises(InputError, match=word.replace("[", r"\[").replace("(", r"\(")):
            bad()


def test_penalty_stiffness_in_newtons_is_converted_once():
    """Penalty(k N/m) on the papers' pipe (ρS known) is the law Penalty(k/ρS, equation_units=True)
    gives, bit for bit."""
    system = beam_system(scenes.point_stops())
    k = 1e7
    a = solve(system, 5e-5, 0.15, 0.25, method=Penalty(k))      # beta: the method's, shorthand
    b = solve(system, 5e-5, 0.15, method=Penalty(k / scenes.PIPE_RHO_S, equation_units=True,
                                                 beta=0.25))
    assert a.impacts > 0 and np.array_equal(a.energy, b.energy)
    assert np.array_equal(a.contact_force, b.contact_force)


def test_solve_reaches_moreau_jean_and_restitution():
    system = beam_system(scenes.point_stops())
    mj = solve(system, 5e-5, 0.05, method=MoreauJean(0.5, 0.0))
    assert mj.solver == "moreau-jean" and mj.theta == 0.5 and mj.beta is None
    old = moreau_jean(system, 5e-5, 0.05)
    assert np.array_equal(mj.energy, old.energy)
    e = solve(system, 5e-5, 0.05, method=PositionLevel(restitution=0.5))
    assert e.solver == "restitution" and e.theta is None and e.beta == 0.5


CASES = [MoreauJean(), MoreauJean(1.0, 0.5), PositionLevel("osqp"), PositionLevel("daqp"),
         PositionLevel("active-set")]


@pytest.mark.parametrize("method", CASES, ids=lambda m: f"{m.name}-{getattr(m, 'solver', '')}")
def test_a_restored_run_goes_on_bit_for_bit(method):
    """Checkpoint at step 1200 of 3000, restore into a new run, drive to the end: every
    row after the checkpoint, every impact event and the last state are the
    uninterrupted run's, to the bit."""
    system = beam_system(scenes.point_stops())
    stepping = Stepping(5e-5, 0.15)
    a = method.build(system, stepping)
    drive(a, chunk=150)
    b = method.build(system, stepping)
    b.advance(1200)
    ck = b.checkpoint()
    c = method.build(system, stepping)
    c.restore(ck)
    drive(c, chunk=150)
    ra, rc = a.result(), c.result()
    assert ra.impacts > 5
    assert np.array_equal(ra.energy[1201:], rc.energy[1201:])
    assert np.array_equal(ra.contact_force[1201:], rc.contact_force[1201:])
    assert np.array_equal(a.u_cur, c.u_cur) and np.array_equal(a.u_prev, c.u_prev)
    for k in ra.impact_events:
        assert np.array_equal(ra.impact_events[k], rc.impact_events[k], equal_nan=True), k


@pytest.mark.parametrize("extra", [["--law", "moreau-jean"], ["--solver", "osqp"],
                                   ["--solver", "daqp"]])
def test_command_line_extension_equals_the_longer_run(tmp_path, extra):
    """A finished run extended by --resume DIR --T longer (restored from its final
    checkpoint) writes the timeseries.csv and impacts.csv of the longer run, byte for
    byte: Moreau–Jean, OSQP and daqp checkpoint and resume like the compiled laws."""
    a, b = tmp_path / "a", tmp_path / "b"
    subprocess.run(PS + extra + ["--T", "0.1", "--checkpoint-every", "0", "--out", str(a)],
                   check=True, capture_output=True)
    subprocess.run(PS + ["--resume", str(a), "--T", "0.2"], check=True, capture_output=True)
    subprocess.run(PS + extra + ["--T", "0.2", "--out", str(b)], check=True,
                   capture_output=True)
    for name in ("timeseries.csv", "impacts.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    s = json.loads((a / "summary.json").read_text())
    assert s["status"] == "success" and s["steps"] == 2000 and s["impacts"] > 0


@pytest.mark.parametrize("solver", ["osqp", "daqp"])
def test_python_laws_take_moving_bounds(solver):
    """Obstacles carried by a shaken support (bounds moving every step): OSQP and daqp
    give the active set's run to round-off and hold the moving bounds at the nodes."""
    s = observe_constraints(beam_system(span_problem(True, "paper")))
    ref = solve(s, dt=1e-4, T=0.3, method=PositionLevel("active-set"))
    r = solve(s, dt=1e-4, T=0.3, method=PositionLevel(solver))
    assert ref.impacts > 3 and r.impacts == ref.impacts
    y = np.column_stack([r.observed[f"y{i}"] for i in range(s.C.shape[0])])
    shift = np.outer(s.bound_motion(r.t), s.bound_shift)
    assert np.maximum(s.lo + shift - y, y - s.hi - shift).max() <= 1e-12
    assert np.abs(r.observed["y0"] - ref.observed["y0"]).max() <= 1e-10


@pytest.mark.parametrize("solver", ["osqp", "daqp"])
def test_python_laws_killed_after_a_checkpoint_resume_byte_for_byte(tmp_path, solver):
    """SIGKILL after the last chunk (test hook SKFEM_BEAM_KILL_AT), so the resume starts
    from the last periodic checkpoint, mid-run: the timeseries.csv and impacts.csv of an
    uninterrupted run of the same solver."""
    import os
    import signal
    args = PS + ["--solver", solver, "--T", "0.15", "--checkpoint-every", "0"]
    ref, out = tmp_path / "ref", tmp_path / "out"
    subprocess.run(args + ["--out", str(ref)], check=True, capture_output=True)
    killed = subprocess.run(args + ["--out", str(out)], capture_output=True,
                            env={**os.environ, "SKFEM_BEAM_KILL_AT": "last-chunk"})
    assert killed.returncode == -signal.SIGKILL
    with np.load(out / "checkpoint.npz") as ck:
        assert 0 < int(ck["n"]) < 1500 and "solver_active" in ck.files
    subprocess.run(PS + ["--resume", str(out)], check=True, capture_output=True, timeout=120)
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name


def test_theta_reaches_moreau_jean_from_the_command_line_and_a_scene_file(tmp_path):
    """--theta and [contact] theta set Moreau–Jean's θ (summary "theta"); θ = 1 (implicit
    Euler) dissipates what θ = 1/2 keeps, so it ends with less energy; a θ given to a
    β-scheme or outside [1/2, 1] is one line, exit 2, nothing written."""
    energy = {}
    for theta in ("0.5", "1.0"):
        out = tmp_path / f"mj{theta}"
        subprocess.run(PS + ["--T", "0.1", "--law", "moreau-jean", "--theta", theta,
                             "--out", str(out)], check=True, capture_output=True)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["theta"] == float(theta) and summary["beta"] is None
        energy[theta] = summary["energy_final"]
    assert energy["1.0"] < 0.99 * energy["0.5"], energy
    scene = Path(methods.__file__).parent / "scene_files" / "point_stops.toml"
    assert load(scene, ['contact.law="moreau-jean"', "contact.theta=1.0"]).method \
        == MoreauJean(1.0)
    for argv, word in ((["--theta", "0.7"], "--theta 0.7 is Moreau–Jean's θ"),
                       (["--law", "moreau-jean", "--theta", "0.2"], "must lie in [1/2, 1]")):
        p = subprocess.run(PS + ["--T", "0.01", "--out", str(tmp_path / "bad")] + argv,
                           capture_output=True, text=True)
        assert p.returncode == 2 and p.stderr.count("\n") == 1 and word in p.stderr, p.stderr
        assert not (tmp_path / "bad").exists()


def test_a_penalty_in_newtons_per_metre_needs_the_beams_mass_per_length():
    """A beam known by k² alone has no ρS to divide N/m by: Penalty(1e8) was taken per unit
    mass silently (8.4× softer on the pipe); it is one line, and equation_units=True runs."""
    import pytest
    from skfem_beam import Beam, BeamProblem, InputError, Obstacles, beam_system, solve
    from skfem_beam.methods import Penalty
    problem = BeamProblem(Beam(1.501, k2=282.84), Obstacles.point_stops(1.501, -0.1, 0.1),
                          J=10)
    with pytest.raises(InputError, match=r"Penalty stiffness=100000000.0 is in N/m, which "
                                         r"needs the beam's mass per length ρS"):
        solve(beam_system(problem), 1e-4, 0.01, method=Penalty(1e8), progress=False)
    assert solve(beam_system(problem), 1e-4, 0.01, progress=False,
                 method=Penalty(1e8, equation_units=True)).success


def test_api_numbers_written_as_strings_are_refused():
    """float("0.2") took a string silently (dt, T, L, k2, a load, a support's amplitude,
    which ended in numpy's UFuncTypeError inside solve): one line each, as J='19' had."""
    from skfem_beam import Load, Support
    for build, word in ((lambda: Beam("1.5", k2=282.84, rho_S=0.1), "L='1.5' is a string"),
                        (lambda: Support(amplitude="0.2", omega=10.0),
                         "amplitude='0.2' is a string"),
                        (lambda: Load.point(1.0, "0.5"), "'0.5' is a string"),
                        (lambda: Obstacles.point_stops(1.5, "-0.1", 0.1), "g1='-0.1' must be")):
        with pytest.raises(InputError) as e:
            build()
        assert word in str(e.value), str(e.value)


def test_a_beta_beside_a_method_that_has_its_own_or_none_is_refused():
    """solve(beta=) beside PositionLevel(beta=0.3) ran with 0.25, beside Moreau–Jean it
    was dropped: one line each; the same β twice, or β with a method at its default
    (which it sets: the shorthand), runs."""
    system = beam_system(BeamProblem(Beam(1.0, k2=1.0), Obstacles.point_stops(1.0, -0.1, 0.1),
                                     J=4))
    for method, word in ((PositionLevel(beta=0.3), "beta=0.25 beside the method's beta=0.3"),
                         (MoreauJean(theta=0.5), "Moreau–Jean has no β")):
        with pytest.raises(InputError) as e:
            solve(system, 1e-3, 2e-3, beta=0.25, method=method)
        assert word in str(e.value), str(e.value)
    assert solve(system, 1e-3, 2e-3, beta=0.5, method=PositionLevel(beta=0.5)).beta == 0.5
    assert solve(system, 1e-3, 2e-3, beta=0.25, method=PositionLevel()).beta == 0.25
    with pytest.raises(InputError, match="needs one x or more"):
        Obstacles.stops([], -0.1, 0.1)


def test_an_initial_profile_of_the_wrong_shape_is_one_line():
    """InitialState(v0=f) with f(x) of another shape than x ended in numpy's broadcast
    error from inside the projection: one line naming v0 (a scalar still broadcasts)."""
    from skfem_beam import InitialState
    for initial, ok in ((InitialState(v0=lambda x: np.zeros(3)), False),
                        (InitialState(v0=lambda x: 0.0 * x + 0.01), True)):
        problem = BeamProblem(Beam(1.0, k2=1.0), Obstacles.point_stops(1.0, -0.1, 0.1), J=4,
                              initial=initial)
        if ok:
            assert np.abs(beam_system(problem).v0).max() > 0
            continue
        with pytest.raises(InputError, match=r"InitialState v0\(x\) returned shape \(3,\)"):
            beam_system(problem)
