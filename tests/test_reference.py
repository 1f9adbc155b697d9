"""Today's outputs stay today's outputs: every pinned run (tests/reference/) against the
arrays stored before the redesign of issue 15, to 1e-12 of each array's largest value."""
import sys
from pathlib import Path

import numpy as np
import pytest

from skfem_beam import scenes

HERE = Path(__file__).parent / "reference"
sys.path.insert(0, str(HERE))
from make_cli import COMMANDS, SUMMARY, outputs  # noqa: E402
from scenes import runs  # noqa: E402

REF = np.load(HERE / "reference.npz")
REF_CLI = np.load(HERE / "reference_cli.npz")
RUNS = runs(scenes)


def assert_same(name, got, ref, rtol=1e-12):
    got, ref = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
    assert got.shape == ref.shape, (name, got.shape, ref.shape)
    finite = np.isfinite(ref)
    assert (np.isfinite(got) == finite).all(), name
    scale = np.abs(ref[finite]).max(initial=0.0)
    err = np.abs(got[finite] - ref[finite]).max(initial=0.0)
    assert err <= rtol * scale, f"{name}: differs by {err:.3g} (scale {scale:.3g})"


@pytest.mark.parametrize("name", list(RUNS))
def test_api_outputs_are_pinned(name):
    for key, value in RUNS[name]().items():
        assert_same(f"{name}/{key}", value, REF[f"{name}/{key}"])


@pytest.mark.parametrize("name", list(COMMANDS))
def test_command_outputs_are_pinned(name, tmp_path):
    got = outputs(name, COMMANDS[name], tmp_path)
    # every pinned column is still written (columns added since, e.g. the work terms and
    # their J versions, are tested by what they mean: tests/test_units.py)
    pinned = {k for k in REF_CLI.files if k.startswith(f"{name}/")}
    assert pinned <= set(got), pinned - set(got)
    got = {k: got[k] for k in pinned}
    for key, value in got.items():
        if key.endswith("/summary"):   # steps, impacts exactly; the rest to 1e-12
            assert value[:2].tolist() == REF_CLI[key][:2].tolist(), (key, SUMMARY)
        assert_same(key, value, REF_CLI[key])
