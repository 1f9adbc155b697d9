"""The second paper's scenes end to end: constraints, penetration, energy."""
import csv
import json

import numpy as np
import pytest

from conftest import exit_code
from skfem_beam.cases import convex_obstacles, energy_decay, flat_obstacles


def run_case(module, tmp_path, *args):
    out = tmp_path / "run"
    return exit_code(module.main, ["--out", str(out), *args]), out


@pytest.mark.usefixtures("charts")
@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_flat_obstacles_defaults(tmp_path, element):
    code, out = run_case(flat_obstacles, tmp_path, "--element", element)
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["steps"] == 1000 and s["solver"] == "active-set" and s["impacts"] > 50
    assert s["max_nodal_violation"] <= 1e-10
    # penetration between nodes: the second paper's Table 3 order or below
    assert 0 < s["max_penetration"] < 2e-3
    assert {"summary.json", "timeseries.csv", "tip_displacement.png", "beam_shapes.png"} \
        <= {p.name for p in out.iterdir()}


def test_penetration_falls_as_J_grows(tmp_path):
    pen = []
    for J in (40, 80, 160):
        (tmp_path / str(J)).mkdir()
        code, out = run_case(convex_obstacles, tmp_path / str(J), "--J", str(J), "--T", "0.6")
        assert code == 0
        pen.append(json.loads((out / "summary.json").read_text())["max_penetration"])
    assert pen[0] > 2 * pen[1] > 4 * pen[2] > 0


def test_flat_obstacles_needs_a_node_at_half_length(tmp_path, capsys):
    code, out = run_case(flat_obstacles, tmp_path, "--J", "41")
    assert code == 2 and "break point x=5" in capsys.readouterr().err
    assert not out.exists()


def test_energy_decay_only_at_impacts(tmp_path):
    code, out = run_case(energy_decay, tmp_path, "--T", "0.5")
    assert code == 0
    rows = list(csv.DictReader(open(out / "energy.csv")))
    for key in ("energy_beta_0.5", "energy_beta_0.25"):
        E = np.array([float(r[key]) for r in rows])
        dE = np.diff(E)
        assert dE.max() <= 1e-10 * E[0]          # never increases
        assert E[-1] < 0.99 * E[0]               # and drops at impacts
        steady = np.abs(dE) <= 1e-10 * E[0]
        assert steady.mean() > 0.5               # constant between impacts


def test_energy_decay_compares_its_own_law_and_reports_an_unstable_comparison(tmp_path,
                                                                            capsys):
    """energy.csv: the comparison is the run's own law at --compare-beta (penalty: its
    springs, not exact contact; the column beside it is the run's), none where the βs
    agree; an unstable comparison (β = 0 above its step limit) is one warning and NaN from
    its end, the run's folder complete; Moreau–Jean has no β to compare."""
    for name, args, columns in (
            ("penalty", ["--law", "penalty", "--compare-beta", "0.5"],
             ["t", "energy_beta_0.25", "energy_beta_0.5"]),
            ("same", ["--restitution", "0.5", "--compare-beta", "0.5"],
             ["t", "energy_beta_0.5"]),
            ("unstable", ["--compare-beta", "0"], ["t", "energy_beta_0.5", "energy_beta_0"]),
            ("mj", ["--law", "moreau-jean"], ["t", "energy_theta_0.5"]),
            # βs that print alike keep two columns (the comparison replaced the run's)
            ("close", ["--beta", "0.3", "--compare-beta", "0.3000001"],
             ["t", "energy_beta_0.3", "energy_beta_0.3000001"])):
        (tmp_path / name).mkdir()
        code, out = run_case(energy_decay, tmp_path / name, "--T", "0.2", *args)
        assert code == 0, name
        rows = list(csv.DictReader(open(out / "energy.csv")))
        assert list(rows[0]) == columns, name
        assert json.loads((out / "summary.json").read_text())["status"] == "success"
        own = np.array([float(r[columns[1]]) for r in rows])
        series = list(csv.DictReader(open(out / "timeseries.csv")))
        assert own[-1] == pytest.approx(float(series[-1]["energy"]), rel=1e-12), name
        if name == "unstable":
            other = np.array([float(r["energy_beta_0"]) for r in rows])
            assert np.isnan(other[-1]) and np.isfinite(other[0])
            assert "--compare-beta 0: that run is unstable" in capsys.readouterr().err
    code, out = run_case(energy_decay, tmp_path, "--law", "moreau-jean", "--compare-beta", "0.3")
    assert code == 2 and "Moreau–Jean has no β to compare" in capsys.readouterr().err
    assert not out.exists()


MESHES = __import__("pathlib").Path(__file__).parents[1] / "meshes"


def test_mesh_files_and_non_uniform_meshes(tmp_path, capsys):
    import meshio
    code, out = run_case(flat_obstacles, tmp_path, "--mesh", str(MESHES / "pipe10_J80.msh"),
                         "--T", "0.1")
    assert code == 0 and json.loads((out / "summary.json").read_text())["J"] == 80
    # non-uniform, refined towards the clamp, with the break point x = 5 as a node
    x = np.r_[10 * np.linspace(0, 0.5, 16) ** 1.5 / 0.5 ** 0.5, np.linspace(5, 10, 21)[1:]]
    path = tmp_path / "graded.vtu"
    meshio.write(path, meshio.Mesh(np.c_[x, 0 * x, 0 * x],
                                   [("line", np.c_[np.arange(x.size - 1), np.arange(1, x.size)])]))
    (tmp_path / "g").mkdir()
    code, out = run_case(flat_obstacles, tmp_path / "g", "--mesh", str(path), "--T", "0.1")
    s = json.loads((out / "summary.json").read_text())
    assert code == 0 and s["J"] == x.size - 1 and s["max_nodal_violation"] <= 1e-12
    # the same mesh without the break point is refused, in one line
    y = x[np.abs(x - 5) > 1e-9]
    meshio.write(path, meshio.Mesh(np.c_[y, 0 * y, 0 * y],
                                   [("line", np.c_[np.arange(y.size - 1), np.arange(1, y.size)])]))
    (tmp_path / "h").mkdir()
    code, out = run_case(flat_obstacles, tmp_path / "h", "--mesh", str(path))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "break point x=5" in err[-1] and not out.exists()


def test_readme_main_job_from_an_empty_folder(tmp_path, monkeypatch):
    """The README's first command: no flags, run where no out/ exists yet."""
    monkeypatch.chdir(tmp_path)
    assert exit_code(flat_obstacles.main, []) == 0
    s = json.loads((tmp_path / "out" / "flat_obstacles" / "summary.json").read_text())
    assert s["case"] == "flat_obstacles" and s["steps"] == 1000 and s["status"] == "success"


def test_springs_that_gain_energy_at_fixed_obstacles_are_warned_of(tmp_path, capsys):
    """energy_decay (f = 0, fixed obstacles) with the default penalty springs: ½E_β
    166.8 → 466.6, the springs' work +299.7, reported as success without a word; now one
    warning line.  Point stops, driven by their support (whose lifted frame leaves the
    stops fixed): the springs' work +5.98 in 0.3 s against 1.38 + 3.43 given, once not
    warned of because a load did work too; exact contact's work there is ≤ 0."""
    from skfem_beam.cases import point_stops
    code, out = run_case(energy_decay, tmp_path, "--law", "penalty", "--compare-beta", "-1",
                         "--format", "none")
    err = capsys.readouterr().err
    assert code == 0 and "warning: the penalty springs did 299.7 of work, 180 % of the " \
        "energy given to the beam (166.8: its start's and the loads' work)" in err
    (tmp_path / "ps").mkdir()
    code, out = run_case(point_stops, tmp_path / "ps", "--law", "penalty", "--T", "0.3",
                         "--format", "none")
    assert code == 0 and "warning: the penalty springs did 5.976 of work, 124 % of the " \
        "energy given to the beam (4.806" in capsys.readouterr().err
