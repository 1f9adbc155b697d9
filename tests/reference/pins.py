"""Pins of every command and method: the sha256 of ``timeseries.csv`` and ``impacts.csv``
(and the summary's numbers) of short runs of each scene with each law, solver, mass and
scene file.  Written before the front end was reshaped (issue "One method object"), so
that a moved line of code that changes one bit of one result fails
``tests/test_pins.py``.

    python tests/reference/pins.py            # write tests/reference/pins.json
    python tests/reference/pins.py --check    # compare, one line per difference
"""
from __future__ import annotations

import hashlib
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

PS, FLAT, BAR = "skfem_beam.cases.point_stops", "skfem_beam.cases.flat_obstacles", \
    "skfem_beam.cases.impacting_bar"
SCENES = Path(__file__).resolve().parents[2] / "skfem_beam" / "scene_files"
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
    "toml_heat_mj": ["skfem_beam", "run", str(SCENES / "heat_exchanger_tube.toml"),
                     "--set", "time.T=0.05", "--set", "contact.law=moreau-jean"],
}
NUMBERS = ("steps", "impacts", "max_nodal_violation", "max_penetration", "energy_final",
           "qp_iterations")
PINS = Path(__file__).with_name("pins.json")


def run(name: str, args: list, folder: Path) -> dict:
    out = folder / name
    p = subprocess.run([sys.executable, "-m", *args, "--format", "none", "--out", str(out)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"exit": p.returncode, "stderr": p.stderr.strip().splitlines()[-1:]}
    pin = {f: hashlib.sha256((out / f).read_bytes()).hexdigest()
           for f in ("timeseries.csv", "impacts.csv") if (out / f).exists()}
    summary = json.loads((out / "summary.json").read_text())
    pin.update({k: summary.get(k) for k in NUMBERS})
    return pin


def all_pins(workers: int = 2) -> dict:
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(workers) as pool:
        futures = {k: pool.submit(run, k, a, Path(tmp)) for k, a in RUNS.items()}
        return {k: f.result() for k, f in futures.items()}


if __name__ == "__main__":
    pins = all_pins()
    if "--check" in sys.argv:
        old = json.loads(PINS.read_text())
        bad = [k for k in old if old[k] != pins.get(k)]
        for k in bad:
            print(f"{k}: {old[k]} != {pins.get(k)}")
        print(f"{len(old) - len(bad)} of {len(old)} pins equal")
        sys.exit(1 if bad else 0)
    PINS.write_text(json.dumps(pins, indent=1, sort_keys=True) + "\n")
    print(json.dumps(pins, indent=1))
