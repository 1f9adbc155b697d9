"""A fresh install: the first run compiles (the law in a child process beside the loop, see
contact.base.Compiled.compile_aside), says so once on stderr, and computes what a warm run
computes; the second run loads everything from numba's cache and says nothing."""
import os
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

import skfem_beam
from skfem_beam import beam_system, numba_speed
from skfem_beam.contact import resolve
from skfem_beam.scenefile import example, load

NOTICE = ("compiling numerical kernels (once per method and scene type; later runs load "
          "them)")


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


PLATE_CHILD = """
from skfem_beam import aside
from skfem_beam.linalg import band_solve
from skfem_beam.plate import Plate, plate_space
from skfem_beam.plate.system import PlateInitial, PlateObstacle, Pressure, plate_system
from skfem_beam.scheme import solve
started, start = [], aside.start
def recorded(kernels):
    started.append([getattr(k, "py_func", getattr(k, "func", None)).__name__ for k, _ in kernels])
    return start(kernels)
aside.start = recorded
system = plate_system(plate_space(Plate(nx=4, ny=4)), obstacles=[PlateObstacle(g1=-1e-4)],
                      initial=PlateInitial(static=Pressure(1e4)))
r = solve(system, 1e-4, 2e-3)
print(len(band_solve.signatures), sum(band_solve.stats.cache_misses.values()))
print(" ".join(sum(started, [])), r.solver)
"""


def test_a_plate_run_sends_its_law_aside(tmp_path):
    """A plate builds W without `band_solve` (operators.multi_rhs_W): BetaScheme compiles
    it once the law is set up, for the one signature the start step and the loop call it
    with, so that a fresh install sends the law aside there, before the loop's compile
    (else all compiled on one core); a beam's run compiles no other."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    p = subprocess.run([sys.executable, "-c", PLATE_CHILD], env=env, capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    compiled, law = p.stdout.splitlines()
    assert compiled == "1 1", p.stdout
    assert law == "active_set_kernel active-set", p.stdout


def test_cold_compile_bench_runs_by_its_path():
    """Its listener child runs the file by path, outside the package: it must import."""
    path = Path(skfem_beam.__file__).parent / "bench" / "cold_compile.py"
    p = subprocess.run([sys.executable, str(path), "--help"], capture_output=True, text=True)
    assert p.returncode == 0 and "--one-core" in p.stdout, p.stderr


@pytest.mark.parametrize("name, early", [
    ("tube_trefoil_holes.toml", "broached_hole_kernel"),
    ("tube_round_holes.toml", "round_hole_kernel"),
    ("tube_round_holes_friction.toml", "round_hole_friction_kernel"),
    ("flat_obstacles.toml", None)])
def test_the_law_sent_aside_early_is_the_one_its_setup_picks(name, early):
    """A law whose kernel the step's rows decide (ContactLaw.kernels_for, read before the
    step operators exist) goes aside while they are built: it must be the kernel `setup`
    picks once they are; none where D decides (flat obstacles: projection or active set)."""
    scene = load(example(name))
    system = beam_system(scene.problem)
    scheme = scene.method.build(system, scene.stepping).scheme
    rows = replace(scheme.step, A=None, D=None)
    picked = resolve("auto").kernels_for(rows)
    if early is None:
        assert picked == () and scheme.law.kernel is not None
    else:
        assert [k.func.__name__ for k in picked] == [early]
        assert picked == (scheme.law.kernel,)


NUMBA_SPEED_CHILD = """
import sys
from skfem_beam import aside, beam_system, numba_speed, solve
from skfem_beam.contact.round_hole import broached_hole_kernel
from skfem_beam.scenefile import example, load
from skfem_beam.scheme.kernels import run_steps
if sys.argv[1] == "1":
    numba_speed.apply()
aside.cores = lambda: 1         # the law compiled here, where its LLVM IR can be read
scene = load(example("tube_trefoil_holes.toml"))
r = solve(beam_system(scene.problem), scene.stepping.dt, 20 * scene.stepping.dt)
with open(sys.argv[2], "w") as out:
    out.write(r.solver + "\\n" + "".join(run_steps.inspect_llvm().values()))
    out.write(broached_hole_kernel.cfunc.inspect_llvm())
from numba.core import inline_closurecall, targetconfig
print(inline_closurecall.copy.deepcopy.__module__, targetconfig.TargetConfig.__eq__.__name__)
"""


def test_numba_speed_compiles_the_same_code(tmp_path):
    """numba_speed removes two of numba's costs, not what numba makes: the LLVM IR of the
    loop (every inlined helper) and of a broached hole's law (its overloads and helpers)
    is the same text with and without it, compiled afresh in two processes."""
    texts = []
    for speed in ("0", "1"):
        cache = tmp_path / f"cache{speed}"
        p = subprocess.run([sys.executable, "-c", NUMBA_SPEED_CHILD, speed,
                            str(tmp_path / f"ir{speed}.ll")],
                           env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        assert p.stdout.split() == (["skfem_beam.numba_speed", "quick_equal"] if speed == "1"
                                    else ["copy", "__eq__"]), p.stdout
        texts.append((tmp_path / f"ir{speed}.ll").read_text())
    assert texts[0].startswith("round-hole\n") and len(texts[0]) > 500_000, texts[0][:200]
    assert texts[0] == texts[1]


def test_numba_speed_flags_compare_as_numba_does():
    """The flags' quicker equality and hash give numba's answers (what its typing cache
    finds depends on them), for flags set alike, apart, and to a default's value."""
    from numba.core import compiler, targetconfig
    numba_speed.apply()
    config = targetconfig.TargetConfig
    a, b, c = compiler.Flags(), compiler.Flags(), compiler.Flags()
    b.nrt, c.nrt = True, False       # c: set to the default's value, so alike a
    pairs = [(a, b, False), (a, c, compiler.Flags.options["nrt"].default is False),
             (b, b.copy(), True), (a, compiler.Flags(), True)]
    for x, y, same in pairs:
        assert (x == y) is same and (y == x) is same
        # numba's own: every option's value, through its property
        assert ({k: getattr(x, k) for k in x.options} == {k: getattr(y, k) for k in y.options}) \
            is same
        assert hash(x) == hash(tuple(sorted(x.options)))
    assert config.values is not None and a.values() == {k: getattr(a, k) for k in a.options}
