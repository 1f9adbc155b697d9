"""A contact law of the user's through the public registry alone
(``skfem_beam.contact.register``): no edit of methods.py, cli.py or the scene file's code.
The toy law is Lemma 4.1's projection written in Python with one parameter (a factor on
μ: 1 is the exact step); it must give the compiled projection's run, be named by the
Python API, ``--solver`` and a scene file's ``[contact] law``, and its parameter, declared
in the law's own table, must reach the step from Python, ``--param`` and ``[contact]``."""
import json
import subprocess
import sys
import textwrap
from functools import partial
from pathlib import Path

import numpy as np
import pytest

import skfem_beam
from skfem_beam import scenes
from skfem_beam.contact import SOLVERS, STEP_SOLVERS, ContactLaw, register
from skfem_beam.errors import InputError
from skfem_beam.methods import PositionLevel
from skfem_beam.scheme import solve
from skfem_beam.semidiscrete import beam_system

TOY = '''
import numpy as np
from skfem_beam.contact import ContactLaw
from skfem_beam.contact.base import Parameter


class Clip:
    """The step's μ_i = factor · (clip(y_free,i) − y_free,i) / D_ii."""
    def __init__(self, diagonal, factor):
        self.diagonal, self.factor = diagonal, factor

    def solve(self, x_free, y_free, lo, hi):
        return self.factor * (np.clip(y_free, lo, hi) - y_free) / self.diagonal, 0

    def checkpoint(self):
        return {}

    def restore(self, saved):
        pass


class ToyClip(ContactLaw):
    name = "toy-clip"
    parameters = (Parameter("factor", "a factor on the exact step's μ", low=0.0, high=1.0),)

    def __init__(self, factor=1.0):
        self.factor = factor

    def solver(self, step):
        return Clip(np.diag(step.D).copy(), self.factor)
'''


@pytest.fixture
def toy(tmp_path, monkeypatch):
    """The toy law's module (a file of the user's), imported; STEP_SOLVERS as it was
    afterwards."""
    (tmp_path / "toy_law.py").write_text(TOY)
    monkeypatch.syspath_prepend(str(tmp_path))
    import toy_law
    saved = dict(STEP_SOLVERS)
    yield toy_law
    STEP_SOLVERS.clear()
    STEP_SOLVERS.update(saved)
    sys.modules.pop("toy_law", None)


def test_a_registered_law_is_a_solver_of_the_python_api(toy):
    register("toy-clip", toy.ToyClip)
    register("toy-clip-half", partial(toy.ToyClip, factor=0.5))
    assert "toy-clip" in SOLVERS and "toy-clip" in tuple(SOLVERS)
    system = beam_system(scenes.point_stops())
    exact = solve(system, 1e-4, 0.2, method=PositionLevel("projection"))
    mine = solve(system, 1e-4, 0.2, method=PositionLevel("toy-clip"))
    half = solve(system, 1e-4, 0.2, method=PositionLevel("toy-clip-half"))
    assert exact.impacts > 0 and mine.solver == "toy-clip"
    scale = np.abs(exact.energy).max()
    assert np.abs(mine.energy - exact.energy).max() <= 1e-12 * scale
    assert mine.max_penetration <= max(exact.max_penetration, 1e-15)   # exact at the node
    # the parameter reaches the step: half the correction leaves the tip inside the stop
    assert half.max_penetration > 1e-6, half.max_penetration


def test_a_registered_law_is_named_by_the_command_line_and_a_scene_file(toy, tmp_path):
    scene = Path(skfem_beam.__file__).parent / "scene_files" / "point_stops.toml"
    script = tmp_path / "run_toy.py"
    script.write_text(textwrap.dedent('''
        import sys
        import toy_law
        from skfem_beam.contact import register
        register("toy-clip", toy_law.ToyClip)
        if sys.argv[1] == "case":
            from skfem_beam.cases.point_stops import main
        else:
            from skfem_beam.__main__ import main
        sys.exit(main(sys.argv[2:]))
    '''))
    env_path = str(tmp_path)
    runs = {"case": ["--dt", "1e-4", "--T", "0.05", "--solver", "toy-clip"],
            "scene": ["run", str(scene), "--set", "time.T=0.05", "--set",
                      'contact.law="toy-clip"']}
    for how, argv in runs.items():
        out = tmp_path / how
        p = subprocess.run([sys.executable, str(script), how, *argv, "--format", "none",
                            "--out", str(out)], capture_output=True, text=True,
                           env={**__import__("os").environ, "PYTHONPATH": env_path})
        assert p.returncode == 0, p.stderr
        assert json.loads((out / "summary.json").read_text())["solver"] == "toy-clip"


def test_a_taken_name_or_a_maker_that_is_no_law_is_refused(toy):
    with pytest.raises(InputError, match="a new, non-empty name is needed"):
        register("projection", toy.ToyClip)
    register("toy-bad", lambda: object())
    with pytest.raises(InputError, match="not a ContactLaw"):
        PositionLevel("toy-bad")
    assert issubclass(toy.ToyClip, ContactLaw)


def _run_toy(tmp_path, how, argv):
    """A command with the toy law registered (the user's script); its exit and folder."""
    script = tmp_path / "run_toy.py"
    script.write_text(textwrap.dedent('''
        import sys
        import toy_law
        from skfem_beam.cli import main_guard
        from skfem_beam.contact import register
        register("toy-clip", toy_law.ToyClip)
        if sys.argv[1] == "case":
            from skfem_beam.cases.point_stops import main
        else:
            from skfem_beam.__main__ import main
        main_guard(lambda: main(sys.argv[2:]))
    '''))
    out = tmp_path / f"{how}-{len(list(tmp_path.iterdir()))}"
    p = subprocess.run([sys.executable, str(script), how, *argv, "--format", "none",
                        "--out", str(out)], capture_output=True, text=True,
                       env={**__import__("os").environ, "PYTHONPATH": str(tmp_path)})
    return p, out


def test_a_law_parameter_from_its_table_reaches_the_step_from_every_front_end(toy, tmp_path):
    """The parameter is the law's (its ``parameters`` table), not a word of ours: Python's
    ``params``, ``--param`` and ``[contact] factor`` give the same run, and half the
    correction leaves the tip inside the stop (exact contact: none)."""
    register("toy-clip", toy.ToyClip)
    system = beam_system(scenes.point_stops())
    half = solve(system, 1e-4, 0.2, method=PositionLevel("toy-clip", params={"factor": 0.5}))
    whole = solve(system, 1e-4, 0.2, method=PositionLevel("toy-clip", params={"factor": 1}))
    assert half.max_penetration > 1e-6 and whole.max_penetration <= 1e-15
    scene = Path(skfem_beam.__file__).parent / "scene_files" / "point_stops.toml"
    runs = {"case": ["--dt", "1e-4", "--T", "0.2", "--solver", "toy-clip", "--param",
                     "factor=0.5"],
            "scene": ["run", str(scene), "--set", "time.T=0.2", "--set", "time.dt=1e-4",
                      "--set", 'contact.law="toy-clip"', "--set", "contact.factor=0.5"]}
    for how, argv in runs.items():
        p, out = _run_toy(tmp_path, how, argv)
        assert p.returncode == 0, p.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert summary["solver"] == "toy-clip"
        assert summary["max_penetration"] > 1e-6, (how, summary["max_penetration"])


@pytest.mark.parametrize("argv, line", [
    (["--param", "factor=2"], "factor must be a number in [0, 1]"),
    (["--param", "gain=0.5"], "--param gain: not a parameter of the 'toy-clip' law "
                              "(its parameters: factor)"),
    (["--param", "factor"], "--param 'factor': give NAME=VALUE with a number"),
    (["--set", "contact.factor=2"], "[contact] factor = 2: factor must be a number in [0, 1]"),
    (["--set", 'contact.factor="half"'], "contact.factor"),
    (["--set", "contact.gain=1"], "unknown key 'gain'; [contact] allows: law, stiffness, "
                                  "restitution, friction, theta, factor"),
])
def test_a_bad_law_parameter_is_one_line(toy, tmp_path, argv, line):
    scene = Path(skfem_beam.__file__).parent / "scene_files" / "point_stops.toml"
    law = (["--solver", "toy-clip"] if argv[0] == "--param" else
           ["--set", 'contact.law="toy-clip"'])
    how, head = ("case", []) if argv[0] == "--param" else ("scene", ["run", str(scene)])
    p, out = _run_toy(tmp_path, how, [*head, *law, *argv, "--T", "0.01"]
                      if how == "case" else [*head, *law, *argv, "--set", "time.T=0.01"])
    assert p.returncode == 2, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and line in p.stderr, p.stderr
    assert not out.exists()
