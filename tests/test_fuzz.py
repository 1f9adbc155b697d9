"""Hostile input, thrown by hypothesis at the API and the command line: every case either
runs with the constraints satisfied and finite energy, or fails with the project's own
error and one clear line — never a traceback, a hang or NaNs in the output."""
import json
import math

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from conftest import exit_code
from skfem_beam import InputError, SolverError, beam_system, scenes, solve
from skfem_beam.cases import point_stops

SETTINGS = settings(max_examples=200, deadline=None, derandomize=True,
                    suppress_health_check=list(HealthCheck))

hostile = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                    st.floats(min_value=-1e3, max_value=1e3),
                    st.sampled_from([0.0, -0.0, 1e-300, 1e300, -1.0]),
                    st.text(max_size=4), st.none(), st.integers(-10**6, 10**6))
plausible = {
    "L": st.floats(0.1, 20), "k2": st.floats(1.0, 1e4), "gap": st.floats(1e-3, 1.0),
    "amplitude": st.floats(-0.5, 0.5), "omega": st.floats(0, 50), "J": st.integers(1, 40),
}


@st.composite
def parameters(draw):
    """Mostly plausible values, each replaced by a hostile one with some probability."""
    p = {k: draw(s) for k, s in plausible.items()}
    for k in list(p):
        if draw(st.integers(0, 5)) == 0:
            p[k] = draw(hostile)
    return p


@SETTINGS
@given(parameters(), st.sampled_from(["hermite", "bspline", "p1", ""]),
       st.one_of(st.floats(0, 0.5), hostile))
# found by hypothesis: scales outside floating-point range, round-off of B-spline coefficients
@example(p={"L": 1.0, "k2": 3.4455121638609e-294, "gap": 1.0, "amplitude": 0.0, "omega": 0.0,
            "J": 1}, element="hermite", beta=0.0)
@example(p={"L": 1.0, "k2": 1.498077612385263e307, "gap": 1.0, "amplitude": 0.0, "omega": 0.0,
            "J": 1}, element="hermite", beta=0.0)
@example(p={"L": 1.0, "k2": 1.0, "gap": 0.001, "amplitude": 3.0, "omega": 96.0, "J": 1},
         element="bspline", beta=0.0)
@example(p={"L": 1.0, "k2": 1.0, "gap": 1.0, "amplitude": 1.9087441698701214e153, "omega": 11.0,
            "J": 6}, element="hermite", beta=0.0)
def test_api_runs_or_refuses(p, element, beta):
    try:
        pb = scenes.point_stops(L=p["L"], k2=p["k2"], gap=p["gap"], amplitude=p["amplitude"],
                                omega=p["omega"], J=p["J"], element=element)
        system = beam_system(pb)
        L = pb.beam.L
        dt = 1e-4 * L**2 / math.sqrt(pb.beam.k2)    # some steps, fewer than 150
        r = solve(system, dt, 100 * dt, beta, frames=5, growth_limit=10.0)
    except (InputError, SolverError) as e:
        assert str(e) and "\n" not in str(e)
        return
    assert r.status in ("success", "unstable")
    assert np.isfinite(r.energy).all() and np.isfinite(r.observed["tip_displacement"]).all()
    if r.status == "success":
        # the stop holds to round-off of the coefficients (a B-spline nodal value sums three)
        gap = abs(float(p["gap"]))
        scale = max(gap, np.abs(r.frames_u[np.isfinite(r.frames_u)]).max(initial=0.0))
        assert np.abs(r.observed["tip_displacement"]).max() <= gap + 1e-13 * scale


flags = st.sampled_from(["--J", "--dt", "--T", "--beta", "--L", "--k2", "--gap", "--amplitude",
                         "--omega", "--element", "--solver", "--method", "--stiffness",
                         "--save-every", "--frames", "--flush-every"])
values = st.one_of(st.sampled_from(["nan", "inf", "-inf", "0", "-1", "1e-300", "abc", "", "1e9",
                                    "0.3", "7", "hermite", "bspline", "osqp", "penalty"]),
                   st.floats(-10, 10).map(repr))


@SETTINGS
@given(st.lists(st.tuples(flags, values), max_size=3))
def test_cli_runs_or_refuses_in_one_line(tmp_path_factory, capsys, pairs):
    out = tmp_path_factory.mktemp("fuzz") / "run"
    argv = ["--T", "0.002", "--dt", "1e-4", "--out", str(out)]
    for flag, value in pairs:
        argv += [f"{flag}={value}"]
    if any(f in ("--dt", "--T") for f, _ in pairs):   # keep runs short: cap the step count
        argv += ["--T", "0.002"] if not any(f == "--T" for f, _ in pairs) else []
    code = exit_code(point_stops.main, argv)
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if not line.startswith("warning:")]
    if code == 0:
        s = json.loads((out / "summary.json").read_text())
        assert s["status"] == "success" and s["max_nodal_violation"] <= 1e-12
        data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
        assert np.isfinite(data.view((float, len(data.dtype)))).all()
    elif code == 4:
        assert json.loads((out / "summary.json").read_text())["status"] == "unstable"
    else:
        assert code in (2, 3) and len(errors) == 1, err
        assert not out.exists() or code == 3
