"""The point-stops case end to end, and its refusals of bad input."""
import csv
import json
import subprocess
import sys

from pathlib import Path

import numpy as np
import pytest

from conftest import SUMMARY_KEYS, assert_refused, exit_code
from skfem_beam.cases import point_stops
from skfem_beam import Beam, BeamProblem, InitialState, InputError, Obstacles, beam_system, solve

MESHES = Path(__file__).parents[1] / "meshes"
CASE = [sys.executable, "-m", "skfem_beam.cases.point_stops"]


def run(args, **kw):
    return subprocess.run(CASE + args, capture_output=True, text=True, timeout=300, **kw)


@pytest.mark.usefixtures("charts")
def test_case_runs_end_to_end(tmp_path):
    out = tmp_path / "run"
    p = run(["--T", "0.3", "--out", str(out)])
    assert p.returncode == 0, p.stderr
    files = {f.name for f in out.iterdir()}
    assert {"summary.json", "timeseries.csv", "tip_displacement.png"} <= files
    s = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(s), SUMMARY_KEYS - set(s)
    assert s["steps"] == 6000 and s["solver"] == "projection" and s["status"] == "success"
    assert s["max_nodal_violation"] == 0.0 and s["impacts"] >= 1
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    assert len(rows) == 6001
    tip = np.array([float(r["tip_displacement"]) for r in rows])
    assert np.abs(tip).max() <= 0.1 * (1 + 1e-15) and tip.max() == pytest.approx(0.1, rel=1e-14)
    assert {"t", "tip_velocity", "energy", "contact_force", "contact_force_N"} <= set(rows[0])


def test_case_matches_the_api(tmp_path, pipe):
    """The command line is a thin shell: same numbers as the API."""
    out = tmp_path / "run"
    assert run(["--T", "0.2", "--out", str(out)]).returncode == 0
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    r = solve(beam_system(pipe), 5e-5, 0.2, 0.5)
    tip = np.array([float(x["tip_displacement"]) for x in rows])
    assert np.abs(tip - r.observed["tip_displacement"]).max() < 1e-12


@pytest.mark.parametrize("args, word", [
    (["--J", "0"], "J=0"), (["--J", "-3"], "J=-3"), (["--J", "x"], "--J"),
    (["--dt", "0"], "dt=0"), (["--dt=-1e-5"], "dt=-1e-05"), (["--dt", "-1e-5"], "dt=-1e-05"),
    (["--L", "0"], "L=0"), (["--k2", "-1"], "k2=-1"), (["--beta", "0.6"], "beta=0.6"),
    (["--beta", "-0.1"], "beta=-0.1"), (["--gap", "0"], "gap=0"), (["--dt", "nan"], "dt=nan"),
    (["--k2", "inf"], "k2=inf"), (["--T", "0"], "T=0"), (["--element", "p2"], "element='p2'"),
    (["--solver", "magic"], "solver='magic'"), (["--method", "springs"], "--method"),
    # J was recorded and the mesh's 19 elements ran
    (["--mesh", str(MESHES / "point_stops_J19.msh"), "--J", "5"], "--J 5 with --mesh"),
])
def test_bad_input_one_line_no_output(tmp_path, capsys, args, word):
    """In-process through the same guard as ``python -m`` (a subprocess each is slow)."""
    assert_refused(point_stops.main, ["--T", "0.01", "--out", str(tmp_path / "run")] + args,
                   word, capsys, tmp_path)


def test_an_empty_out_is_refused(tmp_path, capsys, monkeypatch):
    """--out '' wrote the run's files into the current folder."""
    monkeypatch.chdir(tmp_path)
    assert_refused(point_stops.main, ["--T", "0.01", "--out", ""], "--out '' is empty",
                   capsys, tmp_path)


def test_bad_input_through_python_m(tmp_path):
    p = run(["--J", "0", "--out", str(tmp_path / "run")])
    assert p.returncode == 2 and p.stderr.strip() == "error: J=0 must be a whole number ≥ 1"
    assert not list(tmp_path.iterdir())


def test_unwritable_out_and_existing_results(tmp_path):
    p = run(["--T", "0.01", "--out", "/proc/forbidden/run"])
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1
    out = tmp_path / "run"
    assert run(["--T", "0.01", "--out", str(out)]).returncode == 0
    p = run(["--T", "0.01", "--out", str(out)])
    assert p.returncode == 2 and "--overwrite" in p.stderr
    assert run(["--T", "0.02", "--out", str(out), "--overwrite"]).returncode == 0
    assert json.loads((out / "summary.json").read_text())["steps"] == 400


def test_overwrite_refuses_a_folder_no_run_wrote(tmp_path):
    """--overwrite empties a run's folder, never a folder of the user's own files."""
    (tmp_path / "thesis.tex").write_text("mine")
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "x.csv").write_text("1,2")
    p = run(["--T", "0.01", "--out", str(tmp_path), "--overwrite"])
    assert p.returncode == 2 and p.stderr.strip() == (
        f"error: --out {tmp_path} holds files no run wrote (data, thesis.tex); --overwrite "
        "replaces only a run's folder (one with its summary.json): choose a new or empty "
        "folder")
    assert sorted(q.name for q in tmp_path.rglob("*")) == ["data", "thesis.tex", "x.csv"]


def test_overwrite_keeps_the_users_files_in_a_run_folder(tmp_path):
    """A run's folder holding a user's notes and an export's default .mat: --overwrite
    deleted both without a word; it now names them, exit 2, and removes nothing."""
    out = tmp_path / "run"
    assert run(["--T", "0.01", "--out", str(out)]).returncode == 0
    (out / "notes.txt").write_text("mine")
    (out / "run.mat").write_bytes(b"MATLAB")
    (out / ".git").mkdir()                          # names a run could have written too
    (out / "my_measurements.csv").write_text("1,2")
    before = sorted(q.name for q in out.iterdir())
    p = run(["--T", "0.01", "--out", str(out), "--overwrite"])
    assert p.returncode == 2 and p.stderr.strip() == (
        f"error: --out {out} holds files besides the run's (.git, my_measurements.csv, "
        "notes.txt, …): --overwrite replaces only what a run writes; move them out or choose "
        "another folder")
    assert sorted(q.name for q in out.iterdir()) == before


@pytest.mark.parametrize("mine", ["fields_vtu/my_notes.txt", "runs/my_data.csv",
                                  "orbit_mine.png"])
def test_overwrite_keeps_the_users_files_in_the_run_s_own_subfolders(tmp_path, mine):
    """A user's file inside the run's fields_vtu/ (or a runs/ folder), or named like its
    charts (orbit_*.png): --overwrite deleted it with the run's files, exit 0."""
    out = tmp_path / "run"
    assert run(["--T", "0.01", "--out", str(out)]).returncode == 0
    (out / mine).parent.mkdir(exist_ok=True)
    (out / mine).write_text("mine")
    p = run(["--T", "0.01", "--out", str(out), "--overwrite"])
    assert p.returncode == 2 and mine in p.stderr and p.stderr.count("\n") == 1
    assert (out / mine).read_text() == "mine"


def test_unstable_run_exit_code_and_valid_files(tmp_path):
    out = tmp_path / "run"
    p = run(["--beta", "0.1", "--dt", "1.92e-5", "--T", "0.1", "--out", str(out)])
    assert p.returncode == 4
    assert "warning" in p.stderr and "unstable at step" in p.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "unstable"
    data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    assert np.isfinite(data.view((float, len(data.dtype)))).all()


def test_api_refuses_bad_obstacles_and_initial_state():
    with pytest.raises(InputError, match="g1 ≥ g2"):
        BeamProblem(Beam(1.0, 1.0), Obstacles.point_stops(1.0, 0.1, -0.1), J=4)
    with pytest.raises(InputError, match=r"g1 ≥ g2 at x=0.5 \(g1=0.1, g2=-0.1\)"):
        Obstacles.stops([0.5], 0.1, -0.1)          # where it is built (docs/api.md)
    with pytest.raises(InputError, match="u0 violates"):
        beam_system(BeamProblem(Beam(1.0, 1.0), Obstacles.point_stops(1.0, -0.01, 0.01),
                                initial=InitialState(u0=lambda x: 0.1 * x**2), J=4))
    with pytest.raises(InputError, match="break point"):
        BeamProblem(Beam(1.0, 1.0), Obstacles.point_stops(0.55, -0.01, 0.01), J=4)


def test_penalty_defaults_to_the_papers_beta(tmp_path):
    """β = 1/2 for the contact scheme, 1/4 (trapezoidal) for penalty, unless given."""
    for method, beta in (("contact", 0.5), ("penalty", 0.25)):
        out = tmp_path / method
        code = exit_code(point_stops.main, ["--T", "0.15", "--dt", "1e-5", "--method", method,
                                            "--out", str(out)])
        s = json.loads((out / "summary.json").read_text())
        assert code == 0 and s["beta"] == beta and s["method"] == method
    pen = json.loads((tmp_path / "penalty" / "summary.json").read_text())
    assert pen["impacts"] > 0 and pen["max_penetration"] > 1e-6     # a spring penetrates


def test_a_save_interval_that_does_not_divide_the_steps_says_so(tmp_path):
    """--save-every 7 on 2000 steps: the last row and energy_final are state 1995's; that
    was nowhere said."""
    out = tmp_path / "run"
    p = run(["--T", "0.1", "--save-every", "7", "--format", "none", "--out", str(out)])
    assert p.returncode == 0
    assert "note: a row saved every 7 states does not divide the 2000 steps: the last " \
        "saved row is state 1995 (t=0.09975 s), not the last state" in p.stderr, p.stderr
    data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    assert data["t"][-1] == pytest.approx(0.09975)


def test_an_unstable_runs_summary_agrees_with_its_impacts(tmp_path):
    """Penalty springs at β = 0.2 go unstable at t ≈ 1.03 s: summary.json's impacts and
    penetration disagreed with the impacts.csv it wrote (158 against 185): the rows kept
    ran past the states whose diagnostics were kept."""
    out = tmp_path / "run"
    p = run(["--method", "penalty", "--beta", "0.2", "--dt", "1e-5", "--T", "1.2",
             "--format", "none", "--out", str(out)])
    assert p.returncode == 4, p.stderr
    s = json.loads((out / "summary.json").read_text())
    rows = np.genfromtxt(out / "impacts.csv", delimiter=",", names=True, ndmin=1)
    assert s["status"] == "unstable" and s["impacts"] == rows.size > 100
    assert s["max_penetration"] == rows["max_violation"].max()
    assert rows["t_start"].max() <= s["steps"] * 1e-5 + 1e-12
