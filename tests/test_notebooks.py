"""The notebooks in notebooks/ run from scratch and show what their text says.

Each notebook is executed with nbclient in a fresh ``python3`` kernel whose working
directory is a temporary folder (nothing lands in the repository); the notebook keeps
the numbers it is about in a dict ``key_numbers``, which a cell appended here prints as
JSON, and the checks below read them back.  The committed notebooks must carry no outputs
(``python notebooks/strip.py`` strips them).
"""
from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"
MARK = "KEY_NUMBERS "
REPORT = f"import json\nprint({MARK!r} + json.dumps(key_numbers))"


def check_point_stops(k):
    assert 0 < k["omega1_rel_error_J19"] < 1e-6        # from above, tiny at J = 19
    assert 3.5 < k["omega1_order"] < 4.5                # Hermite eigenvalues: O(h⁴)
    assert abs(k["first_contact_time"] - 0.0879) < 2e-3
    assert k["max_nodal_violation_contact"] == 0.0
    assert k["contact_penetration"] == 0.0
    assert 1e-5 < k["penalty_penetration"] < 1e-4       # 1e8 N/m penetrates ~3e-5 m
    assert k["energy_free_step_change"] < 1e-9          # conserved between impacts
    assert 0.05 < k["energy_loss_relative"] < 0.9       # and dropping at impacts
    assert k["dt_prop31_paper"] == pytest.approx(3.3469e-6, rel=1e-4)   # the paper's number
    assert k["stable_below_limit"] is True
    assert k["unstable_above_limit"] is True


def check_longitudinal(k):
    assert k["tip_difference_hermite_bspline"] < 5e-3
    for scene in ("convex", "flat"):
        for element in ("hermite", "bspline"):
            assert 1.7 < k[f"order_{scene}_{element}"] < 3.0, (scene, element)
    assert 1e-4 < k["penetration_convex_hermite_J40"] < 1e-3
    assert k["energy_free_step_change"] < 1e-8
    assert k["energy_max_rise"] < 1e-9
    assert k["energy_loss_relative_min"] > 0.1


def check_impacting_bar(k):
    assert 1e-3 < k["rigid_l2_u0"] < 1e-2
    assert k["rigid_l2_uL"] < 2e-3
    assert k["elastic_l2_u0"] < 3e-3
    assert k["elastic_l2_uL"] < 1e-3
    assert k["rigid_penetration"] <= 1e-12
    # β = 0, lumped, Δt = h: exact but for the released end node's Nyquist staircase
    assert k["explicit_courant1_rigid_l2_uL"] < 1e-12
    assert k["explicit_courant1_rigid_l2_force"] < 1e-12
    assert k["explicit_courant1_rigid_max_u0_over_h"] == pytest.approx(1.0, abs=1e-9)
    assert k["penalty_penetration"] > 1e-4
    assert k["ex2_rigid_second_impact"] == pytest.approx(3 + math.sqrt(2), abs=0.01)
    assert k["ex2_elastic_second_impact"] == pytest.approx(4.454, abs=0.01)
    assert 0 < k["energy_loss_ex1_rigid"] < 0.01
    assert abs(k["energy_loss_ex1_elastic"]) < 1e-3


CHECKS = {
    "01_point_stops.ipynb": check_point_stops,
    "02_longitudinal_obstacles.ipynb": check_longitudinal,
    "03_impacting_bar.ipynb": check_impacting_bar,
}


def test_every_notebook_is_checked():
    assert sorted(p.name for p in NOTEBOOKS.glob("*.ipynb")) == sorted(CHECKS)


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_committed_notebook_has_no_outputs(name):
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code
    for cell in code:
        assert cell.outputs == [], f"{name}: outputs committed (run python notebooks/strip.py)"
        assert cell.execution_count is None, f"{name}: execution count committed"
    assert nb.metadata.kernelspec.name == "python3"


def execute(path: Path, workdir: Path) -> dict:
    """Run the notebook from scratch in ``workdir``; return its ``key_numbers``."""
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(REPORT))
    # the kernelspec's argv is "python": make it this interpreter (venv or not)
    env = dict(os.environ, PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""),
               PYDEVD_DISABLE_FILE_VALIDATION="1")
    client = NotebookClient(nb, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(workdir)}})
    client.execute(env=env)         # raises CellExecutionError on the first failing cell
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
              if o.output_type == "error"]
    assert not errors, errors
    text = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.output_type == "stream")
    line = next(ln for ln in text.splitlines() if ln.startswith(MARK))
    return json.loads(line[len(MARK):])


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_notebook_runs_from_scratch(name, tmp_path):
    before = sorted(p.name for p in NOTEBOOKS.iterdir())
    key_numbers = execute(NOTEBOOKS / name, tmp_path)
    assert sorted(p.name for p in NOTEBOOKS.iterdir()) == before   # nothing written beside it
    CHECKS[name](key_numbers)
