"""A fresh install: the first run compiles (the law in a child process beside the loop, see
contact.base.Compiled.compile_aside), says so once on stderr, and computes what a warm run
computes; the second run loads everything from numba's cache and says nothing."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import skfem_beam

NOTICE = "compiling numerical kernels (first run only)"


def test_cold_then_warm_run_same_files_one_notice(tmp_path):
    shutil.copytree(Path(skfem_beam.__file__).parent, tmp_path / "skfem_beam",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(tmp_path)
    runs = []
    for name in ("cold", "warm"):   # the active set (coupled obstacles): the main job's law
        p = subprocess.run([sys.executable, "-m", "skfem_beam.cases.flat_obstacles", "--T", "0.1",
                            "--format", "none", "--out", str(tmp_path / name)],
                           cwd=tmp_path, env=env, capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        runs.append(p.stderr)
    assert runs[0].count(NOTICE) == 1 and NOTICE not in runs[1], runs
    # a run without holes or massless rows compiles none of their code (kernels.run_steps
    # prunes it): numba's cache, which holds every function compiled, has none of it
    cached = {f.name.split("-")[0] for f in (tmp_path / "skfem_beam").rglob("*.nbi")}
    assert "kernels.run_steps" in cached, cached
    assert not {"kernels.hole_kinematics", "kernels.massless_force",
                "kernels.massless_work"} & cached, cached
    for f in ("timeseries.csv", "impacts.csv"):
        assert (tmp_path / "cold" / f).read_bytes() == (tmp_path / "warm" / f).read_bytes(), f


CALLEES_CHILD = """
from skfem_beam import aside, beam_system, scenes, solve
from skfem_beam.methods import PositionLevel
from skfem_beam.scheme.kernels import CALLEES
child = aside.start(CALLEES)
assert child is not None and child.wait() == 0, "the child failed"
solve(beam_system(scenes.flat_obstacles(J=8)), dt=1e-3, T=0.05, method=PositionLevel("active-set"))
for f, sig in CALLEES:   # loaded from the child's cache entry, compiled for no other types
    print(f.py_func.__name__, sum(f.stats.cache_hits.values()),
          sum(f.stats.cache_misses.values()), len(f.signatures))
"""


def test_the_callees_compiled_aside_are_the_loops(tmp_path):
    """kernels.CALLEES, which a fresh install compiles in a child (skfem_beam.aside) while
    run_steps compiles, carry the types run_steps calls them with: the loop's compile then
    loads each from the child's cache entry instead of compiling it again."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    p = subprocess.run([sys.executable, "-c", CALLEES_CHILD], env=env, capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    rows = [line.split() for line in p.stdout.splitlines()]
    assert [r[0] for r in rows] == ["rows_matvec", "csr_product", "rows_dot", "write_event",
                                    "energy_beta"], p.stdout
    assert all(r[1:] == ["1", "0", "1"] for r in rows), p.stdout
