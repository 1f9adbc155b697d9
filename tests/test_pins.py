"""Every command and method gives the files it gave when pinned (tests/reference/pins.py):
timeseries.csv and impacts.csv byte for byte, and the summary's numbers."""
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent / "reference"))
from pins import PINS, RUNS, run  # noqa: E402

OLD = json.loads(PINS.read_text())


@pytest.mark.parametrize("name", sorted(RUNS))
def test_outputs_are_the_pinned_ones(name, tmp_path):
    assert run(name, RUNS[name], tmp_path) == OLD[name]
