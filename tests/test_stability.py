"""Where methods fail: the β-family's stability limits and the penalty method."""
import json

import numpy as np
import pytest

from conftest import assert_refused, exit_code
from skfem_beam import beam_system, scenes, solve
from skfem_beam.cases import stability_map
from skfem_beam.methods import Penalty
from skfem_beam.semidiscrete import beam_system as system_of
from skfem_beam.stability import (PAPER_KAPPA_BOUNDS, kappa_h, linear_limit, prop31_limit,
                                  stability_table)


@pytest.fixture(scope="module")
def pipe_system():
    return beam_system(scenes.point_stops())


def test_papers_bounds_hold_and_how_pessimistic(pipe_system):
    kappa = kappa_h(pipe_system)
    L, J, k2 = 1.501, 19, 282.84
    rows = stability_table(kappa, "hermite", k2, L / J, 0.25)
    ratios = {r["kappa_from"]: r["ratio_to_exact"] for r in rows}
    assert all(r >= 1 for r in ratios.values())              # they are upper bounds
    assert 27 < ratios["first paper (5.2), 24·420·19²/37"] < 28
    # the first paper's Δt for J=19, β=1/4: 2√(2/κ̄) = 3.3469e-6 s
    assert prop31_limit(rows[1]["kappa"], 0.25) == pytest.approx(3.3469e-6, rel=1e-4)
    bs = system_of(scenes.point_stops(element="bspline"))
    kb = kappa_h(bs)
    assert kb <= PAPER_KAPPA_BOUNDS["bspline"]["second paper, 5040"] * k2 / (L / J) ** 4


@pytest.mark.parametrize("beta", [0.0, 0.1])
def test_contact_scheme_fails_where_linear_newmark_does(pipe_system, beta):
    limit = linear_limit(kappa_h(pipe_system), beta)
    ok = solve(pipe_system, 0.9 * limit, 0.5, beta, save_every=10, frames=2)
    assert ok.status == "success" and ok.impacts > 0
    assert np.abs(ok.observed["tip_displacement"]).max() <= 0.1 * (1 + 1e-15)
    bad = solve(pipe_system, 1.2 * limit, 0.5, beta, save_every=10, frames=2)
    assert bad.status == "unstable" and bad.t[-1] < 0.1
    assert "linear stability limit" in bad.message and "step" in bad.message
    assert np.isfinite(bad.energy).all()


def _kept_sound(r):
    """Every kept row finite, the tip within the stops, the running diagnostics of kept
    states only (they counted the discarded ones: contact_fraction 44, penetration 1e79)."""
    tip = r.observed["tip_displacement"]
    assert np.isfinite(tip).all() and np.isfinite(r.energy).all()
    assert np.abs(tip).max() <= 0.1 * (1 + 1e-12) and r.energy.min() >= 0, (tip, r.energy)
    assert 0 <= r.contact_fraction <= 1 and r.max_nodal_violation < 1e-12


@pytest.mark.parametrize("beta, ratio, save_every, word", [
    # the loop tests saved states only: one saved state in 4,000 steps was none tested,
    # and the run ended "success" with NaN fields
    (0.0, 4.0, 100_000, "the state is not finite"),
    # just above the limit the tip jumped from stop to stop every step, ½E_β fell to
    # −5,400, inside the a-priori bound: "success"
    (0.24, 1.05, 1, "< 0 (½E_β is positive while stable)"),
    (0.2, 1.01, 1, "< 0 (½E_β is positive while stable)"),
])
def test_instability_the_energy_bound_missed_is_detected(pipe_system, beta, ratio,
                                                          save_every, word):
    dt = ratio * linear_limit(kappa_h(pipe_system), beta)
    r = solve(pipe_system, dt, 0.2, beta, save_every=save_every, frames=2)
    assert r.status == "unstable" and word in r.message, r.message
    _kept_sound(r)


def test_a_runaway_the_energy_hides_keeps_no_row_of_it(pipe_system):
    """β = 0 beyond the limit, no contact: ½E_β is conserved exactly while the unstable
    mode grows, so the loop's test fired only at ~1e4 m/s and kept rows with the tip at
    8,000 m; only the rows before the chunk it was found in are kept."""
    free = beam_system(scenes.point_stops(gap=1e6))
    dt = 2 * linear_limit(kappa_h(free), 0.0)
    r = solve(free, dt, 0.5, 0.0, frames=2)
    assert r.status == "unstable"
    tip = r.observed["tip_displacement"]
    assert np.isfinite(tip).all() and np.abs(tip).max() < 0.01, tip


@pytest.mark.parametrize("beta", [0.25, 0.5])
def test_unconditional_for_beta_at_least_a_quarter(pipe_system, beta):
    paper_kappa = PAPER_KAPPA_BOUNDS["hermite"]["first paper (5.2), 24·420·19²/37"] * 282.84 \
        / (1.501 / 19) ** 4
    dt = 100 * prop31_limit(paper_kappa, 0.25)
    r = solve(pipe_system, dt, 0.5, beta)
    assert r.status == "success" and r.impacts > 0
    assert r.energy.max() < 10 * r.energy[0]


def test_penalty_penetrates_less_as_stiffness_grows(pipe_system):
    """Normal compliance penetrates (the contact scheme does not), less for stiffer springs."""
    pen = []
    for stiffness in (1e6, 1e7, 1e8):
        r = solve(pipe_system, 5e-6, 0.25, 0.25, Penalty(stiffness / scenes.PIPE_RHO_S, equation_units=True),
                  save_every=5, frames=2)
        assert r.status == "success"
        pen.append(np.abs(r.observed["tip_displacement"]).max() - 0.1)
    assert pen[0] > 3 * pen[1] > 9 * pen[2] > 0
    exact = solve(pipe_system, 5e-6, 0.25, 0.25, save_every=5, frames=2)
    assert np.abs(exact.observed["tip_displacement"]).max() - 0.1 <= 1e-16


def test_stability_map_small_grid(tmp_path, charts):
    out = tmp_path / "map"
    assert exit_code(stability_map.main, ["--betas", "0,0.5", "--ratios", "0.9,1.2",
                                          "--T", "0.05", "--out", str(out)]) == 0
    rows = (out / "stability_map.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2 * 2
    s = json.loads((out / "summary.json").read_text())
    assert s["unstable"] >= 2 and (out / "stability_map.png").stat().st_size > 10_000


def test_stability_map_refuses_a_grid_over_budget(tmp_path, capsys):
    assert_refused(stability_map.main, ["--ratios", "0.01", "--T", "2", "--max-seconds", "1",
                                        "--out", str(tmp_path / "m")], "--max-seconds=1", capsys,
                   tmp_path)


@pytest.mark.parametrize("scene, setting", [
    ("flat_obstacles.toml", "loads.0.amplitude=1e200"),      # OverflowError traceback
    ("flat_obstacles.toml", "loads.0.amplitude=1e308"),      # numpy warnings, a folder left
    ("plates/plate_rattling.toml", "loads.0.pressure=1e200"),
])
def test_a_load_too_large_for_floats_is_one_line_and_no_folder(tmp_path, capfd, scene,
                                                               setting):
    """The run finds it at its first chunk: one line, exit 2, and the folder it had made
    is removed (it was left "running", with rows)."""
    from pathlib import Path
    import skfem_beam
    from skfem_beam.scenefile import run_main
    path = Path(skfem_beam.__file__).parent / "scene_files" / scene
    out = tmp_path / "run"
    assert exit_code(run_main, [str(path), "--out", str(out), "--set", setting,
                                "--format", "none"]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"error: {path.name}: the load is too large for floating "
                              "point"), err
    assert not any("Warning" in line for line in err), err
    assert not out.exists()


def test_an_unstable_penalty_run_says_its_springs_lower_the_limit_it_names(tmp_path, capsys):
    """A stiff plate penalty at β = 0 went unstable at Δt = 5e-6 s below the limit it named
    (6.5e-6 s, the structure's alone) without saying why."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    argv = [str(example("plate_on_stops")), "--T", "0.002", "--format", "none", "--out",
            str(tmp_path / "run")] + [a for s in ("contact.law=penalty", "time.dt=5e-6",
                                                  "contact.stiffness=1e12", "time.beta=0")
                                      for a in ("--set", s)]
    assert exit_code(run_main, argv) == 4
    assert "= 6.512e-06 s of the structure alone: the penalty springs lower it" in \
        capsys.readouterr().err


def test_a_load_too_large_for_floats_leaves_an_overwritten_run_as_it_was(tmp_path, capsys):
    """--overwrite over an earlier run with a load found too large by the run: the earlier
    folder was emptied first and then removed; the loads are now checked before it is."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    out = tmp_path / "run"
    argv = [str(example("point_stops")), "--T", "0.01", "--format", "none", "--out", str(out)]
    assert exit_code(run_main, argv) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert exit_code(run_main, argv + ["--overwrite", "--set",
                                       "loads=[{per_mass=true,amplitude=1e300,omega=10.0}]"]) == 2
    assert "the load is too large for floating point" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


def test_an_unstable_run_with_a_norm_energy_keeps_its_rows_to_the_last_good_state(tmp_path):
    """Springs stiff enough to gain energy at β = 1/4 (½E_β a norm of the state): the run
    stops unstable within its first 20,000-step chunk, at the same step whatever the chunks,
    and keeps every saved row up to the last state that passed (it kept the first row
    only), stepped again from the chunk's start: the same bits as the same run to that
    time, its impacts those of the rows kept."""
    from conftest import exit_code
    from skfem_beam.cases import point_stops
    flags = ["--law", "penalty", "--stiffness", "1e11", "--dt", "2e-4", "--format", "none"]
    out = tmp_path / "unstable"
    assert exit_code(point_stops.main, [*flags, "--T", "2", "--out", str(out)]) == 4
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "unstable" and "unstable at step 5063" in s["message"]
    rows = (out / "timeseries.csv").read_text().splitlines()
    assert len(rows) == 1 + 5063          # states 0 … 5062
    # each saved state has its own bound (the load's work up to it): the same step
    # whatever the chunks (it was 5063, 5083 or 5134 with --flush-every)
    for every in ("700", "2500"):
        again = tmp_path / f"every{every}"
        assert exit_code(point_stops.main, [*flags, "--T", "2", "--out", str(again),
                                            "--flush-every", every]) == 4
        message = json.loads((again / "summary.json").read_text())["message"]
        assert "unstable at step 5063 " in message, message
    # the same states as a run that does not stop there (a looser bound: growth_limit)
    same = solve(beam_system(scenes.point_stops()), 2e-4, 5062 * 2e-4,
                 method=Penalty(1e11), growth_limit=1e4, frames=2)
    assert same.status == "success" and same.steps == 5062
    tip = [float(r.split(",")[1]) for r in rows[1:]]
    assert tip == same.observed["tip_displacement"].tolist()
    assert s["impacts"] == same.impacts > 0


def test_springs_below_a_quarter_keep_rows_to_the_chunk_start_only(tmp_path):
    """Penalty springs at β = 0 with Δt below the structure's limit but above the one the
    springs impose: ½E_β is no norm there (the kept rows held a runaway at ±270 m/s, 300×
    the energy); the run keeps its chunk's start and says why; a run whose rows end
    between saved states (save_every 13) has as many impacts in summary.json as in
    impacts.csv (137 against 135 rows)."""
    from conftest import exit_code
    from skfem_beam.cases import point_stops
    out = tmp_path / "springs"
    assert exit_code(point_stops.main, ["--law", "penalty", "--beta", "0", "--stiffness",
                                        "1e9", "--dt", "1e-5", "--T", "0.5", "--format",
                                        "none", "--out", str(out)]) == 4
    s = json.loads((out / "summary.json").read_text())
    assert s["steps"] == 1 and "penalty springs below β = 1/4" in s["message"]
    out = tmp_path / "every13"
    assert exit_code(point_stops.main, ["--law", "penalty", "--stiffness", "1e11", "--dt",
                                        "2e-4", "--T", "2", "--save-every", "13",
                                        "--flush-every", "1", "--format", "none",
                                        "--out", str(out)]) == 4
    s = json.loads((out / "summary.json").read_text())
    rows = (out / "impacts.csv").read_text().splitlines()
    assert s["impacts"] == len(rows) - 1 > 100


def test_a_save_every_beyond_64_bits_is_one_line(tmp_path, capsys):
    """--save-every 2**63 was an OverflowError traceback and a folder left "running"."""
    from conftest import assert_refused
    from skfem_beam.cases import point_stops
    assert_refused(point_stops.main, ["--T", "0.01", "--save-every", str(2**63), "--out",
                                      str(tmp_path / "a")],
                   "save_every=9223372036854775808 must be at most 4,611,686,018,427,387,904",
                   capsys, tmp_path)


def test_a_failed_runs_diagnostics_are_those_of_its_last_state(tmp_path):
    """A contact solver failing at step 80 with --save-every 7: summary.json's steps (79),
    impacts and impacts.csv are those of the last good state (they were a later state's
    than the rows' while the run was cut to a saved state)."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    out = tmp_path / "failed"
    code = exit_code(run_main, [str(example("tube_round_holes")), "--set",
                                "contact.law=penalty", "--set", "contact.stiffness=1e11",
                                "--set", "time.dt=1e-3", "--T", "5", "--save-every", "7",
                                "--format", "none", "--out", str(out)])
    s = json.loads((out / "summary.json").read_text())
    assert code == 3 and s["status"] == "failed" and s["steps"] == 79
    rows = (out / "impacts.csv").read_text().splitlines()
    t = rows[0].split(",").index("t_start")
    starts = [float(r.split(",")[t]) for r in rows[1:]]
    assert s["impacts"] == len(starts) > 0 and max(starts) <= 79e-3 + 1e-12


def test_kappa_h_is_the_same_number_every_time():
    """ARPACK's own random start made summary.json's kappa_h differ in its last digits
    from call to call (…0.0003, …0.00055 for the round-hole tube, 124 unknowns)."""
    from skfem_beam.scenefile import example, load
    system = beam_system(load(example("tube_round_holes")).problem)
    assert system.n >= 100                  # the sparse (Lanczos) branch
    first = kappa_h(system)
    assert all(kappa_h(system) == first for _ in range(4))


def test_an_unstable_run_names_the_time_of_its_last_row_written(tmp_path, capsys):
    """With --save-every 100 an explicit run found unstable at its first saved state keeps
    the row at t = 0 only: its line said "results up to t=0.01 s written"."""
    from skfem_beam.cases import flat_obstacles
    out = tmp_path / "run"
    argv = ["--beta", "0", "--dt", "0.01", "--T", "5", "--save-every", "100", "--format",
            "none", "--out", str(out)]
    assert exit_code(flat_obstacles.main, argv) == 4
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.endswith(f"; results up to t=0 s written to {out}"), err
    assert (out / "timeseries.csv").read_text().splitlines()[-1].startswith("0.0,")


def test_an_unstable_penalty_run_says_when_its_energy_left_its_bound_and_why(tmp_path,
                                                                             capsys):
    """The main job's penalty method at its defaults goes unstable at t = 1.606 s, its energy
    growing from about 1.1 s: the rows kept were unmarked, and the springs' gain, said for
    a run that ends, was not said for one that stops unstable."""
    from skfem_beam.cases import flat_obstacles
    out = tmp_path / "run"
    assert exit_code(flat_obstacles.main, ["--method", "penalty", "--T", "2", "--format",
                                           "none", "--out", str(out)]) == 4
    import re
    err = capsys.readouterr().err.splitlines()
    # an instability's step is a matter of the last bits: times to a few steps (1.606 s
    # and 1.483 s on the machine of tests/reference/pins)
    stop = re.match(r"error: unstable at step \d+ \(t=([\d.]+) s\)", err[0])
    passed = re.search(r"its energy passed the loads' a-priori bound \(√E¹ \+ their "
                       r"work\)² at t=([\d.]+) s: the rows from there on show", err[0])
    assert stop and passed, err
    assert 1.4 < float(passed[1]) < float(stop[1]) < 1.7
    gain = re.match(r"warning: the penalty springs did ([\d.]+) of work", err[1])
    assert gain and float(gain[1]) > 10, err        # 66.27 against 0.66 given
    assert passed[0] in json.loads((out / "summary.json").read_text())["message"]
