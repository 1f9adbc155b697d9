import os
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from skfem_beam import chart_process, numba_speed, scenes
from skfem_beam.cli import main_guard

# the suite compiles as a command does (numba_speed: the same code, in less time)
numba_speed.apply()

sys.path.insert(0, str(Path(__file__).parent / "reference"))


@cache
def _machine_pins():
    """(this machine's pins or None, the line that says which check the pins' tests run)."""
    from pins import machine_pins
    return machine_pins()


def pytest_configure(config):
    # commands draw no charts in the suite (half of a short command's CPU), but in the
    # tests that ask for them (the `charts` fixture); SKFEM_BEAM_CHARTS=1 draws them all
    os.environ.setdefault(chart_process.CHARTS, "0")


@pytest.fixture
def charts(monkeypatch):
    """Commands and in-process runs draw their charts (the suite's default is none)."""
    monkeypatch.setenv(chart_process.CHARTS, "1")


def pytest_sessionstart(session):
    # the fingerprint before any test runs (here and in each xdist worker): a test that
    # starts a Dask cluster leaves OPENBLAS_NUM_THREADS=1 in os.environ (its nannies run
    # in this process), which a fingerprint read after it would see as another machine
    _machine_pins()


def pytest_report_header(config):
    return _machine_pins()[1]


def pytest_terminal_summary(terminalreporter):
    terminalreporter.write_line(_machine_pins()[1])


@pytest.fixture(scope="session")
def machine_pins():
    """This machine's pins (tests/reference/pins/), or None: then only values are checked."""
    return _machine_pins()[0]


@pytest.fixture(scope="session")
def pipe():
    """The first paper's scene as a problem object (J=19 Hermite)."""
    return scenes.point_stops()

# summary.json keys every case writes (the output contract, docs/design.md §5)
SUMMARY_KEYS = {"case", "J", "dt", "T", "beta", "element", "solver", "steps", "wall_time_s",
                "max_penetration", "max_nodal_violation", "energy_final", "impacts"}


def rate(errors, hs):
    """Least-squares slope of log(error) against log(h)."""
    return np.polyfit(np.log(hs), np.log(errors), 1)[0]


def exit_code(main, argv) -> int:
    """Run a case's ``main(argv)`` in process through the same guard as ``python -m``
    (one error line, exit codes) and return its exit code."""
    with pytest.raises(SystemExit) as exit_:
        main_guard(lambda: main(argv))
    return exit_.value.code


def assert_refused(main, argv, word, capsys, folder) -> None:
    """``main`` refuses ``argv``: exit code 2, one stderr line naming ``word``, and
    ``folder`` (the output's parent) left empty: no partial or hidden output folder."""
    assert exit_code(main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and word in err, err
    assert not list(folder.iterdir())


def assert_scene_refused(tmp_path, capsys, files: dict, scene: str, word: str) -> None:
    """The scene file ``scene`` among ``files`` (name → text or bytes, written into a
    folder of their own) is refused by ``python -m skfem_beam run`` as assert_refused
    says: exit 2, one line naming ``word``, nothing written."""
    from skfem_beam.scenefile import run_main
    src = tmp_path / "src"
    src.mkdir()
    for name, content in files.items():
        (src / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(src / scene), "--out", str(out / "run")], word, capsys, out)


def resumed(make, cut: int):
    """(a run driven to its end, the same run restored from a checkpoint at state ``cut``
    and driven to its end); ``make()`` builds a fresh run.  Asserts that the restored one
    went on bit for bit: the same last state and impact events."""
    import numpy as np
    from skfem_beam.scheme.solve import drive
    a, b, c = make(), make(), make()
    drive(a)
    b.advance(cut)
    c.restore(b.checkpoint())
    drive(c)
    assert np.array_equal(a.u_cur, c.u_cur) and np.array_equal(a.u_prev, c.u_prev)
    ea, ec = a.impact_events(), c.impact_events()
    assert all(np.array_equal(ea[k], ec[k], equal_nan=True) for k in ea)
    return a, c


def assert_exact_with_friction(r, clearance: float) -> None:
    """A run of the position-level law with Coulomb friction: no penetration at the nodes
    (≤ 1e-12 of the clearance), the energy identity with the friction's work to 1e-9, and
    friction that dissipates at every step."""
    assert r.solver == "round-hole-friction" and r.impacts > 10
    assert r.max_nodal_violation <= 1e-12 * clearance
    w = r.work
    gap = r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"] - w["friction"]
    assert np.abs(gap).max() <= 1e-9 * np.abs(r.energy).max()
    assert w["friction"][-1] < 0 and w["contact"][-1] < 0
    assert np.diff(w["friction"]).max() <= 1e-15 * abs(w["friction"][-1])


def random_broached(rng, widths, ridge: float):
    """A random broached hole of radius 1 (2 to 5 lands, each ``widths`` (a, b) × its
    share of the turn wide, at a random angle) and a random SPD 2 × 2 block D
    (AAᵀ + ridge·I): one local problem of the broached-hole laws."""
    n = int(rng.integers(2, 6))
    from skfem_beam.holes import Hole
    hole = Hole.broached(n, rng.uniform(*widths) * 2 * np.pi / n, 1.0, rng.uniform(-3, 3))
    A = rng.normal(size=(2, 2))
    return hole, A @ A.T + ridge * np.eye(2)


@cache
def compiled(kernel):
    """A kernel compiled without a Python entry (``no_cpython_wrapper``: called from
    compiled code only, e.g. contact.round_hole.inner), callable from a test."""
    from numba import njit

    @njit
    def call(*args):
        return kernel(*args)
    return call
