"""Measure how far the reference runs move from one machine to another, and write each
run's tolerances (tolerances.json; docs/tests.md says how they were measured).

    python tests/reference/spread.py save DIR              # every reference run, here
    python tests/reference/spread.py save DIR RUN [...]    # these pinned commands only
    python tests/reference/spread.py tolerances DIR [...]  # each DIR against the stored

``tolerances`` measures the runs the folders hold and keeps the table's other entries (a
command added since, measured alone, joins the table).

A second sample on the same machine: another x86-64 target for numba, OpenBLAS and numpy
(and a cache of numba's own for it):

    NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=/tmp/nb-generic OPENBLAS_CORETYPE=Sandybridge \\
        NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4" python tests/reference/spread.py save DIR

The stored arrays are what the tests compare with: reference.npz (the API's runs) and
reference_cli.npz (the case commands'), recorded on another machine before issue 15, and
values.npz (the pinned commands' columns: pins.py --values).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
from compare import TOLERANCES, run_spread, runs_of, tolerance  # noqa: E402

FILES = {"api": "reference.npz", "cli": "reference_cli.npz", "commands": "values.npz"}


def save(folder: Path, only: list[str]) -> None:
    from make_cli import COMMANDS, outputs
    from pins import RUNS, all_runs, values_of
    from scenes import runs
    from skfem_beam import scenes
    folder.mkdir(parents=True, exist_ok=True)
    if only:
        with tempfile.TemporaryDirectory() as tmp:
            outs = all_runs(Path(tmp), {k: RUNS[k] for k in only})
            np.savez_compressed(folder / FILES["commands"], **values_of(outs))
        return
    data = {f"{name}/{k}": np.asarray(v) for name, make in runs(scenes).items()
            for k, v in make().items()}
    np.savez_compressed(folder / FILES["api"], **data)
    with tempfile.TemporaryDirectory() as tmp:
        data = {}
        for name, args in COMMANDS.items():
            data.update(outputs(name, args, tmp))
        np.savez_compressed(folder / FILES["cli"], **data)
    with tempfile.TemporaryDirectory() as tmp:      # its names are COMMANDS' too
        np.savez_compressed(folder / FILES["commands"], **values_of(all_runs(Path(tmp))))


def measure(folders: list[Path]) -> dict:
    """group/run -> the largest spread over the folders, against the stored arrays."""
    measured = {}
    for group, file in FILES.items():
        ref = runs_of(HERE / file)
        for folder in [f for f in folders if (f / file).exists()]:
            got = runs_of(folder / file)
            for name in set(ref) & set(got):
                s, key = run_spread(got[name], ref[name]), f"{group}/{name}"
                old = measured.get(key, {"before": 0.0, "after": 0.0})
                measured[key] = {w: max(old[w], s[w]) for w in s}
    return measured


def write_tolerances(folders: list[Path]) -> None:
    old = json.loads(TOLERANCES.read_text()) if TOLERANCES.exists() else {}
    new = measure(folders)
    measured = {**old.get("measured", {}), **new}
    tol = {k: {w: tolerance(v, w) for w, v in m.items()} for k, m in measured.items()}
    for k in sorted(new):
        m, t = measured[k], tol[k]
        print(f"{k:40s} before {m['before']:.2e} -> {t['before']:.1e}   "
              f"after {m['after']:.2e} -> {t['after']:.1e}")
    samples = sorted({*old.get("samples", ()), *(f.name for f in folders)})
    TOLERANCES.write_text(json.dumps({"samples": samples, "measured": measured,
                                      "tolerance": tol}, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    if sys.argv[1:2] == ["save"]:
        save(Path(sys.argv[2]), sys.argv[3:])
    elif sys.argv[1:2] == ["tolerances"]:
        write_tolerances([Path(a) for a in sys.argv[2:]])
    else:
        sys.exit(__doc__)
