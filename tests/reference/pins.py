"""Pins of every command and method, per machine: the sha256 of ``timeseries.csv`` and
``impacts.csv`` (and the summary's numbers) of short runs of each scene with each law,
solver, mass and scene file, and a digest of the API's and the case commands' reference
arrays (tests/test_reference.py).  A moved line of code that changes one bit of one result
fails ``tests/test_pins.py`` on a machine whose pins are recorded.

The bits are one machine's (CPU, numba's target, BLAS, library versions:
tests/reference/machine.py): pins/<fingerprint>.json holds them with the fingerprint that
made them.  On any machine the same runs are compared with values.npz to a tolerance
(tests/reference/compare.py).

    python tests/reference/pins.py            # record this machine's pins
    python tests/reference/pins.py --check    # compare with them, one line per difference
    python tests/reference/pins.py --values   # write values.npz (after a change of results)
"""
from __future__ import annotations

import csv
import hashlib
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
from machine import differences, fingerprint, label  # noqa: E402

PS, FLAT, BAR = "skfem_beam.cases.point_stops", "skfem_beam.cases.flat_obstacles", \
    "skfem_beam.cases.impacting_bar"
SCENES = HERE.parents[1] / "skfem_beam" / "scene_files"
RUNS = {
    "ps": [PS, "--T", "0.1"],
    "ps_active_set": [PS, "--T", "0.1", "--solver", "active-set"],
    "ps_penalty": [PS, "--T", "0.1", "--law", "penalty"],
    "ps_penalty_method": [PS, "--T", "0.1", "--method", "penalty", "--stiffness", "1e7"],
    "ps_moreau_jean": [PS, "--T", "0.1", "--law", "moreau-jean"],
    "ps_restitution": [PS, "--T", "0.1", "--restitution", "0.5"],
    "ps_mj_restitution": [PS, "--T", "0.1", "--law", "moreau-jean", "--restitution", "1"],
    "ps_redistributed": [PS, "--T", "0.1", "--mass", "redistributed"],
    "ps_quasi_static": [PS, "--T", "0.1", "--mass", "redistributed", "--massless",
                        "quasi-static", "--beta", "0.25"],
    "ps_osqp": [PS, "--T", "0.03", "--solver", "osqp"],
    "ps_daqp": [PS, "--T", "0.05", "--solver", "daqp"],
    "ps_bspline_save": [PS, "--T", "0.1", "--element", "bspline", "--dt", "1e-5",
                        "--save-every", "7", "--probe", "0.75"],
    "flat": [FLAT],
    "flat_penalty": [FLAT, "--law", "penalty", "--stiffness", "1e6"],
    "flat_moreau_jean": [FLAT, "--law", "moreau-jean", "--T", "0.5"],
    "flat_osqp": [FLAT, "--solver", "osqp", "--T", "0.2"],
    "flat_daqp": [FLAT, "--solver", "daqp", "--T", "0.2"],
    "flat_bspline_probe": [FLAT, "--element", "bspline", "--probe", "5.0", "--probe", "9.5"],
    "convex": ["skfem_beam.cases.convex_obstacles", "--element", "bspline"],
    "energy_decay": ["skfem_beam.cases.energy_decay", "--T", "0.5", "--beta", "0.25"],
    "bar": [BAR],
    "bar_elastic": [BAR, "--obstacle", "elastic", "--k", "100"],
    "bar_penalty": [BAR, "--law", "penalty", "--stiffness", "1e5"],
    "bar_moreau_jean": [BAR, "--law", "moreau-jean"],
    "bar_consistent_right": [BAR, "--mass", "consistent", "--beta", "0.5",
                             "--obstacle-at", "right", "--far-end", "clamped", "--v0", "-1",
                             "--u0", "0"],
    "bar_redistributed": [BAR, "--mass", "redistributed", "--massless", "quasi-static"],
    "bar_A": [BAR, "--A", "2e-4", "--b", "0.01", "--restitution", "0.5"],
    **{f"toml_{p.stem}": ["skfem_beam", "run", str(p), "--set", "time.T=0.05"]
       for p in sorted(SCENES.glob("*.toml"))},
    **{f"toml_{p.stem}": ["skfem_beam", "run", str(p)]      # their own T: short already
       for p in sorted((SCENES / "plates").glob("*.toml"))},
    "toml_heat_mj": ["skfem_beam", "run", str(SCENES / "heat_exchanger_tube.toml"),
                     "--set", "time.T=0.05", "--set", "contact.law=moreau-jean"],
    "toml_friction_mj": ["skfem_beam", "run", str(SCENES / "tube_round_holes_friction.toml"),
                         "--set", "time.T=0.05", "--set", "contact.law=moreau-jean"],
}
NUMBERS = ("steps", "impacts", "max_nodal_violation", "max_penetration", "energy_final",
           "qp_iterations")
PIN_DIR = HERE / "pins"
VALUES = HERE / "values.npz"


def execute(name: str, args: list, folder: Path):
    """Run one pinned command into folder/name: its output folder, or a dict saying how it
    failed (so that a failure is a pin difference, not a crash of the check)."""
    out = folder / name
    p = subprocess.run([sys.executable, "-m", *args, "--format", "none", "--out", str(out)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"exit": p.returncode, "stderr": p.stderr.strip().splitlines()[-1:]}
    return out


def pin_of(out) -> dict:
    """The bits of a run: its CSVs' sha256 and the summary's numbers."""
    if isinstance(out, dict):
        return out
    pin = {f: hashlib.sha256((out / f).read_bytes()).hexdigest()
           for f in ("timeseries.csv", "impacts.csv") if (out / f).exists()}
    summary = json.loads((out / "summary.json").read_text())
    pin.update({k: summary.get(k) for k in NUMBERS})
    return pin


def _columns(path: Path) -> dict:
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float).reshape(len(rows) - 1, len(rows[0]))
    return {h: data[:, i] for i, h in enumerate(rows[0])}


def arrays_of(name: str, out: Path) -> dict:
    """What is compared across machines: the timeseries' columns, the impacts' start times
    and the summary's numbers, as ``name/key`` arrays."""
    arrays = {f"{name}/{k}": v for k, v in _columns(out / "timeseries.csv").items()}
    impacts = out / "impacts.csv"
    starts = _columns(impacts).get("t_start", np.empty(0)) if impacts.exists() else np.empty(0)
    arrays[f"{name}/impacts_t_start"] = starts
    summary = json.loads((out / "summary.json").read_text())
    arrays[f"{name}/summary"] = np.array([float(summary.get(k) or 0.0) for k in NUMBERS])
    return arrays


def values_of(outs: dict) -> dict:
    """The arrays of every run of ``all_runs``, which must all have succeeded."""
    failed = {k: o for k, o in outs.items() if isinstance(o, dict)}
    assert not failed, failed
    return {key: a for name, out in outs.items() for key, a in arrays_of(name, out).items()}


def digest(arrays: dict) -> str:
    """One sha256 for a dict of arrays (keys, shapes and bytes)."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(np.asarray(arrays[k], dtype=float))
        h.update(f"{k}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def machine_pins():
    """(this machine's pins or None, the line that says which check runs)."""
    fp = fingerprint()
    own = PIN_DIR / f"{label(fp)}.json"
    if own.exists():
        return json.loads(own.read_text()), \
            f"pins: this machine's ({own.relative_to(HERE.parents[1])}): bits checked"
    others = [json.loads(p.read_text())["machine"] for p in sorted(PIN_DIR.glob("*.json"))]
    why = "; ".join(f"{label(o)} differs in {', '.join(differences(fp, o))}" for o in others)
    return None, (f"pins: none recorded on this machine ({label(fp)}; {why or 'none at all'}): "
                  f"values checked to tolerance, bits not; record them with "
                  f"`python tests/reference/pins.py`")


def _reference_digests() -> dict:
    """The digests of tests/test_reference.py's runs: the API's and the case commands'."""
    from make_cli import COMMANDS, outputs
    from scenes import runs
    from skfem_beam import scenes
    api = {name: digest(make()) for name, make in runs(scenes).items()}
    with tempfile.TemporaryDirectory() as tmp:
        cli = {name: digest(outputs(name, args, tmp)) for name, args in COMMANDS.items()}
    return {"api": api, "cli": cli}


def all_runs(folder: Path, runs: dict = RUNS, workers: int = 2) -> dict:
    with ThreadPoolExecutor(workers) as pool:
        futures = {k: pool.submit(execute, k, a, folder) for k, a in runs.items()}
        return {k: f.result() for k, f in futures.items()}


def main(argv) -> int:
    if argv not in ([], ["--check"], ["--values"]):     # --help must not record (it did)
        print(f"usage: python tests/reference/pins.py [--check | --values] (got "
              f"{' '.join(argv)}); see the module docstring", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        outs = all_runs(Path(tmp))
        if "--values" in argv:
            np.savez_compressed(VALUES, **values_of(outs))
            print(f"{VALUES}: {len(outs)} runs")
            return 0
        pins = {"machine": fingerprint(), "commands": {k: pin_of(o) for k, o in outs.items()},
                **_reference_digests()}
    if "--check" in argv:
        old, line = machine_pins()
        print(line)
        if old is None:
            return 1
        parts = ("commands", "api", "cli")     # a run added or gone is a difference too
        bad = [(part, k) for part in parts for k in sorted({*old[part], *pins[part]})
               if old[part].get(k) != pins[part].get(k)]
        for part, k in bad:
            print(f"{part}/{k}: {old[part].get(k)} != {pins[part].get(k)}")
        total = sum(len({*old[p], *pins[p]}) for p in parts)
        print(f"{total - len(bad)} of {total} pins equal")
        return 1 if bad else 0
    PIN_DIR.mkdir(exist_ok=True)
    path = PIN_DIR / f"{label(pins['machine'])}.json"
    path.write_text(json.dumps(pins, indent=1, sort_keys=True) + "\n")
    print(f"{path}: {len(pins['commands'])} commands, {len(pins['api'])} API runs, "
          f"{len(pins['cli'])} case commands")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
