"""Every command and method gives the results it gave when pinned (tests/reference/pins.py):
on a machine whose pins are recorded, timeseries.csv and impacts.csv byte for byte and the
summary's numbers; on every machine, the same columns as values.npz to the measured
cross-machine tolerances (tests/reference/compare.py), the same steps and impacts."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent / "reference"))
from compare import assert_run_close, decorrelated, runs_of  # noqa: E402
from pins import RUNS, VALUES, arrays_of, execute, pin_of  # noqa: E402

REF = runs_of(VALUES)


@pytest.mark.parametrize("name", sorted(RUNS))
def test_outputs_are_the_pinned_ones(name, tmp_path, machine_pins):
    out = execute(name, RUNS[name], tmp_path)
    if machine_pins is not None:
        assert pin_of(out) == machine_pins["commands"][name]
    assert not isinstance(out, dict), out
    got, ref = {k.split("/", 1)[1]: v for k, v in arrays_of(name, out).items()}, REF[name]
    counts = [0] if decorrelated(f"commands/{name}") else [0, 1]   # steps, impacts
    assert got["summary"][counts].tolist() == ref["summary"][counts].tolist()
    assert_run_close(f"commands/{name}", got, ref)
