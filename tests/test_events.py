"""impacts.csv and the per-node / per-obstacle contact statistics of summary.json:
against the run's own series (impulse = ∫ contact force dt), the bar's exact impact,
several obstacles, and a SIGKILL + --resume (the same table as an uninterrupted run)."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from skfem_beam import BeamProblem, Obstacles, beam_system, scenes
from skfem_beam.cases import flat_obstacles, impacting_bar, point_stops
from skfem_beam.contact import resolve
from skfem_beam.output.events import COLUMNS, write_impacts
from skfem_beam.results import read_csv, read_run
from skfem_beam.scheme import Run, Stepping, drive
from skfem_beam.scheme.beta import BetaScheme


def run_case(main, tmp_path, name, argv):
    out = tmp_path / name
    assert main(argv + ["--format", "none", "--out", str(out)]) == 0
    return read_run(out)


@pytest.mark.parametrize("method", ["contact", "penalty"])
def test_beam_impulses_are_the_integral_of_the_contact_force(tmp_path, method):
    r = run_case(point_stops.main, tmp_path, method,
                 ["--dt", "1e-5", "--T", "0.4", "--method", method])
    imp, s = r.impacts, r.summary
    assert list(imp) == list(COLUMNS)
    n = imp["t_start"].size
    assert n == s["impacts"] > 10
    # N·s against the N column, every step saved; a penalty spring's β-weighted force
    # goes on after the node has left it, and is counted
    force = r.series["contact_force_N"]
    assert imp["impulse"].sum() == pytest.approx(force.sum() * s["dt"], rel=1e-12)
    assert imp["peak_force"].max() == pytest.approx(np.abs(force).max(), rel=1e-12)
    # the upper stop pushes down, the lower up
    assert np.all(np.sign(imp["impulse"]) == np.where(imp["bound"] == 1, 1, -1))
    assert np.all(imp["t_end"] > imp["t_start"]) and np.all(np.diff(imp["t_start"]) > 0)
    # one constrained node: its contact fraction is the run's own
    (node,) = s["impact_statistics"]["nodes"]
    assert node["x"] == 1.501 and node["impacts"] == n
    assert node["contact_fraction"] == pytest.approx(s["contact_fraction"], rel=1e-12)
    assert node["max_impulse"] == np.abs(imp["impulse"]).max()
    assert node["max_violation"] == s["max_nodal_violation"]
    assert s["impact_statistics"]["units"]["impulse"] == "N·s"


@pytest.mark.parametrize("flags", [[], ["--obstacle-at", "right", "--v0", "1"],
                                   ["--A", "0.01"], ["--obstacle", "elastic"],
                                   ["--method", "penalty", "--stiffness", "1e4"]])
def test_bar_impulse_is_the_integral_of_R(tmp_path, flags):
    r = run_case(impacting_bar.main, tmp_path, "bar", flags)
    imp, s, dt = r.impacts, r.summary, r.summary["dt"]
    R = r.series["contact_force"]          # R ≥ 0 at either end, R(tₙ) from state n + 1
    assert np.all(imp["impulse"] > 0) and np.nanmin(R) >= 0
    assert imp["impulse"].sum() == pytest.approx(np.nansum(R) * dt, rel=1e-12)
    # each impact: R over its states (shifted by one: R at tₙ is the force of step n → n+1)
    start = np.rint(imp["t_start"] / dt).astype(int)
    for i, a in enumerate(start):
        b = start[i + 1] if i + 1 < start.size else R.size + 1
        assert imp["impulse"][i] == pytest.approx(np.nansum(R[a - 1:b - 1]) * dt, rel=1e-12)
    A = 0.01 if "--A" in flags else 1.0
    # the energy is in J where the cross-section is given, else per unit cross-section
    if "--A" in flags:
        assert s["energy_final_J"] == s["energy_final"] == pytest.approx(0.5 * A, rel=0.02)
    else:
        assert s["energy_final_J"] is None
    if flags in ([], ["--A", "0.01"]):             # the rigid obstacle, [DRF] Example 1
        # exact: the bar (ρL = 1, v0 = −1) rests on the obstacle for 2L/c = 2 s and
        # leaves with +1: impulse 2ρAL|v0|
        (t0, t1), total = (imp["t_start"][0], imp["t_end"][0]), imp["impulse"][0]
        assert imp["t_start"].size == 1 and t0 <= 2 * dt and abs(t1 - 2.0) < 10 * dt
        assert total == pytest.approx(2.0 * A, rel=0.01)
        unit = "N·s" if A != 1.0 else "Pa·s"
        assert s["impact_statistics"]["units"]["impulse"] == unit


def test_several_obstacles_are_grouped(tmp_path):
    # two pairs of point stops (x = 0.75 and L) and a lower span over [1.05, 1.35]
    pipe = scenes.point_stops()
    L = pipe.beam.L
    obstacles = Obstacles.combine(Obstacles.stops([0.75, L], -0.02, 0.02),
                                  Obstacles.span(1.05, 1.35, g1=-0.03))
    nodes = np.union1d(np.linspace(0, L, 21), [0.75, 1.05, 1.35])
    pb = BeamProblem(pipe.beam, obstacles, pipe.support, initial=pipe.initial, nodes=nodes)
    run = Run(BetaScheme(beam_system(pb), Stepping(1e-4, 0.4), resolve("auto", None)))
    drive(run)
    stats = write_impacts(tmp_path, run, {"force": "N", "impulse": "N·s"},
                          pb.beam.rho_S, 1.0, obstacles)["impact_statistics"]
    table = read_csv(tmp_path / "impacts.csv")
    groups = stats["obstacles"]
    assert sum(g["impacts"] for g in groups) == table["x"].size == run.result().impacts > 0
    assert sum(n["impacts"] for n in stats["nodes"]) == table["x"].size
    where = {g["where"]: g for g in groups}
    assert set(where) <= {"point stops at x=0.75", f"point stops at x={L:g}",
                          "span [1.05, 1.35]"} and len(where) >= 2
    for g in groups:      # each group holds exactly the rows at its nodes
        assert g["x"] and all(x in table["x"] for x in g["x"])
        if g["where"].startswith("span"):
            assert all(1.05 - 1e-12 <= x <= 1.35 + 1e-12 for x in g["x"])
        rows = np.isin(table["x"], g["x"])
        assert g["impacts"] == rows.sum()
        assert g["max_impulse"] == np.abs(table["impulse"][rows]).max()


CASE = [sys.executable, "-m", "skfem_beam.cases.point_stops"]
ARGS = ["--dt", "1e-5", "--T", "1.0", "--flush-every", "2000", "--format", "none"]


def test_sigkill_then_resume_writes_the_same_impacts(tmp_path):
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert subprocess.run(CASE + ARGS + ["--out", str(ref)], capture_output=True).returncode == 0
    size = (ref / "timeseries.csv").stat().st_size
    p = subprocess.Popen(CASE + ARGS + ["--out", str(killed), "--checkpoint-every", "0"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    csv = killed / "timeseries.csv"
    while time.monotonic() < deadline and p.poll() is None:
        if (killed / "checkpoint.npz").exists() and csv.exists() and \
                csv.stat().st_size > size // 2:
            break
        time.sleep(0.002)
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    if json.loads((killed / "summary.json").read_text())["status"] != "running":
        pytest.skip("the run finished before it could be killed")
    assert not (killed / "impacts.csv").exists()
    res = subprocess.run(CASE + ["--resume", str(killed)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    table = (ref / "impacts.csv").read_bytes()
    assert table.count(b"\n") > 100
    assert (killed / "impacts.csv").read_bytes() == table
    a, b = (json.loads((d / "summary.json").read_text())["impact_statistics"]
            for d in (ref, killed))
    assert a == b


@pytest.mark.parametrize("law", ["penalty", "active-set"])
def test_impulses_are_the_contact_impulse_applied_along_the_span(tmp_path, law):
    """Obstacles along the span (many constrained nodes): Σ impulse = Σ λΔt of the run to
    round-off, and each event owns exactly its node's force from its first state to the
    second state after it leaves (or the node's next impact).  A penalty spring's force
    trails the contact by up to two states: the loop's sums over the states in contact
    alone missed 13-100 % of it on this scene (dt = 1e-3 to 1e-4, 1e6 to 1e8 N/m)."""
    flags = ["--law", "penalty"] if law == "penalty" else ["--solver", "active-set"]
    r = run_case(flat_obstacles.main, tmp_path, law, flags)
    imp, s = r.impacts, r.summary
    assert imp["t_start"].size == s["impacts"] > 50 and len(set(imp["x"])) > 5
    applied = r.series["contact_force_N"].sum() * s["dt"]
    assert imp["impulse"].sum() == pytest.approx(applied, rel=1e-12)
    # per node and per event, from the run's own forces (every state, every node)
    pb = scenes.flat_obstacles()
    stiffness = s["penalty_stiffness_N_per_m"]
    run = Run(BetaScheme(beam_system(pb), Stepping(s["dt"], s["T"]),
              resolve(law, stiffness / (pb.beam.rho_S or 1.0) if stiffness else None),
              s["beta"]))
    drive(run)
    ev, dt, lam = run.impact_events(), run.dt, run.result().contact_force   # states × nodes
    assert ev["impulse"].sum() * (pb.beam.rho_S or 1.0) == pytest.approx(applied, rel=1e-12)
    owned = np.zeros(lam.shape, dtype=bool)
    start, end = (np.rint(ev[k] / dt).astype(int) for k in ("t_start", "t_end"))
    tail = 0.0
    small = 1.2e-14 * np.abs(ev["impulse"]).max()   # for an impulse near 0: the largest's scale
    for i, j in enumerate(ev["value"]):
        later = start[(ev["value"] == j) & (start > start[i])]
        last = min(run.n if ev["open"][i] else end[i] + 1, later.min(initial=run.n + 1) - 1)
        f = lam[start[i]:last + 1, j]
        owned[start[i]:last + 1, j] = True
        assert ev["impulse"][i] == pytest.approx(f.sum() * dt, rel=1e-12, abs=small)
        assert ev["peak_force"][i] == np.abs(f).max()
        tail += np.abs(lam[end[i]:last + 1, j]).sum() if not ev["open"][i] else 0.0
    assert not lam[~owned].any()                  # no force outside an event
    # the force after the node has left: a spring's, none for exact contact
    assert (tail > 0) == (law == "penalty")


def test_a_bar_that_starts_on_its_obstacle_opens_its_event_at_the_first_step(tmp_path):
    """impacting_bar's default starts at u0 = 0 on the obstacle with v0 = −1: the start
    step's law holds it there, so its event starts at t₁ with the velocity it hits with,
    −1 (it read t₂ and 0: the start step's contact opened no event)."""
    import csv
    out = tmp_path / "bar"
    assert impacting_bar.main(["--T", "0.01", "--out", str(out), "--format", "none"]) == 0
    with open(out / "impacts.csv", newline="") as fh:
        first = next(csv.DictReader(fh))
    assert float(first["t_start"]) == pytest.approx(1e-3, rel=1e-12)
    assert float(first["velocity"]) == -1.0


def test_a_flat_profile_is_not_called_point_stops():
    """One breakpoint is a point stop only where the bounds act at that x alone: the flat
    obstacles' profile (x ≥ L/2, kink at L/2) was labelled "point stops at x=5" in the
    spring-support table, summary.json and exports."""
    from skfem_beam.output.events import _describe
    assert _describe(scenes.flat_profile(10.0)) == "profile, kink at x=5"
    assert _describe(Obstacles.point_stops(1.5, -0.1, 0.1)) == "point stops at x=1.5"
    assert _describe(Obstacles.span(1.0, 2.0, g1=-0.1)) == "span [1, 2]"


def test_impacts_csv_written_a_piece_at_a_time_is_the_same_file(tmp_path, monkeypatch):
    """impacts.csv is formatted ROWS_AT_A_TIME rows at a time (its text for 669,000 impacts
    took about 500 MB in one piece): three rows a piece give the same bytes."""
    from conftest import exit_code
    from skfem_beam.cases import point_stops
    from skfem_beam.output import events
    files = []
    for rows in (events.ROWS_AT_A_TIME, 3):
        monkeypatch.setattr(events, "ROWS_AT_A_TIME", rows)
        out = tmp_path / str(rows)
        assert exit_code(point_stops.main, ["--T", "0.3", "--format", "none",
                                            "--out", str(out)]) == 0
        files.append((out / "impacts.csv").read_bytes())
    assert files[0] == files[1] and files[0].count(b"\n") > 10


@pytest.mark.parametrize("flags", [[], ["--law", "moreau-jean"]])
def test_a_run_in_contact_from_its_start_has_a_contact_fraction_of_one(tmp_path, flags):
    """The bar rests on its obstacle from t = 0 to 2L/c = 2 s: in contact at every state of
    a 0.3 s run.  Its contact_fraction read 301/300 (the start's state counted over the
    n − 1 steps from t₁), and a 10-step run 10/9."""
    r = run_case(impacting_bar.main, tmp_path, "bar", flags + ["--T", "0.3"])
    assert r.summary["contact_fraction"] == 1.0
