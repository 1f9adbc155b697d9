"""Write tests/reference/reference_cli.npz: the timeseries.csv columns and the summary's
numbers of the case commands (run once, before a change that must not alter results)."""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

COMMANDS = {
    "point_stops": ["skfem_beam.cases.point_stops", "--T", "0.1"],
    "flat_obstacles": ["skfem_beam.cases.flat_obstacles"],
    "convex_obstacles": ["skfem_beam.cases.convex_obstacles", "--element", "bspline"],
    "energy_decay": ["skfem_beam.cases.energy_decay", "--T", "0.5"],
    "impacting_bar": ["skfem_beam.cases.impacting_bar"],
    "impacting_bar_elastic": ["skfem_beam.cases.impacting_bar", "--obstacle", "elastic"],
}
SUMMARY = ("steps", "impacts", "max_nodal_violation", "max_penetration", "energy_final")


def outputs(name, args, folder):
    out = Path(folder) / name
    subprocess.run([sys.executable, "-m", *args, "--format", "none", "--out", str(out)],
                   check=True, capture_output=True)
    data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    summary = json.loads((out / "summary.json").read_text())
    arrays = {f"{name}/{k}": data[k] for k in data.dtype.names}
    arrays[f"{name}/summary"] = np.array([float(summary[k]) for k in SUMMARY])
    return arrays


if __name__ == "__main__":
    data = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in COMMANDS.items():
            data.update(outputs(name, args, tmp))
            print(name)
    np.savez_compressed(Path(__file__).parent / "reference_cli.npz", **data)
