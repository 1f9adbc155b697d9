import numpy as np
import pytest

from skfem_beam import scenes
from skfem_beam.cli import main_guard


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
