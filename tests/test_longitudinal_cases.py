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
