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
