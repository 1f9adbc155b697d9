"""The work-precision benchmark in its quick form (the issue asks the suite to run it)."""
import csv

import numpy as np

from skfem_beam.bench import work_precision


def test_quick_work_precision(tmp_path):
    assert work_precision.main(["--quick", "--out", str(tmp_path)]) == 0
    rows = list(csv.DictReader(open(tmp_path / "work_precision.csv")))
    assert (tmp_path / "work_precision.png").stat().st_size > 30_000
    by = {}
    for r in rows:
        by.setdefault((r["scene"], r["method"], float(r["courant"])), []).append(r)
    assert len(by) == 2 * 2 * len(work_precision.METHODS)
    assert all(len(v) >= 4 for v in by.values())            # a ladder of four or more
    col = lambda key, *k: np.array([float(r[key]) for r in by[k]])  # noqa: E731
    pos, mj, mm = "position, average, β=1/4", "Moreau–Jean θ=1/2 e=0, average", \
        "modified mass (redistributed), β=1/2"
    qs = "modified mass (redistributed), β=1/4, quasi-static"
    for scene in ("rod", "bar"):
        for c in (0.04, 0.4):
            e = col("error", scene, pos, c)
            assert np.all(np.diff(e) < 0)                        # converges
            assert col("penetration", scene, pos, c).max() < 1e-15
            assert col("penetration", scene, mm, c).max() < 1e-15
            assert col("penetration", scene, qs, c).max() < 1e-15
            assert np.all(col("penetration", scene, mj, c) > 1e-6)   # O(Δt)
            assert np.all(col("energy_drift", scene, pos, c) < 0)   # E_β only falls
    # a soft penalty spring penetrates; a stiff one at Δt/h = 0.4 gains energy
    assert col("penetration", "bar", "penalty k=1e3, average, β=1/4", 0.04).min() > 1e-3
    assert col("energy_drift", "rod", "penalty k=1e5, average, β=1/4", 0.4).max() > 1
