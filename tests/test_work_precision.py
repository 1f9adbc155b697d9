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
        by.setdefault((r["scene"], r["method"]), []).append(r)
    assert all(len(v) >= 4 for v in by.values())            # a ladder of four or more
    err = lambda scene, method: np.array([float(r["error"]) for r in by[(scene, method)]])  # noqa
    viol = lambda scene, method: max(float(r["violation"]) for r in by[(scene, method)])  # noqa
    # the contact-implicit scheme converges to the exact bar solution, without penetrating
    e = err("bar", "contact β=1/4")
    assert np.all(np.diff(e) < 0) and e[-1] < 1e-3 and viol("bar", "contact β=1/4") < 1e-12
    # a soft penalty spring converges to the wrong (spring) solution and penetrates
    assert err("bar", "penalty k=1000 β=1/4")[-1] > 3 * e[-1]
    assert viol("bar", "penalty k=1000 β=1/4") > 1e-3
    # convex scene: the finest rung is several times better than the coarsest, both elements
    for m in ("contact β=1/2 hermite active-set", "contact β=1/2 bspline active-set"):
        assert err("convex", m)[-1] < err("convex", m)[0] / 4
    assert viol("point_stops", "contact β=1/2 hermite") <= 1e-15   # round-off of the cubic at L
